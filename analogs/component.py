"""Base classes of analog components: a component declares physics, it never integrates."""

from __future__ import annotations

import hashlib
import inspect
from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

from .parameter import Param, Parameter

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration, FrameDeclaration
    from .model import Model

__all__ = ["Component", "Attachment", "Rig"]


class Component:
    """An analog component declared by its coordinates, parameters, bodies and energies.

    Subclasses set the class attributes and implement :meth:`declare`; they never write
    equations of motion. Parameter values given as keywords become the defaults of the
    assembled model.

    Parameters
    ----------
    name : str
        Component name; its parameters are called ``"<name>.<parameter>"``.
    bounds : mapping, optional
        ``{"length": (lower, upper)}`` replaces declared physical bounds (they must stay
        inside the physical ones).
    **values : float
        Parameter values by local name (``mass=1.338``); unknown names raise ``TypeError``.

    Examples
    --------
    >>> from analogs import Pendulum
    >>> Pendulum("p1", mass=1.338, length=0.057).parameter("length").default
    0.057
    """

    #: Local names of the generalized coordinates the component adds.
    coordinates: ClassVar[tuple[str, ...]] = ()
    #: Parameter specifications by local name.
    parameters: ClassVar[Mapping[str, Param]] = {}
    #: Coordinates that hinge elements attached to this component act on.
    hinge_angles: ClassVar[tuple[str, ...]] = ()

    def __init__(
        self,
        name: str,
        *,
        bounds: Mapping[str, tuple[float, float]] | None = None,
        **values: float | None,
    ) -> None:
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(
                f"{type(self).__name__} name must be an identifier such as `p1`, got {name!r}"
            )
        self.name = name
        known = set(self.parameters)
        unknown = sorted(set(values) - known) + sorted(set(bounds or {}) - known)
        if unknown:
            raise TypeError(
                f"{type(self).__name__}({name!r}) has no parameter {', '.join(map(repr, unknown))}; "
                f"its parameters are {', '.join(sorted(known)) or 'none'}"
            )
        self._values = {k: float(v) for k, v in values.items() if v is not None}
        self._bounds = {k: (float(lo), float(hi)) for k, (lo, hi) in (bounds or {}).items()}

    # -- declared quantities ---------------------------------------------------------------
    @property
    def prefix(self) -> str:
        """Namespace of this component's parameters and coordinates."""
        return self.name

    @property
    def label(self) -> str:
        """Human-readable identification used in error messages."""
        return f"{type(self).__name__}({self.name!r})"

    def parameter(self, local: str) -> Parameter:
        """The bound :class:`Parameter` called ``local`` (e.g. ``"length"``)."""
        spec = self.parameters[local]
        lower, upper = self._bounds.get(local, (spec.lower, spec.upper))
        default = self._values.get(local, spec.default)
        return Parameter(
            f"{self.prefix}.{local}", spec.unit, default, lower, upper, spec.description
        )

    def bound_parameters(self) -> tuple[Parameter, ...]:
        """All parameters with full dotted names, in declaration order."""
        return tuple(self.parameter(k) for k in self.parameters)

    def problems(self) -> list[str]:
        """Problems of this component on its own (bounds, defaults)."""
        out = []
        for local, (lo, hi) in self._bounds.items():
            spec = self.parameters[local]
            if not lo <= hi:
                out.append(f"{self.label}: bounds of `{local}` are reversed: ({lo}, {hi})")
            if lo < spec.lower or hi > spec.upper:
                out.append(
                    f"{self.label}: bounds ({lo}, {hi}) of `{local}` leave the physical range "
                    f"[{spec.lower}, {spec.upper}] {spec.unit}"
                )
        for p in self.bound_parameters():
            if p.default is not None and (msg := p.check(p.default)):
                out.append(f"{self.label}: {msg}")
        return out

    def declare(self, k: "Declaration") -> None:
        """Declare bodies, energies and forces through ``k`` (see :class:`Declaration`)."""
        raise NotImplementedError(f"{type(self).__name__} must implement declare(k)")

    # -- identity, composition -------------------------------------------------------------
    def structure(self) -> str:
        """A string that changes whenever the derived equations could change.

        It holds the class, a hash of its source, the name and :meth:`_extra_structure`;
        parameter values and bounds are left out because equations are symbolic in them.
        """
        cls = type(self)
        try:
            source = inspect.getsource(cls)
        except (OSError, TypeError):
            source = cls.__qualname__
        digest = hashlib.sha256(source.encode()).hexdigest()[:16]
        return f"{cls.__module__}.{cls.__qualname__}[{digest}]({self.name};{self._extra_structure()})"

    def _extra_structure(self) -> str:
        """Constructor settings that are not parameters (axes, options)."""
        return ""

    def __add__(self, other: "Component | Model") -> "Model":
        from .model import Model

        return Model((self,)) + other

    def __repr__(self) -> str:
        vals = ", ".join(f"{k}={v!r}" for k, v in self._values.items())
        return f"{type(self).__name__}({self.name!r}{', ' if vals else ''}{vals})"


class Attachment(Component):
    """An element attached to a host component's hinge (spring, damper, diaphragm).

    The ``name`` is the host's name; the element's parameters live in the host's
    namespace (``HingeSpring("p1")`` has ``p1.stiffness``).
    """

    @property
    def host(self) -> str:
        """Name of the component this element attaches to."""
        return self.name

    @property
    def label(self) -> str:
        return f"{type(self).__name__} on {self.name!r}"


class Rig(Component):
    """The prescribed motion of the tank frame (a test rig or a vehicle).

    A rig declares how the tank frame ``T`` and its origin ``O`` move in the inertial
    frame, which signals it takes as inputs, the gravity vector, and the channels its
    transducer measures. Components never depend on which rig moves them.
    """

    #: Output channels the rig's transducer measures (names of model outputs).
    measured: ClassVar[tuple[str, ...]] = ()

    def __init__(
        self,
        name: str = "rig",
        *,
        bounds: Mapping[str, tuple[float, float]] | None = None,
        **values: float | None,
    ) -> None:
        super().__init__(name, bounds=bounds, **values)

    def declare(self, k: "Declaration") -> None:
        """Rigs add no generalized coordinates by default (the dry mass is added by
        :meth:`declare_frame`)."""

    def declare_frame(self, f: "FrameDeclaration") -> None:
        """Set the tank frame's motion, the inputs and gravity on ``f``."""
        raise NotImplementedError(f"{type(self).__name__} must implement declare_frame(f)")

