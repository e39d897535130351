"""Tank + fill + liquid -> lateral slosh modes -> pendulum analog parameters.

Analog quantities from each mode ``phi_n = U_n(r, z) cos(theta)`` (heights from the tank
bottom, ``lambda_n = omega_n^2 / g``):

* slosh (pendulum) mass ``m_n = rho pi lambda_n a_n^2 / b_n``, ``a_n = int r^2 U dr``,
  ``b_n = int r U^2 dr`` over the free surface (matches the lateral force);
* pendulum length ``L_n = g / omega_n^2 = 1 / lambda_n``;
* bob height ``h_n = I_n / (lambda_n a_n)`` with ``I_n = int (z (U_r + U/r) - r U_z) r dr dz``
  the mode's pitch angular-momentum integral (matches the pitch moment under lateral
  excitation); hinge height ``h_n + L_n``. For a sphere the wall pressure passes through
  the centre, and the hinge is exactly at the centre, which the solvers reproduce;
* wave-height to bob-amplitude ratio ``lambda_n U_n(r_s) a_n / b_n``: the free-surface
  elevation at the wall divided by the bob's lateral displacement in the same motion;
* fixed mass ``m_0 = m_liquid - sum m_n`` (kept modes), at the height that preserves the
  static centre of gravity;
* fixed-mass pitch inertia: **inferred convention** -- the frozen liquid's moment of inertia
  about a horizontal axis through the fixed mass, minus the bobs as point masses,
  ``I_0 = I_rigid(h_0) - sum m_n (h_n - h_0)^2`` (so that the analog has the inertia of the
  frozen liquid about its c.g.). This is not the potential-flow effective inertia (which is
  near zero for a sphere); it is the definition that reproduces the SLOSH code's values in
  the seed's Table 8 (0.007/0.010/0.014 kg m^2), inferred from them.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Union

from . import _fem, _legacy, _ritz
from ._modes import RawModes
from .analog import FixedMassPrediction, SloshMode, TankPrediction
from .damping import cylinder_damping, damping_validity, sphere_damping
from .geometry import WATER, Capsule, Cylinder, Liquid, Sphere, Tank
from .rectangular import Rectangular

__all__ = ["MAX_MODES", "Exact", "FiniteElements", "FixedMassPrediction", "Legacy", "Ritz",
           "SloshMode", "TankPrediction", "predict"]

#: Most slosh modes :func:`predict` computes.
MAX_MODES = 6


# -- solver strategies ---------------------------------------------------------------------
@dataclass(frozen=True)
class Ritz:
    """Ritz with m = 1 solid harmonics up to ``degree`` (exponential convergence up to half
    full spheres, algebraic above: use ``degree >= 80`` beyond 85 % fill)."""

    #: Highest degree of the solid harmonics.
    degree: int = 60
    #: Relative cut-off of small singular values of the Ritz matrices (their conditioning
    #: grows with the degree).
    rcond: float = 1e-12
    #: The solver's name (``predict(method=...)``, reports).
    name: str = "ritz"

    def solve(self, tank: Tank, depth: float, n_modes: int) -> RawModes:
        """The first ``n_modes`` lateral modes of ``tank`` filled to ``depth`` (m)."""
        return _ritz.solve(tank, depth, degree=self.degree, n_modes=n_modes, rcond=self.rcond)


@dataclass(frozen=True)
class FiniteElements:
    """Axisymmetric degree-``degree`` finite elements with ``layers`` geometric layers
    (ratio ``ratio``) towards the contact line."""

    degree: int = 7
    layers: int = 7
    ratio: float = 0.2
    #: The solver's name (``predict(method=...)``, reports).
    name: str = "fem"

    def solve(self, tank: Tank, depth: float, n_modes: int) -> RawModes:
        """The first ``n_modes`` lateral modes of ``tank`` filled to ``depth`` (m)."""
        return _fem.solve(tank, depth, degree=self.degree, layers=self.layers,
                          ratio=self.ratio, n_modes=n_modes)


@dataclass(frozen=True)
class Legacy:
    """The SLOSH code's Lomen basis: ``n_poly`` polynomial + ``n_bessel`` Bessel-exponential
    functions (spheres only)."""

    n_poly: int = 5
    n_bessel: int = 5
    #: The solver's name (``predict(method=...)``, reports).
    name: str = "legacy"

    def solve(self, tank: Tank, depth: float, n_modes: int) -> RawModes:
        """The first ``n_modes`` lateral modes of ``tank`` filled to ``depth`` (m)."""
        return _legacy.solve(tank, depth, n_poly=self.n_poly, n_bessel=self.n_bessel,
                             n_modes=n_modes)


@dataclass(frozen=True)
class Exact:
    """Converged answer: Ritz where it converges fast (spheres up to 75 % depth, shallow
    cylinders), graded finite elements elsewhere."""

    #: The solver's name (``predict(method=...)``, reports).
    name: str = "exact"

    def choose(self, tank: Tank, depth: float) -> Ritz | FiniteElements:
        """The solver that converges fast for ``tank`` filled to ``depth`` (m)."""
        if isinstance(tank, Sphere) and depth <= 1.5 * tank.radius:
            return Ritz(degree=40 if depth <= tank.radius else 60)
        if isinstance(tank, Cylinder) and depth <= 2.0 * tank.radius:
            return Ritz(degree=40)
        return FiniteElements()

    def solve(self, tank: Tank, depth: float, n_modes: int) -> RawModes:
        """The first ``n_modes`` lateral modes of ``tank`` filled to ``depth`` (m)."""
        return self.choose(tank, depth).solve(tank, depth, n_modes)


Solver = Union[Exact, Ritz, FiniteElements, Legacy]
#: The solvers by name (``predict(..., method="exact")``).
METHODS = {"exact": Exact, "ritz": Ritz, "fem": FiniteElements, "legacy": Legacy}


#: What the damping ratio of the higher modes is (the tank report's footnote and note).
MODE1_DAMPING = ("the first mode's damping ratio: the SP-106 correlations are for the first "
                 "mode, and the SLOSH code gives the same value to every mode; estimate a "
                 "higher mode's damping from data")


# -- results -------------------------------------------------------------------------------
def _damping(tank: Tank | Rectangular, depth: float, liquid: Liquid, gravity: float
             ) -> tuple[float, str | None]:
    """The damping ratio and, when the correlation does not hold there, why."""
    nu = liquid.viscosity
    if isinstance(tank, Sphere):
        shape, radius, h = "sphere", tank.radius, depth
    elif isinstance(tank, Cylinder):
        shape, radius, h = "cylinder", tank.radius, depth
    elif isinstance(tank, Capsule):
        a, c = tank.radius, tank.cylinder_length
        if depth <= a:  # bottom dome: a sphere of the same radius at this depth
            shape, radius, h = "sphere", a, depth
        elif depth >= a + c:  # top dome
            shape, radius, h = "sphere", a, depth - c
        else:
            shape, radius, h = "cylinder", a, depth
    else:
        return float("nan"), None
    zeta = (sphere_damping if shape == "sphere" else cylinder_damping)(radius, h, nu, gravity)
    return zeta, damping_validity(shape, radius, h, nu, gravity)


def _solver(method: str | Solver) -> Solver:
    if isinstance(method, str):
        try:
            return METHODS[method]()
        except KeyError:
            raise ValueError(f"`method` must be one of {sorted(METHODS)} or a solver object "
                             f"(`Ritz()`, `FiniteElements()`, `Legacy()`); got {method!r}."
                             ) from None
    if not hasattr(method, "solve"):
        raise ValueError(f"`method` must be a name or a solver object; got {method!r}.")
    return method


def predict(tank: Tank | Rectangular, *, fill: float | None = None, volume_fill: float | None = None,
            liquid: Liquid = WATER, gravity: float = 9.81, method: str | Solver = "exact",
            modes: int = 2, diaphragm: bool = False) -> TankPrediction:
    """Predict the pendulum analog of lateral slosh for a tank, fill and liquid.

    Parameters
    ----------
    tank : Tank or Rectangular
        :class:`Sphere`, :class:`Cylinder`, :class:`Capsule` or :class:`Profile`, solved
        by ``method``; or an upright :class:`~analogs.tank.rectangular.Rectangular` tank,
        whose modes are in closed form (``method`` must then be ``"exact"``).
    fill, volume_fill : float
        Liquid depth / tank height, or liquid volume / tank volume, in (0, 1); give one.
    liquid : Liquid
        Density (kg/m^3) and kinematic viscosity (m^2/s); default water at 20 C.
    gravity : float
        Axial acceleration in m/s^2 (default 9.81).
    method : str or solver
        ``"exact"`` (default), ``"legacy"``, ``"ritz"``, ``"fem"`` or a solver object
        (:class:`Exact`, :class:`Ritz`, :class:`FiniteElements`, :class:`Legacy`).
    modes : int
        Number of modes kept as pendulums (default 2).
    diaphragm : bool
        The tank has a diaphragm: the prediction stays the free-surface one and a note
        says what the diaphragm changes.

    Returns
    -------
    TankPrediction

    Examples
    --------
    >>> p = predict(Sphere(0.1016), fill=0.5)
    >>> round(p.modes[0].lam * 0.1016, 4)
    1.5602
    """
    if not isinstance(tank, (Tank, Rectangular)):
        raise ValueError("`tank` must be a Sphere, Cylinder, Capsule, Profile or Rectangular; "
                         f"got {tank!r}.")
    gravity_ = float(gravity) if isinstance(gravity, (int, float)) else float("nan")
    if not (math.isfinite(gravity_) and gravity_ > 0):
        raise ValueError(f"`gravity` must be a positive acceleration in m/s^2; got {gravity!r}.")
    if not (isinstance(modes, int) and 1 <= modes <= MAX_MODES):
        raise ValueError(f"`modes` must be an integer from 1 to {MAX_MODES}; got {modes!r}.")
    if not isinstance(liquid, Liquid):
        raise ValueError(f"`liquid` must be a Liquid(density=..., viscosity=...); got {liquid!r}.")
    solver = _solver(method)
    depth = tank.depth_from_fill(fill, volume_fill=volume_fill)
    rho, g = liquid.density, gravity_
    zeta, validity = _damping(tank, depth, liquid, g)

    t0 = time.perf_counter()
    if isinstance(tank, Rectangular):
        if solver.name != "exact":
            raise ValueError(f"a rectangular tank's modes are in closed form: `method` must be "
                             f"\"exact\"; got {solver.name!r}.")
        terms = [(m.lam, rho * m.volume, m.bob_height, m.amplitude_ratio)
                 for m in tank.modes(depth, modes)]
        used, size = "closed form", 0
    else:
        raw = solver.solve(tank, depth, modes)
        used = solver.choose(tank, depth).name if isinstance(solver, Exact) else solver.name
        terms = [(raw.lam[n], rho * math.pi * raw.lam[n] * raw.a[n] ** 2 / raw.b[n],
                  raw.moment[n] / (raw.lam[n] * raw.a[n]),
                  raw.lam[n] * raw.u_wall[n] * raw.a[n] / raw.b[n]) for n in range(modes)]
        size = raw.size
    seconds = time.perf_counter() - t0

    volume = tank.volume(depth)
    m_liq = rho * volume
    z_cg = tank.centroid_height(depth)
    out = [SloshMode(index=n + 1, frequency_hz=math.sqrt(lam * g) / (2.0 * math.pi),
                     lam=float(lam), mass=float(mass), length=float(1.0 / lam),
                     hinge_height=float(bob + 1.0 / lam), bob_height=float(bob),
                     amplitude_ratio=float(ratio), damping_ratio=zeta)
           for n, (lam, mass, bob, ratio) in enumerate(terms)]
    m0 = m_liq - sum(m.mass for m in out)
    h0 = (m_liq * z_cg - sum(m.mass * m.bob_height for m in out)) / m0
    inertia = rho * tank.rigid_inertia(depth, h0) - sum(m.mass * (m.bob_height - h0) ** 2
                                                       for m in out)
    notes = []
    if diaphragm:
        notes.append("diaphragm: this is the free-surface prediction; a diaphragm raises the "
                     "frequency, lowers the slosh mass and adds damping - estimate them from data")
    if len(out) > 1 and math.isfinite(zeta):
        notes.append(f"modes 2 and up: {MODE1_DAMPING}")
    if not math.isfinite(zeta):
        what = "general profile" if tank.shape == "profile" else f"{tank.shape} tank"
        notes.append(f"no damping correlation for a {what}: damping_ratio is nan")
    if validity:
        notes.append(validity)
    if isinstance(solver, Legacy):
        notes.append("legacy Lomen basis (SLOSH code conventions): not converged above half full")
    return TankPrediction(
        tank=tank, liquid=liquid, gravity=g, depth=float(depth),
        fill_fraction=float(depth / tank.height), volume_fraction=float(volume / tank.volume()),
        liquid_mass=float(m_liq), liquid_cg_height=float(z_cg), method=solver.name,
        solver=used, modes=tuple(out),
        fixed_mass=FixedMassPrediction(mass=float(m0), height=float(h0), inertia=float(inertia)),
        diaphragm=bool(diaphragm), size=size, seconds=seconds, notes=tuple(notes))
