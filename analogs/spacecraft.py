"""A free spin-stabilised spacecraft carrying a tank: the bus is the rig, with coordinates.

The bus is a rigid body free in space (no gravity, no external force or torque). Its
attitude (and, optionally, the position of its centre of mass) are generalized coordinates
of the rig, so the analog components in the tank move the bus and the bus moves them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ._units import TINY_INERTIA, TINY_MASS
from .component import Rig
from .errors import InputError
from .parameter import Param
from .spinning import TANK_AXES

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration

__all__ = ["FreeSpacecraft", "body_angular_velocity"]


class FreeSpacecraft(Rig):
    """A spin-stabilised spacecraft bus, free in space, carrying one tank.

    Kinematics. A reference frame ``R`` spins at the nominal ``spin_rate`` ``Omega``
    (rad/s) about the inertial ``N.z``. The bus frame ``B`` (principal axes of the bus,
    ``B.z`` the nominal spin axis) is oriented relative to ``R`` by the body-fixed 1-2-3
    angles ``phi``, ``theta``, ``psi`` (rad): rotate about ``R.x`` by ``phi``, then about
    the new y by ``theta``, then about the new z by ``psi``. Steady spin at ``Omega`` about
    ``N.z`` is the state with all three angles and their rates zero, so the equations are
    autonomous and steady spin is an equilibrium (the angles stay small near it; the set is
    singular only at ``theta = +-90 deg``). With ``translation=True`` (default) the bus
    centre of mass is at ``x R.x + y R.y + z R.z`` (m); otherwise it is held at the origin,
    which is exact only for components without translating mass (rotors).

    Coordinates (``<name>.``): ``x``, ``y``, ``z`` (with translation), ``phi``, ``theta``,
    ``psi``.

    The tank origin ``O`` (where components are declared) is at ``radius B.x + height B.z``
    from the bus centre of mass. ``tank_axis="spin"``: the tank frame ``T`` is ``B``;
    ``"inward"``: ``T.z = -B.x`` points toward the spin axis (pendulums hang outward in
    the centrifugal field), ``T.x = B.z`` and ``T.y = B.y``.

    Parameters (``<name>.``): ``spin_rate`` (rad/s), ``mass`` (kg) and the central principal
    inertias ``inertia_x``, ``inertia_y``, ``inertia_z`` (kg m^2) of the bus without the
    modelled liquid, ``radius`` and ``height`` (m) of the tank origin.

    Outputs: no channel is measured (``measured = ()``); the force and torque outputs are
    those on the whole spacecraft, zero up to round-off for a free body.

    Examples
    --------
    >>> from analogs import Rotor
    >>> from analogs.spacecraft import FreeSpacecraft
    >>> model = (FreeSpacecraft(translation=False) + Rotor("rx", axis="x")
    ...          + Rotor("ry", axis="y"))
    >>> model.rig.coordinates
    ('phi', 'theta', 'psi')
    """

    measured = ()

    def __init__(self, *, translation: bool = True, tank_axis: str = "spin",
                 name: str = "bus", bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        if tank_axis not in TANK_AXES:
            raise InputError(
                f"FreeSpacecraft tank_axis must be one of {', '.join(map(repr, TANK_AXES))}, "
                f"got {tank_axis!r}")
        self.translation = bool(translation)
        self.tank_axis = tank_axis
        self.coordinates = (("x", "y", "z") if self.translation else ()) + ("phi", "theta", "psi")
        self.coordinate_units = {c: "m" if c in "xyz" else "rad" for c in self.coordinates}
        self.parameters = {
            "spin_rate": Param("rad/s", None, description="nominal spin rate about the bus z axis"),
            "mass": Param("kg", None, TINY_MASS, description="bus mass (without modelled liquid)"),
            "inertia_x": Param("kg m^2", None, TINY_INERTIA, description="bus central inertia about x"),
            "inertia_y": Param("kg m^2", None, TINY_INERTIA, description="bus central inertia about y"),
            "inertia_z": Param("kg m^2", None, TINY_INERTIA,
                               description="bus central inertia about the spin axis z"),
            "radius": Param("m", 0.0, 0.0, description="tank origin's distance from the bus z axis, along x"),
            "height": Param("m", 0.0,
                            description="tank origin's height along z above the bus centre of mass"),
        }
        super().__init__(name, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return f"{'translation' if self.translation else 'fixed-cm'};{self.tank_axis}"

    def problems(self) -> list[str]:
        out = super().problems()
        ix, iy, iz = (self._values.get(f"inertia_{a}") for a in "xyz")
        if None not in (ix, iy, iz):
            a, b, c = sorted((ix, iy, iz))
            if a + b < c:
                out.append(f"{self.label}: inertias ({ix}, {iy}, {iz}) kg m^2 violate the "
                           "triangle inequality of a rigid body")
        return out

    def declare_frame(self, f: "FrameDeclaration") -> None:
        import sympy as sp
        from sympy.physics.mechanics import Vector, outer

        N, T, p, q = f.inertial, f.tank, f.p, f.q
        R = f.frame("reference")
        R.orient_axis(N, N.z, p.spin_rate * f.t)
        # expressed in R, so that N's basis (and explicit time) never enters the energies
        R.set_ang_vel(N, p.spin_rate * R.z)
        B = f.frame("bus")
        B.orient_body_fixed(R, (q.phi, q.theta, q.psi), "123")
        if self.tank_axis == "spin":
            T.orient_axis(B, B.z, 0)
        else:
            T.orient_axis(B, B.y, -sp.pi / 2)
        centre = q.x * R.x + q.y * R.y + q.z * R.z if self.translation else Vector(0)
        f.origin_position = centre + p.radius * B.x + p.height * B.z
        f.gravity = Vector(0)
        inertia = (p.inertia_x * outer(B.x, B.x) + p.inertia_y * outer(B.y, B.y)
                   + p.inertia_z * outer(B.z, B.z))
        f.add_body(p.mass, -(p.radius * B.x + p.height * B.z), B, inertia)


def body_angular_velocity(phi, theta, psi, phi_dot, theta_dot, psi_dot, spin_rate,
                          lib=np):
    """Angular velocity of the bus in bus axes (rad/s) from the :class:`FreeSpacecraft`
    coordinates ``phi``, ``theta``, ``psi`` (rad, the 1-2-3 angles) and their rates
    ``phi_dot``, ``theta_dot``, ``psi_dot`` (rad/s) relative to the reference frame, plus
    ``spin_rate`` (rad/s) about the inertial z axis.

    Returns the tuple ``(omega_x, omega_y, omega_z)``; ``lib`` supplies ``sin`` and
    ``cos`` (``numpy`` for arrays, ``casadi`` for symbolic use).

    Examples
    --------
    >>> [round(float(w), 6) for w in body_angular_velocity(0, 0, 0, 0.01, 0, 0, 5.0)]
    [0.01, 0.0, 5.0]
    """
    sf, cf, st, ct = lib.sin(phi), lib.cos(phi), lib.sin(theta), lib.cos(theta)
    sp_, cp = lib.sin(psi), lib.cos(psi)
    wx = phi_dot * ct * cp + theta_dot * sp_
    wy = -phi_dot * ct * sp_ + theta_dot * cp
    wz = phi_dot * st + psi_dot
    # the reference frame's z axis (the nominal spin axis) in bus components
    zx = sf * sp_ - cf * st * cp
    zy = sf * cp + cf * st * sp_
    zz = cf * ct
    return wx + spin_rate * zx, wy + spin_rate * zy, wz + spin_rate * zz
