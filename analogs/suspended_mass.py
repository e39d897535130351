"""A mass suspended on springs and dampers along tank axes."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ._units import TINY_MASS
from .component import Component
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["SuspendedMass"]


class SuspendedMass(Component):
    """A point ``mass`` (kg) at rest at ``height`` (m) on the tank axis, free to move along
    the chosen tank ``axes`` against springs ``stiffness_<axis>`` (N/m) and dampers
    ``damping_<axis>`` (N s/m). Coordinates ``s_<axis>`` (m) are displacements from rest.
    """

    def __init__(self, name: str = "s1", *, axes: str = "x",
                 bounds: dict[str, tuple[float, float]] | None = None,
                 **values: float | None) -> None:
        if not axes or any(a not in "xyz" for a in axes) or len(set(axes)) != len(axes):
            raise InputError(f"SuspendedMass axes must be distinct letters of 'xyz', got {axes!r}")
        self.axes = axes
        self.coordinates = tuple(f"s_{a}" for a in axes)
        self.coordinate_units = {f"s_{a}": "m" for a in axes}
        self.derived = {f"{q}_{a}": u for a in axes
                        for q, u in (("frequency_hz", "Hz"), ("damping_ratio", "-"))}
        params = {
            "mass": Param("kg", None, TINY_MASS, description="suspended mass"),
            "height": Param("m", None, description="rest height above the tank origin"),
        }
        for a in axes:
            params[f"stiffness_{a}"] = Param("N/m", None, 0.0, description=f"spring along {a}")
            params[f"damping_{a}"] = Param("N s/m", 0.0, 0.0, description=f"damper along {a}")
        self.parameters = params
        super().__init__(name, bounds=bounds, **values)

    def _extra_structure(self) -> str:
        return self.axes

    def derived_values(self, v, *, gravity, hinge_stiffness, hinge_damping):
        """Per axis: ``sqrt(k/m) / 2 pi`` (Hz) and ``c / (2 sqrt(k m))``."""
        out = {}
        m = v.get("mass")
        for a in self.axes:
            k, c = v.get(f"stiffness_{a}"), v.get(f"damping_{a}", 0.0)
            if m is None or k is None:
                continue
            out[f"frequency_hz_{a}"] = (k / m) ** 0.5 / (2 * math.pi)
            out[f"damping_ratio_{a}"] = c / (2 * (k * m) ** 0.5)
        return out

    def declare(self, k: "Declaration") -> None:
        T, p = k.tank, k.p
        position = p.height * T.z
        for a in self.axes:
            s, sd = k.q[f"s_{a}"], k.qd[f"s_{a}"]
            position = position + s * getattr(T, a)
            k.add_potential(p[f"stiffness_{a}"] * s**2 / 2)
            k.add_dissipation(p[f"damping_{a}"] * sd**2 / 2)
        k.add_particle(p.mass, position)
