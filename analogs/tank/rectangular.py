"""An upright rectangular tank and its lateral slosh modes in closed form.

Frame: origin at the centre of the tank bottom, ``x`` along the motion (the tank's
``length`` a), ``y`` across it (``width`` b), ``z`` up; SI units.

Modes
-----
Linear potential flow in a box is separable. The modes that a motion along ``x`` excites
have the free-surface shape ``eta_n = sin(k_n x)``, ``k_n = (2n - 1) pi / a``, and the
potential ``phi_n = sin(k_n x) cosh(k_n z) / cosh(k_n h)`` (``h`` the liquid depth), so

* ``omega_n^2 = g k_n tanh(k_n h)`` (NASA SP-106, Abramson 1966, ch. 2 and 6; Ibrahim 2005,
  "Liquid Sloshing Dynamics", ch. 1: the frequency of the 2-D standing wave);
* slosh mass ``m_n = rho b lambda_n A_n^2 / B_n`` with ``lambda_n = omega_n^2 / g``,
  ``A_n = int x eta_n dx = 2 (-1)^(n+1) / k_n^2`` and ``B_n = int eta_n^2 dx = a / 2``:
  ``m_n = m_liquid 8 tanh(k_n h) / ((2n - 1)^3 pi^3 h / a)`` - the same definition as the
  axisymmetric solvers' ``rho pi lambda a_n^2 / b_n`` (the mode's share of the lateral
  force), and the SP-106 / Ibrahim mechanical-model mass; the masses of all modes add up
  to the liquid mass in shallow liquid (``sum 8 / ((2n - 1)^2 pi^2) = 1``);
* pendulum length ``L_n = g / omega_n^2``;
* bob height ``h_n = h - (2 / k_n) tanh(k_n h / 2)`` from the pitch angular-momentum
  integral ``int (z phi_x - x phi_z) dA / (lambda_n A_n)``, the axisymmetric solvers'
  convention (for a flat-bottom cylinder the same integral gives SP-106's
  ``h - (2 R / xi) tanh(xi h / 2 R)``);
* wave height at the wall over the bob's lateral amplitude ``lambda_n eta_n(a/2) A_n / B_n
  = 4 tanh(k_n h) / ((2n - 1) pi)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .geometry import _check_positive, fill_fraction

__all__ = ["Rectangular", "RectangularMode"]


@dataclass(frozen=True)
class RectangularMode:
    """One lateral slosh mode of a :class:`Rectangular` tank (SI units, heights from the
    tank bottom; ``mass`` per unit liquid density, m^3)."""

    lam: float  #: omega^2 / g, 1/m
    volume: float  #: slosh mass / density, m^3
    bob_height: float  #: m
    amplitude_ratio: float  #: wave height at the wall / bob lateral amplitude, -


@dataclass(frozen=True)
class Rectangular:
    """Upright rectangular tank (a box with a flat bottom and vertical walls).

    Parameters
    ----------
    length : float
        Inside length along the motion (m): the slosh modes' wavelength direction.
    width : float
        Inside width across the motion (m).
    height : float
        Inside height (m); the depth fraction ``fill`` is measured against it.

    Examples
    --------
    >>> tank = Rectangular(0.4, 0.2, 0.3)
    >>> round(tank.liquid_mass(0.5, 1000.0), 6)    # 0.4 x 0.2 x 0.15 m of water
    12.0
    """

    length: float
    width: float
    height: float

    def __init__(self, length: float, width: float, height: float) -> None:
        object.__setattr__(self, "length", _check_positive("length", length, "m"))
        object.__setattr__(self, "width", _check_positive("width", width, "m"))
        object.__setattr__(self, "height", _check_positive("height", height, "m"))

    @property
    def shape(self) -> str:
        return "rectangular"

    @property
    def radius(self) -> float:
        """Half the length along the motion (m): the lateral half-size reports use where an
        axisymmetric tank gives its radius (``lambda_R`` is ``lambda a / 2``)."""
        return 0.5 * self.length

    def volume(self, depth: float | None = None) -> float:
        """Volume in m^3 below ``depth`` (m); the whole tank if ``depth`` is None."""
        depth = self.height if depth is None else depth
        return self.length * self.width * depth

    def depth_from_fill(self, fill: float | None = None, *, volume_fill: float | None = None
                        ) -> float:
        """Liquid depth in m from a depth fraction ``fill`` or a volume fraction
        ``volume_fill`` (the same for vertical walls); give exactly one."""
        _, value = fill_fraction(fill, volume_fill)  # vertical walls: the same fraction
        return value * self.height

    def liquid_mass(self, fill: float, density: float) -> float:
        """Mass in kg of liquid of ``density`` (kg/m^3) filled to ``fill`` (depth / height)."""
        return float(density * self.volume(self.depth_from_fill(fill)))

    def centroid_height(self, depth: float) -> float:
        """Height in m of the liquid's centre of mass for liquid depth ``depth`` (m)."""
        return 0.5 * depth

    def rigid_inertia(self, depth: float, about: float) -> float:
        """Moment of inertia per unit density (m^5) of the liquid frozen solid up to
        ``depth`` (m) about the horizontal axis across the motion (``y``) at height
        ``about`` (m)."""
        a, b = self.length, self.width
        return b * (a**3 * depth / 12.0 + a * ((depth - about) ** 3 + about**3) / 3.0)

    def modes(self, depth: float, n_modes: int) -> tuple[RectangularMode, ...]:
        """The first ``n_modes`` lateral modes at liquid depth ``depth`` (m), in closed form
        (module docstring)."""
        a, b = self.length, self.width
        out = []
        for n in range(1, n_modes + 1):
            k = (2 * n - 1) * math.pi / a
            th = math.tanh(k * depth)
            lam = k * th
            area_moment = 2.0 / k**2  # |int x eta dx|; the sign of a mode is arbitrary
            out.append(RectangularMode(
                lam=lam, volume=b * lam * area_moment**2 / (0.5 * a),
                bob_height=depth - (2.0 / k) * math.tanh(0.5 * k * depth),
                amplitude_ratio=lam * area_moment / (0.5 * a)))
        return tuple(out)

    def __repr__(self) -> str:
        return f"Rectangular(length={self.length!r}, width={self.width!r}, height={self.height!r})"
