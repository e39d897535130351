"""Amplitude-dependent hinge elements: dry (Coulomb) friction, a cubic spring, and a small
library of torque terms for effects no named element describes.

They act on the host's hinge angles like :class:`analogs.HingeSpring` and
:class:`analogs.HingeDamper`; a pendulum's small-amplitude frequency and damping ratio do
not include them (their effect grows or fades with the swing).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from .component import Attachment
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["HingeFriction", "CubicHingeSpring", "HingeTorqueTerms", "TORQUE_TERMS",
           "FRICTION_RATE"]

#: Rate scale of the smoothed sign of dry friction [rad/s]: the torque is
#: ``Tc tanh(rate / FRICTION_RATE)``, so below ~0.02 rad/s (a swing of 2 mrad at 2 Hz) the
#: friction acts as a viscous damper ``Tc / FRICTION_RATE``; above, as Coulomb friction.
#: Smooth enough for IPOPT to converge in a few iterations, but it biases a fitted ``Tc``
#: against sharp friction (+3.2 % on a noise-free record with tanh over 1e-3 rad/s;
#: :class:`HingeFriction` takes a sharper ``rate`` for a final fit: +1.4 % at 0.005).
FRICTION_RATE = 0.02


class HingeFriction(Attachment):
    """Dry (Coulomb) friction on the host's hinge: torque ``-Tc tanh(hinge rate / rate)``
    (a smoothed ``-Tc sign``; ``rate`` [rad/s] defaults to :data:`FRICTION_RATE`). A
    sharper ``rate`` is less biased against true Coulomb friction but stiffer: RK4 at the
    step ``h`` stays stable while ``h Tc / (rate m L^2) < 2.8``.

    Parameter ``<host>.coulomb_friction`` (N m). Its equivalent viscous damping falls with
    the swing amplitude ``A`` as ``4 Tc / (pi A omega)`` (a diaphragm or bearing that
    sticks)."""

    parameters = {"coulomb_friction": Param("N m", 0.0, 0.0, description="dry hinge friction torque")}

    def __init__(self, host: str = "p1", *, coulomb_friction: float | None = None,
                 rate: float = FRICTION_RATE,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
            raise InputError(f"HingeFriction: `rate` must be a positive rate scale in rad/s, "
                             f"got {rate!r}")
        super().__init__(host, bounds=bounds, coulomb_friction=coulomb_friction)
        self.rate = float(rate)

    def _extra_structure(self) -> str:
        return "" if self.rate == FRICTION_RATE else f"rate={self.rate!r}"

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        for a, r in zip(k.hinge, k.hinge_rates):
            k.add_force(a, -k.p.coulomb_friction * sp.tanh(r / self.rate))


class CubicHingeSpring(Attachment):
    """Cubic (hardening for ``k3 > 0``, softening for ``k3 < 0``) hinge spring: torque
    ``-k3 angle^3``, potential ``k3 angle^4 / 4``.

    Parameter ``<host>.cubic_stiffness`` (N m/rad^3). The frequency rises (hardening) or
    falls (softening) with the swing: at amplitude ``A`` the stiffness seen is about
    ``3 k3 A^2 / 4`` more than the linear one (an elastomeric diaphragm that stiffens)."""

    parameters = {"cubic_stiffness": Param("N m/rad^3", 0.0, description="cubic hinge stiffness")}

    def __init__(self, host: str = "p1", *, cubic_stiffness: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(host, bounds=bounds, cubic_stiffness=cubic_stiffness)

    def declare(self, k: "Declaration") -> None:
        k.add_potential(sum(k.p.cubic_stiffness * a**4 / 4 for a in k.hinge))


def _smooth_sign(r: Any) -> Any:
    import sympy as sp

    return sp.tanh(r / FRICTION_RATE)


#: The library's hinge torque terms: name -> (term of angle ``a`` and rate ``r``, unit of its
#: coefficient, what it describes). The torque is ``-coefficient * term``.
TORQUE_TERMS: dict[str, tuple[Callable[[Any, Any], Any], str, str]] = {
    "angle_squared": (lambda a, r: a**2, "N m/rad^2", "asymmetric stiffness"),
    "angle_cubed": (lambda a, r: a**3, "N m/rad^3", "cubic stiffness"),
    "rate_cubed": (lambda a, r: r**3, "N m s^3/rad^3", "cubic damping"),
    "rate_abs_rate": (lambda a, r: r * abs(r), "N m s^2/rad^2", "quadratic damping"),
    "angle2_rate": (lambda a, r: a**2 * r, "N m s/rad^3", "damping that grows with the angle"),
    "abs_angle_rate": (lambda a, r: abs(a) * r, "N m s/rad^2",
                       "damping that grows with |angle|"),
    "angle_rate2": (lambda a, r: a * r**2, "N m s^2/rad^3", "stiffness that grows with the rate"),
    "sign_rate": (lambda a, r: _smooth_sign(r), "N m", "dry friction (smoothed sign)"),
}


class HingeTorqueTerms(Attachment):
    """A sparse library of hinge torque terms: torque ``-sum_i c_i term_i(angle, rate)``
    over the chosen ``terms`` of :data:`TORQUE_TERMS` (powers and products of the angle and
    its rate, a smoothed sign of the rate), each coefficient a parameter
    ``<host>.torque_<term>`` with its unit. The diagnosis selects the few that an effect
    outside the named elements needs."""

    def __init__(self, host: str = "p1", *, terms: Sequence[str] = ("angle_cubed",),
                 bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        unknown = [t for t in terms if t not in TORQUE_TERMS]
        if unknown or not terms or len(set(terms)) != len(terms):
            raise InputError(f"HingeTorqueTerms terms must be distinct names of "
                             f"{', '.join(TORQUE_TERMS)}; got {list(terms)!r}")
        self.terms = tuple(terms)
        self.parameters = {f"torque_{t}": Param(TORQUE_TERMS[t][1], 0.0,
                                                description=TORQUE_TERMS[t][2])
                           for t in self.terms}
        super().__init__(host, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return ",".join(self.terms)

    def declare(self, k: "Declaration") -> None:
        for a, r in zip(k.hinge, k.hinge_rates):
            torque = sum(k.p[f"torque_{t}"] * TORQUE_TERMS[t][0](a, r) for t in self.terms)
            k.add_force(a, -torque)
