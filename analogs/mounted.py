"""Place a component away from the tank origin: several tanks on one rig or spacecraft."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .component import Attachment, Component, Rig
from .errors import InputError
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["Mounted", "MOUNT_AXES"]

#: Orientations of a mounted component's own tank frame (see :class:`Mounted`).
MOUNT_AXES = ("parallel", "inward")

_MOUNT_PARAMS = {
    "mount_radius": Param("m", 0.0, 0.0,
                          description="distance of the component's tank origin from the z axis"),
    "mount_azimuth": Param("rad", 0.0, description="azimuth of the mount, from x toward y"),
    "mount_height": Param("m", 0.0, description="height of the component's tank origin along z"),
}


class Mounted(Component):
    """``component`` declared in its own tank frame ``M``, placed on the rig's tank frame
    ``T`` at ``mount_radius (cos(az) T.x + sin(az) T.y) + mount_height T.z`` (m), with
    ``az = mount_azimuth`` (rad): ``mount_radius`` (m, from the ``T.z`` axis),
    ``mount_azimuth`` (rad, from ``T.x`` toward ``T.y``) and ``mount_height`` (m, along
    ``T.z``) are the mount's parameters (None: given later, as any parameter value).

    ``axis="parallel"`` (default): ``M`` is ``T`` turned by ``az`` about ``T.z`` (so the
    component's x axis points radially outward). ``axis="inward"``: ``M.z`` points from the
    mount toward the ``T.z`` axis (a pendulum hangs outward in the centrifugal field of a
    spin about ``T.z``), ``M.x = T.z`` and ``M.y`` is tangential.

    The wrapped component keeps its name, coordinates, hinges and parameters (hinge
    elements attach to it by name as usual); the mount adds ``<name>.mount_radius``,
    ``<name>.mount_azimuth`` and ``<name>.mount_height``.

    Examples
    --------
    >>> from analogs import HingeDamper, SphericalPendulum
    >>> from analogs.mounted import Mounted
    >>> from analogs.spacecraft import FreeSpacecraft
    >>> model = (FreeSpacecraft()
    ...          + Mounted(SphericalPendulum("p1"), axis="inward", mount_radius=0.8)
    ...          + Mounted(SphericalPendulum("p2"), axis="inward", mount_radius=0.8,
    ...                    mount_azimuth=3.14159) + HingeDamper("p1") + HingeDamper("p2"))
    >>> model.parameter("p2.mount_radius").default
    0.8
    """

    def __init__(self, component: Component, *, axis: str = "parallel",
                 mount_radius: float | None = None, mount_azimuth: float | None = None,
                 mount_height: float | None = None) -> None:
        if isinstance(component, (Rig, Attachment, Mounted)) or not isinstance(component, Component):
            raise TypeError(
                f"Mounted wraps an analog component such as `SphericalPendulum('p1')`, got "
                f"{component!r}; attach hinge elements to the mounted component by name")
        if axis not in MOUNT_AXES:
            raise InputError(
                f"Mounted axis must be one of {', '.join(map(repr, MOUNT_AXES))}, got {axis!r}")
        clash = sorted(set(component.parameters) & set(_MOUNT_PARAMS))
        if clash:
            raise InputError(f"{component.label} already has parameters {clash}")
        self.component = component
        self.axis = axis
        self.coordinates = component.coordinates
        self.coordinate_units = component.coordinate_units
        self.derived = component.derived
        self.hinge_angles = component.hinge_angles
        self.parameters = {**component.parameters, **_MOUNT_PARAMS}
        mount = {"mount_radius": mount_radius, "mount_azimuth": mount_azimuth,
                 "mount_height": mount_height}
        super().__init__(component.name, bounds=component.given_bounds,
                         **component.given_values, **mount)

    @property
    def label(self) -> str:
        return f"Mounted({self.component.label})"

    def _extra_structure(self) -> str:
        return f"{self.axis};{self.component.structure()}"

    def problems(self) -> list[str]:
        return super().problems() + self.component.problems()

    def derived_values(self, v, **context):
        """The wrapped component's derived quantities (``context``: the keywords of
        :meth:`Component.derived_values`)."""
        return self.component.derived_values(v, **context)

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        T, p = k.tank, k.p
        azimuth = k.frame("mount_azimuth")
        azimuth.orient_axis(T, T.z, p.mount_azimuth)
        if self.axis == "parallel":
            frame = azimuth
        else:
            frame = k.frame("mount")
            frame.orient_axis(azimuth, azimuth.y, -sp.pi / 2)
        offset = p.mount_radius * azimuth.x + p.mount_height * T.z
        self.component.declare(_MountedDeclaration(k, frame, offset))

    def __repr__(self) -> str:
        vals = ", ".join(f"{n}={v!r}" for n, v in self._values.items() if n in _MOUNT_PARAMS)
        return f"Mounted({self.component!r}, axis={self.axis!r}{', ' if vals else ''}{vals})"


class _MountedDeclaration:
    """A component's view of a mount: its own tank frame, positions shifted by the mount."""

    def __init__(self, k: "Declaration", frame: Any, offset: Any) -> None:
        self._k = k
        self._frame = frame
        self._offset = offset

    @property
    def tank(self):
        return self._frame

    def __getattr__(self, name: str) -> Any:
        return getattr(self._k, name)

    def add_particle(self, mass, position) -> None:
        self._k.add_particle(mass, self._offset + position)

    def add_body(self, mass, position, frame, inertia) -> None:
        self._k.add_body(mass, self._offset + position, frame, inertia)
