"""Vehicle-coupled interface: the tank frame's motion given by a flight simulation.

At each step the vehicle knows the tank frame's linear acceleration, angular velocity and
angular acceleration and the local gravity (or thrust) acceleration, all in tank-frame
components; any derived model then returns the force and torque at the tank mount.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .component import Attachment, Component, Rig
from .errors import InputError
from .fixed_mass import FixedMass
from .hinge import DiaphragmSpring, HingeDamper, HingeSpring, SwingDamper
from .parameter import Param
from .pendulum import Pendulum, SphericalPendulum

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration
    from .model import Model

__all__ = ["VehicleFrame", "axisymmetric", "degrees_of_freedom"]

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


#: Hinge elements that act alike on a spherical pendulum's two angles and on a planar
#: pendulum's one: linear in the angle or its rate, so a swing along either tank axis is the
#: planar swing and any other direction agrees at small amplitude.
_LINEAR_HINGE = (HingeSpring, HingeDamper, DiaphragmSpring, SwingDamper)


def axisymmetric(model: "Model") -> "Model":
    """The analog of an axisymmetric tank in three dimensions: ``model`` (a lateral-rig
    analog, rig included or not) with each planar :class:`~analogs.Pendulum` replaced by a
    :class:`~analogs.SphericalPendulum` of the same name, parameter values and bounds.

    The slosh mass, length, hinge height and hinge spring and damper are the same about
    both lateral axes, as they are in a tank symmetric about its z axis (a sphere,
    cylinder or capsule); a swing along tank x or along tank y is then exactly the planar
    analog's swing. The hinge damper becomes a :class:`~analogs.SwingDamper` (the same
    ``damping``, on the rod's angular velocity), so the damping is the same in every
    direction of swing; the hinge spring and a diaphragm act on each of the spherical
    pendulum's angles (``alpha`` toward +x, ``beta`` toward +y), which for a swing in
    another direction agrees with an isotropic hinge to second order in the swing angle.

    Raises
    ------
    InputError
        When a component cannot be made three-dimensional this way (an amplitude-dependent
        hinge element acts on each angle separately, not on the swing; a suspended mass
        or any other component has no axisymmetric form here); the message names it.

    Examples
    --------
    >>> from analogs import FixedMass, HingeDamper, LateralRig, Pendulum
    >>> m = axisymmetric(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1"))
    >>> [type(c).__name__ for c in m.components]
    ['LateralRig', 'FixedMass', 'SphericalPendulum', 'SwingDamper']
    """
    from .model import Model

    planar = {c.name for c in model.components if type(c) is Pendulum}
    out, problems = [], []
    for c in model.components:
        if type(c) is Pendulum:
            out.append(SphericalPendulum(c.name, bounds=c.given_bounds, **c.given_values))
        elif type(c) is HingeDamper and c.host in planar:
            out.append(SwingDamper(c.host, bounds=c.given_bounds, **c.given_values))
        elif isinstance(c, (Rig, FixedMass, SphericalPendulum)):
            out.append(c)
        elif isinstance(c, Attachment) and c.host in planar:
            if type(c) not in _LINEAR_HINGE:
                problems.append(
                    f"{c.label} acts on each angle of a spherical pendulum separately, not "
                    "on the swing, so its 3-D form would depend on the swing direction")
            out.append(c)
        elif isinstance(c, Attachment):
            out.append(c)
        else:
            problems.append(f"{c.label} has no axisymmetric three-dimensional form here")
    if problems:
        raise InputError(
            "the analog cannot be made three-dimensional (slosh along tank x and y): "
            + "; ".join(problems) + "; export the in-plane (x-z) form with `--planar` "
            "(`VehicleFrame(planar=True)`) instead")
    return Model(out)


def degrees_of_freedom(model: "Model") -> tuple[str, ...]:
    """One line per component with coordinates: its name, kind, number of degrees of
    freedom, coordinates and, for slosh analogs, the directions they swing in; e.g.
    ``"p1: SphericalPendulum, 2 DOF (p1.alpha, p1.beta): slosh along tank x (p1.alpha) and
    y (p1.beta)"``.
    Rigs and components without coordinates (rigid masses) are summed up in a last line.
    """
    lines, rigid = [], []
    for c in model.components:
        if isinstance(c, (Rig, Attachment)):
            continue
        if not c.coordinates:
            rigid.append(c.name)
            continue
        coords = ", ".join(f"{c.name}.{q}" for q in c.coordinates)
        line = f"{c.name}: {type(c).__name__}, {len(c.coordinates)} DOF ({coords})"
        swing = _swing(c)
        lines.append(line + (f": {swing}" if swing else ""))
    if rigid:
        lines.append(f"{', '.join(rigid)}: rigid, no DOF")
    return tuple(lines)


def _swing(c: Component) -> str:
    if type(c) is Pendulum:
        axis = "x" if c.plane == "xz" else "y"
        return (f"slosh along tank {axis} only (planar, {c.plane[0]}-{c.plane[1]} plane): "
                f"none along tank {'y' if axis == 'x' else 'x'}")
    if type(c) is SphericalPendulum:
        return f"slosh along tank x ({c.name}.alpha) and y ({c.name}.beta)"
    return ""
