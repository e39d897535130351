"""A rig that moves the tank in 3-D, its motion measured: translation and attitude as inputs,
six force/torque channels at the transducer's reference point in the transducer's axes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from .component import Rig
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration

__all__ = ["MotionRig", "MOTION_AXES", "TRANSLATIONS", "ROTATIONS", "TRANSDUCER_PARAMETERS"]

#: Translations of the tank origin in the lab (m), along the lab's x, y, z.
TRANSLATIONS = ("x", "y", "z")
#: Attitude angles of the tank frame (rad): z-y-x (yaw, then pitch, then roll) Tait-Bryan.
ROTATIONS = ("roll", "pitch", "yaw")
#: Every motion axis, in the order the rig declares its inputs.
MOTION_AXES = TRANSLATIONS + ROTATIONS
#: The rig parameters that place the transducer: its reference point (m, tank axes) and the
#: turn of its axes from the tank's (rad, z-y-x).
TRANSDUCER_PARAMETERS = ("transducer_x", "transducer_y", "transducer_z",
                         "transducer_roll", "transducer_pitch", "transducer_yaw")


class MotionRig(Rig):
    """A tank moved by a rig whose motion is measured in 3-D (a hexapod, a robot arm, a
    shaker table, or a lateral carriage with a six-axis transducer).

    The lab frame ``N`` is inertial with ``N.z`` up; gravity acts along ``-N.z``. The tank
    frame ``T`` (origin ``O`` on the tank axis at the tank bottom) is placed by the input
    signals of ``axes`` (each with its first and second time derivatives, ``rig.<axis>``,
    ``rig.<axis>_dot``, ``rig.<axis>_ddot``), the axes left out being held at zero:

    - ``x``, ``y``, ``z`` (m): the position of ``O`` in lab components;
    - ``roll``, ``pitch``, ``yaw`` (rad): the attitude ``R = Rz(yaw) Ry(pitch) Rx(roll)``
      of ``T`` in ``N`` (z-y-x Tait-Bryan angles, any size away from pitch = +/-90 deg); at
      zero angles ``T = N``.

    With ``axes=("x",)`` this is :class:`~analogs.LateralRig`'s motion (the input is the
    same ``rig.x``).

    The transducer measures ``force_x/y/z`` (N) and ``torque_x/y/z`` (N m), the force and
    torque it applies to the tank assembly, in its own axes ``S`` and about its reference
    point ``P``: ``F_S = R_S^T F``, ``M_S = R_S^T (M_O - r_P x F)``, with ``r_P =
    (transducer_x, transducer_y, transducer_z)`` (m, tank components) and ``R_S =
    Rz(transducer_yaw) Ry(transducer_pitch) Rx(transducer_roll)`` the turn of its axes from
    the tank's (rad; a transducer mounted turned by 180 deg about the tank axis has
    ``transducer_yaw = pi``). All six are 0 by default: the channels are then the tank-frame
    force and the torque about ``O``, as on the other rigs. The rig carries ``dry_mass``
    (kg) at ``O``.

    Parameters (``rig.``): ``dry_mass`` (kg), ``gravity`` (m/s^2) and the six transducer
    parameters (:data:`TRANSDUCER_PARAMETERS`), which a case file fixes.

    Examples
    --------
    >>> from analogs import FixedMass, SphericalPendulum
    >>> from analogs.motion_rig import MotionRig
    >>> model = MotionRig(axes=("x", "y", "pitch")) + FixedMass("fixed") + SphericalPendulum("p1")
    >>> model.rig.axes
    ('x', 'y', 'pitch')
    """

    measured = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")

    def __init__(self, *, axes: Sequence[str] = ("x",), name: str = "rig",
                 bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        if isinstance(axes, str) or not all(isinstance(a, str) for a in axes):
            raise InputError(f"MotionRig axes must be a sequence of axis names from "
                             f"{', '.join(MOTION_AXES)}, e.g. `axes=(\"x\", \"pitch\")`; got "
                             f"{axes!r}")
        unknown = [a for a in axes if a not in MOTION_AXES]
        repeated = sorted({a for a in axes if list(axes).count(a) > 1})
        if unknown or repeated or not axes:
            why = (f"unknown {', '.join(map(repr, unknown))}" if unknown else
                   f"repeated {', '.join(map(repr, repeated))}" if repeated else "none given")
            raise InputError(f"MotionRig axes: {why}; expected one or more of "
                             f"{', '.join(MOTION_AXES)}")
        self.axes = tuple(a for a in MOTION_AXES if a in axes)
        params = {
            "dry_mass": Param("kg", None, 0.0,
                              description="dry mass moving with the tank at its origin, seen by "
                                          "the transducer"),
            "gravity": Param("m/s^2", 9.80665, 1e-9,
                             description="gravity along -z of the lab frame"),
        }
        for axis in TRANSLATIONS:
            params[f"transducer_{axis}"] = Param(
                "m", 0.0, description=f"transducer reference point, tank {axis} component")
        for angle in ROTATIONS:
            params[f"transducer_{angle}"] = Param(
                "rad", 0.0, description=f"{angle} of the transducer axes from the tank axes "
                                        "(z-y-x)")
        self.parameters = params
        super().__init__(name, bounds=bounds, **values)

    @property
    def rotates(self) -> bool:
        """Whether the tank's attitude is an input."""
        return any(a in ROTATIONS for a in self.axes)

    def _extra_structure(self) -> str:
        return ",".join(self.axes)

    def restoring_gravity(self, v):
        # the tank's tilts are small on such rigs: the slosh frequencies are those under g
        return v.get("gravity")

    def declare_frame(self, f: "FrameDeclaration") -> None:
        import sympy as sp
        from sympy.physics.mechanics import Vector

        N, T, p = f.inertial, f.tank, f.p
        units = {a: "m" for a in TRANSLATIONS} | {a: "rad" for a in ROTATIONS}
        signal = {a: f.add_input(a, units[a]) if a in self.axes else sp.S.Zero
                  for a in MOTION_AXES}
        if self.rotates:
            T.orient_body_fixed(N, (signal["yaw"], signal["pitch"], signal["roll"]), "zyx")
        else:
            T.orient_axis(N, N.z, 0)
        f.origin_position = signal["x"] * N.x + signal["y"] * N.y + signal["z"] * N.z
        f.gravity = -p.gravity * N.z
        f.add_particle(p.dry_mass, Vector(0))
        S = f.frame("transducer")
        S.orient_body_fixed(T, (p.transducer_yaw, p.transducer_pitch, p.transducer_roll), "zyx")
        f.set_transducer(p.transducer_x * T.x + p.transducer_y * T.y + p.transducer_z * T.z, S)
