"""Test rigs: the prescribed motion of the tank frame."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .component import Rig
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import FrameDeclaration

__all__ = ["LateralRig", "crank_displacement"]

_GRAVITY = Param("m/s^2", 9.80665, 1e-9, description="gravity along -z of the inertial frame")
_DRY_MASS = Param("kg", None, 0.0, description="dry mass moving with the tank, seen by the transducer")


class LateralRig(Rig):
    """Lateral slosh rig: the tank translates along the inertial x axis under gravity -z.

    ``excitation="measured"``: the carriage displacement ``rig.x`` (m) is an input signal
    (with its first and second derivatives ``rig.x_dot``, ``rig.x_ddot``).

    ``excitation="crank"``: a flywheel turning at ``phi(t) = flywheel_angle +
    (2 pi drive_frequency + omega_correction) t`` drives the carriage through a crank of
    ``crank_radius`` and a connecting rod of ``rod_length`` ("locomotive arm"):
    ``x = r cos(phi) + sqrt(l^2 - r^2 sin^2 phi) - l`` (see :func:`crank_displacement`).

    The tank frame origin ``O`` is on the tank axis at the tank bottom and is the
    reference point of the transducer's torques. The measured channel is ``force_x``, the
    force the transducer applies to the tank assembly (dry mass included), in N.
    """

    measured = ("force_x",)

    def __init__(self, *, excitation: str = "measured", name: str = "rig",
                 bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        if excitation not in ("measured", "crank"):
            raise InputError(
                f"LateralRig excitation must be 'measured' or 'crank', got {excitation!r}"
            )
        self.excitation = excitation
        params = {"dry_mass": _DRY_MASS, "gravity": _GRAVITY}
        if excitation == "crank":
            params |= {
                "crank_radius": Param("m", None, 1e-9, description="crank (flywheel pin) radius"),
                "rod_length": Param("m", None, 1e-9, description="connecting rod length"),
                "drive_frequency": Param("Hz", None, 0.0, description="nominal flywheel frequency"),
                "omega_correction": Param("rad/s", 0.0, -0.5, 0.5,
                                          description="flywheel angular velocity correction"),
                "flywheel_angle": Param("rad", 0.0, -2.0, 2.0, description="initial flywheel angle"),
            }
        self.parameters = params
        super().__init__(name, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return self.excitation

    def restoring_gravity(self, v):
        return v.get("gravity")

    def problems(self) -> list[str]:
        out = super().problems()
        r = self._values.get("crank_radius")
        rod = self._values.get("rod_length")
        if r is not None and rod is not None and not rod > r:
            out.append(f"{self.label}: rod_length ({rod} m) must exceed crank_radius ({r} m)")
        return out

    def declare_frame(self, f: "FrameDeclaration") -> None:
        import sympy as sp
        from sympy.physics.mechanics import Vector

        N, T, p = f.inertial, f.tank, f.p
        T.orient_axis(N, N.z, 0)
        if self.excitation == "measured":
            x = f.add_input("x", "m")
        else:
            phi = p.flywheel_angle + (2 * sp.pi * p.drive_frequency + p.omega_correction) * f.t
            x = crank_displacement(phi, p.crank_radius, p.rod_length, sp)
        f.origin_position = x * N.x
        f.gravity = -p.gravity * N.z
        f.add_particle(p.dry_mass, Vector(0))


def crank_displacement(phi, radius, rod_length, lib=math):
    """Carriage displacement (m) of a crank of ``radius`` and rod of ``rod_length`` (m)
    at flywheel angle ``phi`` (rad): ``r cos(phi) + sqrt(l^2 - r^2 sin^2 phi) - l``.

    ``lib`` supplies ``cos``, ``sin`` and ``sqrt`` (``math``, ``numpy``, ``sympy``, ``casadi``).
    """
    return radius * lib.cos(phi) + lib.sqrt(rod_length**2 - (radius * lib.sin(phi)) ** 2) - rod_length
