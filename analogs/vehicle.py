"""Vehicle-coupled interface: the tank frame's motion given by a flight simulation.

At each step the vehicle knows the tank frame's linear acceleration, angular velocity and
angular acceleration and the local gravity (or thrust) acceleration, all in tank-frame
components; any derived model then returns the force and torque at the tank mount.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .component import Rig
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration

__all__ = ["VehicleFrame"]

_AXES = ("x", "y", "z")


class VehicleFrame(Rig):
    """A tank on a vehicle in flight: the tank frame's motion comes from the vehicle.

    Inputs (tank-frame components, SI units), in this order:

    - ``vehicle.accel_x/y/z`` (m/s^2): inertial acceleration of the tank origin ``O``;
    - ``vehicle.omega_x/y/z`` (rad/s): angular velocity of the tank frame;
    - ``vehicle.alpha_x/y/z`` (rad/s^2): its angular acceleration (the time derivative of
      the ``omega`` components, which for a frame's own angular velocity is the same
      taken in the tank or the inertial frame);
    - ``vehicle.gravity_x/y/z`` (m/s^2): the gravitational acceleration at the tank (zero
      in free fall; a thrusting vehicle's "apparent gravity" comes from ``accel``).

    ``planar=True`` keeps the in-plane components of the x-z plane only (``accel_x``,
    ``accel_z``, ``omega_y``, ``alpha_y``, ``gravity_x``, ``gravity_z``), for planar
    analogs such as :class:`~analogs.Pendulum`.

    Outputs are the model's usual ones: ``force_*`` and ``torque_*`` that the mount applies
    to the tank assembly (``dry_mass`` included, default 0 kg: liquid only), in tank-frame
    components, torques about ``O``; the force and torque the tank exerts on the vehicle
    are their negatives. About a mount point at ``r_M`` from ``O``, the torque is
    ``torque - r_M x force``. ``kinetic_energy`` is relative to a non-rotating frame moving
    with ``O``; ``potential_energy`` is that of the apparent gravity ``gravity - accel``.

    How: the translation of ``O`` enters Lagrange's equations only through its
    acceleration, exactly as a uniform inertial (d'Alembert) field ``-accel``; so the tank
    origin is held fixed and the apparent gravity ``gravity - accel`` acts instead, while the
    tank frame rotates with the prescribed angular velocity.

    Examples
    --------
    >>> from analogs import FixedMass, Pendulum
    >>> from analogs.vehicle import VehicleFrame
    >>> model = VehicleFrame(planar=True) + FixedMass("fixed") + Pendulum("p1")
    """

    def __init__(self, *, planar: bool = False, name: str = "vehicle",
                 bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        self.planar = bool(planar)
        self.parameters = {
            "dry_mass": Param("kg", 0.0, 0.0,
                              description="dry mass moving with the tank, seen by the mount"),
        }
        self.measured = (("force_x", "force_z", "torque_y") if self.planar else
                         ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z"))
        super().__init__(name, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return "planar" if self.planar else "3d"

    @property
    def axes(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Axes of the translational inputs (accel, gravity) and rotational ones (omega,
        alpha)."""
        return (("x", "z"), ("y",)) if self.planar else (_AXES, _AXES)

    def declare_frame(self, f: "FrameDeclaration") -> None:
        from sympy.physics.mechanics import Vector

        T, N = f.tank, f.inertial
        lin, rot = self.axes
        accel = {a: f.add_input(f"accel_{a}", "m/s^2", derivatives=0) for a in lin}
        omega = {a: f.add_input(f"omega_{a}", "rad/s", derivatives=0) for a in rot}
        for a in rot:
            f.add_input(f"alpha_{a}", "rad/s^2", derivatives=0, derivative_of=omega[a])
        gravity = {a: f.add_input(f"gravity_{a}", "m/s^2", derivatives=0) for a in lin}
        w = Vector(0)
        for a in rot:
            w += omega[a] * getattr(T, a)
        T.set_ang_vel(N, w)
        f.origin_position = Vector(0)
        apparent = Vector(0)
        for a in lin:
            apparent += (gravity[a] - accel[a]) * getattr(T, a)
        f.gravity = apparent
        f.add_particle(f.p.dry_mass, Vector(0))
