"""Spinning slosh test rig: a tank spinning about the table axis while that axis nutates."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .component import Rig
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration

__all__ = ["SpinningRig", "TANK_AXES", "MOTIONS", "MOTION_INPUTS"]

#: Orientations of the tank axis on a spinning table (see :class:`SpinningRig`).
TANK_AXES = ("spin", "inward")
#: How the rig motion is given (see :class:`SpinningRig`).
MOTIONS = ("constant", "input")
#: The rig's input signals with ``motion="input"`` (each with ``_dot`` and ``_ddot``), in
#: the order the derived model lists them: the table's spin angle, the nutation (precession)
#: phase of the table axis about the vertical and the cone half-angle, all in rad.
MOTION_INPUTS = ("spin_angle", "nutation_phase", "cone_angle")


class SpinningRig(Rig):
    """Spinning Slosh Test Rig: spin about the table axis plus an independent nutation.

    The motion of the tank frame is a 3-1-3 rotation from the inertial frame ``N``
    (``N.z`` up, the table axis at rest) by three angles, the nutation phase ``phi(t)``,
    the cone half-angle ``theta_n(t)`` and the table's spin angle ``sigma(t)``:

    1. the nutation frame ``C`` turns about ``N.z`` by ``phi``;
    2. the table frame ``D`` is ``C`` tilted about ``C.x`` by the cone half-angle
       ``theta_n``: the table (spin) axis ``D.z`` sweeps a cone of half-angle ``theta_n``
       about ``N.z`` at ``phi' / 2 pi`` Hz (positive: in the sense of the spin), with its
       vertex at the inertial origin (the nutation pivot);
    3. the spin frame ``S`` turns about ``D.z`` by ``sigma - phi``, so that without
       nutation (``theta_n = 0``) the table has turned by exactly ``sigma`` about ``N.z``
       whatever ``phi``; its angular velocity is ``phi' N.z + theta_n' C.x + (sigma' -
       phi') D.z``. Seen from the spinning table, the tilt of the table axis turns
       backwards at ``sigma' - phi'`` rad/s.

    ``motion="constant"`` (default): ``sigma = Omega_s t``, ``phi = 2 pi f_n t`` and a
    constant ``theta_n``, all parameters (the rig takes no input signals).
    ``motion="input"``: the three angles are input signals ``rig.spin_angle``,
    ``rig.nutation_phase`` and ``rig.cone_angle`` (rad), each with its first and second
    time derivatives (``_dot``, ``_ddot``; :data:`MOTION_INPUTS`), as a test records them
    (a table spun up, a cone angle ramped in) or as a schedule
    (:class:`derive.schedule.Schedule`) gives them; the parameters ``spin_rate``,
    ``nutation_angle`` and ``nutation_frequency`` are then absent.

    The tank origin ``O`` (the transducer's mount point and torque reference) sits at
    ``O = height D.z + radius S.x``: ``radius`` (m) from the spin axis along the radial
    direction ``S.x`` (0: on the axis, as on the modified SSTR) and ``height`` (m) above the
    nutation pivot along the spin axis. ``S.y`` is the tangential direction (the way ``O``
    moves for ``Omega_s > 0``).

    ``tank_axis`` orients the tank frame ``T`` in which components are declared:

    - ``"spin"`` (default): ``T = S``, the tank axis ``T.z`` along the spin axis and
      ``T.x`` radially outward; at ``t = 0``, ``T.x = N.x``, ``T.y = cos(theta_n) N.y +
      sin(theta_n) N.z`` and ``T.z = -sin(theta_n) N.y + cos(theta_n) N.z``.
    - ``"inward"``: ``T.z = -S.x`` points from ``O`` toward the spin axis, so that analogs
      that hang along ``-T.z`` (pendulums) hang outward in the centrifugal field;
      ``T.x = S.z`` (the spin axis) and ``T.y = S.y`` (tangential).

    Gravity acts along ``-N.z`` with magnitude ``rig.gravity`` unless ``gravity=False``
    (a table in orbit, or to study the centrifugal field alone). The rig carries
    ``dry_mass`` (kg) at ``O``. Measured channels: ``force_x/y/z`` (N) and
    ``torque_x/y/z`` (N m) that the transducer applies to the tank assembly, in tank-frame
    components, torques about ``O``.

    Parameters (``rig.``): ``spin_rate`` (rad/s), ``radius`` (m, default 0),
    ``height`` (m, default 0), ``nutation_angle`` (rad, default 0, in [0, pi/2)),
    ``nutation_frequency`` (Hz, default 0, either sign), ``dry_mass`` (kg) and, with
    gravity, ``gravity`` (m/s^2); with ``motion="input"`` only ``dry_mass``, ``radius``,
    ``height`` and ``gravity``.

    Examples
    --------
    >>> from analogs import SphericalPendulum
    >>> from analogs.spinning import SpinningRig
    >>> model = SpinningRig(spin_rate=6.0, radius=0.5) + SphericalPendulum("p1")
    >>> model.rig.measured[:3]
    ('force_x', 'force_y', 'force_z')
    """

    measured = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")

    def __init__(self, *, gravity: bool = True, tank_axis: str = "spin", motion: str = "constant",
                 name: str = "rig", bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        if motion not in MOTIONS:
            raise InputError(
                f"SpinningRig motion must be one of {', '.join(map(repr, MOTIONS))}, got {motion!r}")
        if tank_axis not in TANK_AXES:
            raise InputError(
                f"SpinningRig tank_axis must be one of {', '.join(map(repr, TANK_AXES))}, "
                f"got {tank_axis!r}")
        if not isinstance(gravity, bool):
            raise TypeError(
                f"SpinningRig(gravity=...) says whether gravity acts (True/False), got "
                f"{gravity!r}; give its value as a parameter, e.g. `{{'rig.gravity': 9.81}}`")
        self.with_gravity = gravity
        self.tank_axis = tank_axis
        self.motion = motion
        params = {
            "dry_mass": Param("kg", None, 0.0,
                              description="dry mass moving with the tank, seen by the transducer"),
            "spin_rate": Param("rad/s", None, description="table spin rate Omega_s about its axis"),
            "radius": Param("m", 0.0, 0.0, description="distance of the tank origin from the spin axis"),
            "height": Param("m", 0.0, description="height of the tank origin above the nutation pivot"),
            "nutation_angle": Param("rad", 0.0, 0.0, math.pi / 2 - 1e-6,
                                    description="half-angle of the cone swept by the table axis"),
            "nutation_frequency": Param("Hz", 0.0,
                                        description="coning frequency of the table axis about "
                                                    "the vertical (positive: with the spin)"),
        }
        if motion == "input":
            for key in ("spin_rate", "nutation_angle", "nutation_frequency"):
                del params[key]
        if gravity:
            params["gravity"] = Param("m/s^2", 9.80665, 0.0,
                                      description="gravity along -z of the inertial frame")
        self.parameters = params
        super().__init__(name, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return f"{self.tank_axis};{'g' if self.with_gravity else 'no-g'};{self.motion}"

    def declare_frame(self, f: "FrameDeclaration") -> None:
        import sympy as sp
        from sympy.physics.mechanics import Vector

        N, T, p = f.inertial, f.tank, f.p
        if self.motion == "input":
            sigma, phi, theta = (f.add_input(name, "rad") for name in MOTION_INPUTS)
        else:
            phi = 2 * sp.pi * p.nutation_frequency * f.t
            sigma, theta = p.spin_rate * f.t, p.nutation_angle
        C, D, S = f.frame("nutation"), f.frame("table"), f.frame("spin")
        C.orient_axis(N, N.z, phi)
        D.orient_axis(C, C.x, theta)
        S.orient_axis(D, D.z, sigma - phi)
        if self.tank_axis == "spin":
            T.orient_axis(S, S.z, 0)
        else:
            T.orient_axis(S, S.y, -sp.pi / 2)
        f.origin_position = p.height * D.z + p.radius * S.x
        f.gravity = -p.gravity * N.z if self.with_gravity else Vector(0)
        f.add_particle(p.dry_mass, Vector(0))
