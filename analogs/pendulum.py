"""Pendulum analogs of lateral slosh modes: planar (1 DOF) and spherical (2 DOF)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ._units import TINY_LENGTH, TINY_MASS
from .component import Component
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["Pendulum", "SphericalPendulum"]

_PENDULUM_PARAMS = {
    "mass": Param("kg", None, TINY_MASS, description="pendulum (slosh) mass"),
    "length": Param("m", None, TINY_LENGTH, description="pendulum length"),
    "hinge_height": Param("m", None, description="hinge height above the tank origin"),
}


class _PendulumBase(Component):
    derived = {"frequency_hz": "Hz", "damping_ratio": "-"}

    def derived_values(self, v, *, gravity, hinge_stiffness, hinge_damping):
        """Small-amplitude frequency ``sqrt(g/L + k/(m L^2)) / 2 pi`` (Hz) and damping
        ratio ``c / (2 sqrt((m g L + k) m L^2))`` with ``k`` and ``c`` the hinge stiffness
        and damping of the attachments; only under uniform gravity."""
        m, L = v.get("mass"), v.get("length")
        if gravity is None or m is None or L is None:
            return {}
        k, c = hinge_stiffness, hinge_damping
        omega = (gravity / L + k / (m * L**2)) ** 0.5
        return {"frequency_hz": omega / (2 * math.pi),
                "damping_ratio": c / (2 * ((m * gravity * L + k) * m * L**2) ** 0.5)}

    def __init__(self, name: str, *, mass: float | None = None, length: float | None = None,
                 hinge_height: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(name, bounds=bounds, mass=mass, length=length, hinge_height=hinge_height)


class Pendulum(_PendulumBase):
    """Planar pendulum, one slosh mode: bob ``mass`` (kg) on a massless rod of ``length``
    (m) hinged on the tank axis at ``hinge_height`` (m).

    The coordinate ``theta`` (rad) is the rod angle from the tank's -z axis, positive when
    the bob moves toward +x (or +y for ``plane="yz"``). Hinge elements attach to it.
    """

    coordinates = ("theta",)
    coordinate_units = {"theta": "rad"}
    hinge_angles = ("theta",)
    parameters = _PENDULUM_PARAMS

    def __init__(self, name: str = "p1", *, mass: float | None = None,
                 length: float | None = None, hinge_height: float | None = None,
                 plane: str = "xz",
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        if plane not in ("xz", "yz"):
            raise InputError(f"Pendulum plane must be 'xz' or 'yz', got {plane!r}")
        self.plane = plane
        super().__init__(name, mass=mass, length=length, hinge_height=hinge_height, bounds=bounds)

    def _extra_structure(self) -> str:
        return self.plane

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        T, p, th = k.tank, k.p, k.q.theta
        lateral = T.x if self.plane == "xz" else T.y
        k.add_particle(p.mass, p.hinge_height * T.z + p.length * (sp.sin(th) * lateral - sp.cos(th) * T.z))


class SphericalPendulum(_PendulumBase):
    """Spherical pendulum (2 DOF) for three-dimensional rigs.

    Coordinates: ``alpha`` (rad), the swing toward +x, and ``beta`` (rad), the swing
    toward +y; the bob sits at ``hinge + L (sin a cos b, sin b, -cos a cos b)`` in the
    tank frame, so with ``beta = 0`` it is the planar :class:`Pendulum`.
    """

    coordinates = ("alpha", "beta")
    coordinate_units = {"alpha": "rad", "beta": "rad"}
    hinge_angles = ("alpha", "beta")
    parameters = _PENDULUM_PARAMS

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        T, p, a, b = k.tank, k.p, k.q.alpha, k.q.beta
        direction = sp.sin(a) * sp.cos(b) * T.x + sp.sin(b) * T.y - sp.cos(a) * sp.cos(b) * T.z
        k.add_particle(p.mass, p.hinge_height * T.z + p.length * direction)
