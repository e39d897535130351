"""The rigid (non-sloshing) part of the liquid."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._units import TINY_MASS
from .component import Component
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["FixedMass"]


class FixedMass(Component):
    """Liquid that moves rigidly with the tank: a rigid body on the tank axis.

    Parameters (``<name>.``): ``mass`` (kg), ``height`` of its centre above the tank origin
    (m), ``inertia`` about a transverse (pitch) axis through its centre (kg m^2) and
    ``axial_inertia`` about the tank axis (kg m^2). Heights and inertias enter only torques
    and rotating rigs; they are needed only when an output uses them.
    """

    parameters = {
        "mass": Param("kg", None, TINY_MASS, description="fixed (non-sloshing) liquid mass"),
        "height": Param("m", None, description="height of the fixed mass centre above the tank origin"),
        "inertia": Param("kg m^2", None, 0.0, description="pitch inertia about the fixed mass centre"),
        "axial_inertia": Param("kg m^2", None, 0.0, description="inertia about the tank axis"),
    }

    def __init__(self, name: str = "fixed", *, mass: float | None = None,
                 height: float | None = None, inertia: float | None = None,
                 axial_inertia: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(name, bounds=bounds, mass=mass, height=height, inertia=inertia,
                         axial_inertia=axial_inertia)

    def declare(self, k: "Declaration") -> None:
        from sympy.physics.mechanics import outer

        T, p = k.tank, k.p
        inertia = p.inertia * (outer(T.x, T.x) + outer(T.y, T.y)) + p.axial_inertia * outer(T.z, T.z)
        k.add_body(p.mass, p.height * T.z, T, inertia)
