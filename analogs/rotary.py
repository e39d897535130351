"""Green et al.'s SSTR analogs: the rotary oscillator and the 3-DOF (rigid-body) pendulum."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ._units import TINY_INERTIA, TINY_LENGTH, TINY_MASS
from .component import Component
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["RotaryOscillator", "ThreeDofPendulum"]


class RotaryOscillator(Component):
    """Green et al.'s rotary oscillator: an inertia on torsional springs and dampers about
    two tank axes, for the torque resonance the SSTR records in the tangential and, less,
    the radial torque with little or no force resonance.

    A body without mass in translation turns relative to the tank by ``a1`` (rad) about
    the first axis of ``axes`` and then by ``a2`` (rad) about the second axis of the turned
    frame (``axes="xy"``: the radial ``T.x`` and the tangential ``T.y`` of a tank whose axis
    is the spin axis; ``"zy"`` for :class:`~analogs.SpinningRig` ``tank_axis="inward"``).
    It has the inertia ``inertia`` (kg m^2) about both of these body axes and none about the
    third (the liquid's inertia about that axis belongs to the fixed mass); each angle has a
    torsional spring ``stiffness`` (N m/rad) and a viscous damper ``damping`` (N m s/rad) to
    the tank. It exerts torques on the tank, no force.

    Derived: the natural frequency ``sqrt(k / J) / 2 pi`` (Hz) and damping ratio ``c / (2
    sqrt(k J))`` of the oscillator in a non-rotating tank. In a tank spinning at ``Omega``
    about the third axis the tank sees its two circular modes at ``sqrt(k/J) -/+ Omega``
    (rad/s), and with the damping relative to the tank the oscillator is stable only when
    ``sqrt(k / J) > Omega``.

    Examples
    --------
    >>> from analogs import RotaryOscillator
    >>> RotaryOscillator("o1", inertia=2e-3, stiffness=0.2).coordinates
    ('a1', 'a2')
    """

    coordinates = ("a1", "a2")
    coordinate_units = {"a1": "rad", "a2": "rad"}
    derived = {"frequency_hz": "Hz", "damping_ratio": "-"}
    parameters = {
        "inertia": Param("kg m^2", None, TINY_INERTIA,
                         description="oscillator inertia about each of its two axes"),
        "stiffness": Param("N m/rad", None, 0.0, description="torsional spring on each angle"),
        "damping": Param("N m s/rad", 0.0, 0.0, description="torsional damper on each angle"),
    }

    def __init__(self, name: str = "o1", *, inertia: float | None = None,
                 stiffness: float | None = None, damping: float | None = None,
                 axes: str = "xy", bounds: dict[str, tuple[float, float]] | None = None) -> None:
        if len(axes) != 2 or len(set(axes)) != 2 or any(a not in "xyz" for a in axes):
            raise InputError(f"RotaryOscillator axes must be two distinct letters of 'xyz' "
                             f"(e.g. 'xy': radial then tangential), got {axes!r}")
        self.axes = axes
        super().__init__(name, bounds=bounds, inertia=inertia, stiffness=stiffness,
                         damping=damping)

    def _extra_structure(self) -> str:
        return self.axes

    def derived_values(self, v, *, gravity, hinge_stiffness, hinge_damping):
        """Natural frequency (Hz) and damping ratio of the oscillator, tank not rotating."""
        J, k = v.get("inertia"), v.get("stiffness")
        if J is None or k is None:
            return {}
        return {"frequency_hz": (k / J) ** 0.5 / (2 * math.pi),
                "damping_ratio": v.get("damping", 0.0) / (2 * (k * J) ** 0.5)}

    def declare(self, k: "Declaration") -> None:
        from sympy.physics.mechanics import Vector, outer

        T, p = k.tank, k.p
        first, second = self.axes
        tilted = k.frame("tilt")
        tilted.orient_axis(T, getattr(T, first), k.q.a1)
        body = k.frame("body")
        body.orient_axis(tilted, getattr(tilted, second), k.q.a2)
        u1, u2 = getattr(body, first), getattr(body, second)
        k.add_body(0, Vector(0), body, p.inertia * (outer(u1, u1) + outer(u2, u2)))
        k.add_potential(p.stiffness * (k.q.a1**2 + k.q.a2**2) / 2)
        k.add_dissipation(p.damping * (k.qd.a1**2 + k.qd.a2**2) / 2)


class ThreeDofPendulum(Component):
    """The 3-DOF pendulum of Green et al.: a rigid bob on a ball joint.

    The rod hangs from a hinge on the tank axis at ``hinge_height`` (m) and swings by
    ``alpha`` (toward +x) and ``beta`` (toward +y) as :class:`~analogs.SphericalPendulum`
    does; the bob, a rigid body of ``mass`` (kg) whose centre is ``length`` (m) from the
    hinge, also turns about the rod by ``gamma`` (rad). Its central inertia is
    ``inertia`` (kg m^2) about axes across the rod and ``axial_inertia`` (kg m^2) about the
    rod; the twist has its own torsional spring ``twist_stiffness`` (N m/rad) and damper
    ``twist_damping`` (N m s/rad). Hinge elements (springs, dampers, diaphragms) attach to
    the swing angles ``alpha`` and ``beta``. With zero inertias it moves as the spherical
    pendulum (``gamma`` then carries no inertia: give ``axial_inertia`` > 0 to estimate it).

    Derived: the small-amplitude frequency ``sqrt((m g L + k) / (m L^2 + I)) / 2 pi`` (Hz)
    and damping ratio ``c / (2 sqrt((m g L + k)(m L^2 + I)))`` of a swing under uniform
    gravity, with ``k`` and ``c`` the hinge stiffness and damping.
    """

    coordinates = ("alpha", "beta", "gamma")
    coordinate_units = {"alpha": "rad", "beta": "rad", "gamma": "rad"}
    hinge_angles = ("alpha", "beta")
    derived = {"frequency_hz": "Hz", "damping_ratio": "-"}
    parameters = {
        "mass": Param("kg", None, TINY_MASS, description="bob (slosh) mass"),
        "length": Param("m", None, TINY_LENGTH, description="hinge to bob centre"),
        "hinge_height": Param("m", None, description="hinge height above the tank origin"),
        "inertia": Param("kg m^2", None, 0.0, description="bob inertia across the rod"),
        "axial_inertia": Param("kg m^2", None, 0.0, description="bob inertia about the rod"),
        "twist_stiffness": Param("N m/rad", 0.0, 0.0, description="torsional spring on the twist"),
        "twist_damping": Param("N m s/rad", 0.0, 0.0, description="torsional damper on the twist"),
    }

    def __init__(self, name: str = "p1", *, bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        super().__init__(name, bounds=bounds, **values)

    def derived_values(self, v, *, gravity, hinge_stiffness, hinge_damping):
        """Swing frequency (Hz) and damping ratio under uniform gravity."""
        m, L, I = v.get("mass"), v.get("length"), v.get("inertia")
        if gravity is None or m is None or L is None or I is None:
            return {}
        stiff, inert = m * gravity * L + hinge_stiffness, m * L**2 + I
        return {"frequency_hz": (stiff / inert) ** 0.5 / (2 * math.pi),
                "damping_ratio": hinge_damping / (2 * (stiff * inert) ** 0.5)}

    def declare(self, k: "Declaration") -> None:
        from sympy.physics.mechanics import outer

        T, p, q = k.tank, k.p, k.q
        # the rod frame: T turned by -alpha about T.y, then by beta about the turned x, so
        # that -rod.z is the spherical pendulum's direction (sin a cos b, sin b, -cos a cos b)
        swing = k.frame("swing")
        swing.orient_axis(T, T.y, -q.alpha)
        rod = k.frame("rod")
        rod.orient_axis(swing, swing.x, q.beta)
        bob = k.frame("bob")
        bob.orient_axis(rod, rod.z, q.gamma)
        # the inertia is written in the rod frame: symmetric about the rod, so the twist
        # enters only through the bob's angular velocity
        inertia = p.inertia * (outer(rod.x, rod.x) + outer(rod.y, rod.y)) \
            + p.axial_inertia * outer(rod.z, rod.z)
        k.add_body(p.mass, p.hinge_height * T.z - p.length * rod.z, bob, inertia)
        k.add_potential(p.twist_stiffness * q.gamma**2 / 2)
        k.add_dissipation(p.twist_damping * k.qd.gamma**2 / 2)
