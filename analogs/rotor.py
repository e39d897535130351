"""Rotor analog of rotational slosh (Dodge's homogeneous-vortex model)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._units import TINY_INERTIA
from .component import Component
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["Rotor"]


class Rotor(Component):
    """A disk of inertia ``inertia`` (kg m^2) spinning about a tank axis, coupled to the
    tank only by a viscous torque ``-damping * psi_dot`` (N m s/rad).

    Coordinate ``psi`` (rad): the disk angle relative to the tank. The disk is massless
    in translation; only its angular momentum about ``axis`` matters.
    """

    coordinates = ("psi",)
    coordinate_units = {"psi": "rad"}
    parameters = {
        "inertia": Param("kg m^2", None, TINY_INERTIA, description="rotor inertia about its axis"),
        "damping": Param("N m s/rad", 0.0, 0.0, description="viscous coupling to the tank"),
    }

    def __init__(self, name: str = "rotor", *, inertia: float | None = None,
                 damping: float | None = None, axis: str = "z",
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        if axis not in ("x", "y", "z"):
            raise InputError(f"Rotor axis must be 'x', 'y' or 'z', got {axis!r}")
        self.axis = axis
        super().__init__(name, bounds=bounds, inertia=inertia, damping=damping)

    def _extra_structure(self) -> str:
        return self.axis

    def declare(self, k: "Declaration") -> None:
        from sympy.physics.mechanics import Vector, outer

        T = k.tank
        axis = getattr(T, self.axis)
        disk = k.frame("disk")
        disk.orient_axis(T, axis, k.q.psi)
        k.add_body(0, Vector(0), disk, k.p.inertia * outer(axis, axis))
        k.add_dissipation(k.p.damping * k.qd.psi**2 / 2)
