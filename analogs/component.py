"""Base classes of analog components: a component declares physics, it never integrates."""

from __future__ import annotations

import hashlib
import inspect
import sys
import weakref
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from .errors import InputError
from .parameter import Param, Parameter

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration, FrameDeclaration
    from .model import Model

__all__ = ["Component", "Attachment", "Rig", "SourceUnavailable"]


class SourceUnavailable(RuntimeError):
    """The source of a component class (or of the module defining it) cannot be read, e.g.
    a class made with ``exec``: its equations cannot be keyed for the derivation cache."""

    def __init__(self, cls: type, what: str) -> None:
        self.cls = cls
        super().__init__(
            f"the source of {what} of {cls.__module__}.{cls.__qualname__} cannot be read "
            "(a class made with `exec` or typed into an interactive interpreter?)")


def source_digest(cls: type) -> str:
    """Hash of the source of every class in ``cls``'s MRO (up to :class:`Component`) and of
    the modules defining them, so that a change to a base class or to a module-level helper
    that ``declare`` calls changes the digest. Raises :class:`SourceUnavailable`.

    Computed once per class object: the code a class runs cannot change without a new class
    object (a reload or a new definition), which gets its own digest."""
    if cls not in _DIGESTS:
        _DIGESTS[cls] = _source_digest(cls)
    return _DIGESTS[cls]


_DIGESTS: "weakref.WeakKeyDictionary[type, str]" = weakref.WeakKeyDictionary()


def _source_digest(cls: type) -> str:
    h = hashlib.sha256()
    for klass in cls.__mro__:
        if klass is object:
            continue
        text, classes = _module_source(sys.modules.get(klass.__module__), klass)
        if klass.__qualname__ not in classes:
            raise SourceUnavailable(klass, "the class")
        h.update(klass.__qualname__.encode())
        h.update(text.encode())  # holds the class's own source
        if klass is Component:
            break
    return h.hexdigest()[:16]


def _module_source(module, klass: type) -> tuple[str, frozenset[str]]:
    """The source of ``module`` and the qualified names of the classes it defines (parsed
    once per source text: reading each class with ``inspect.getsource`` parses the module
    again for every class)."""
    try:
        text = inspect.getsource(module)  # type: ignore[arg-type]
    except (OSError, TypeError):
        raise SourceUnavailable(klass, "the module") from None
    if text not in _CLASSES:
        import ast

        names: set[str] = set()

        def visit(node, prefix: str) -> None:
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.ClassDef):
                    names.add(prefix + child.name)
                    visit(child, f"{prefix}{child.name}.")
                elif isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    visit(child, f"{prefix}{child.name}.<locals>.")
                else:
                    visit(child, prefix)

        visit(ast.parse(text), "")
        _CLASSES[text] = frozenset(names)
    return text, _CLASSES[text]


_CLASSES: dict[str, frozenset[str]] = {}


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
    #: SI unit of each coordinate by local name (``"rad"``, ``"m"``); every coordinate
    #: needs one (exports and reports read it here).
    coordinate_units: ClassVar[Mapping[str, str]] = {}
    #: Quantities derived from the parameters (:meth:`derived_values`), name -> SI unit.
    derived: ClassVar[Mapping[str, str]] = {}
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
            raise InputError(
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

    @property
    def given_values(self) -> dict[str, float]:
        """Parameter values given to the constructor (SI units), by local name: a copy,
        without the declared defaults (``Pendulum("p1", length=0.05).given_values`` is
        ``{"length": 0.05}``)."""
        return dict(self._values)

    @property
    def given_bounds(self) -> dict[str, tuple[float, float]]:
        """Bounds given to the constructor (``bounds=``), by local name: a copy, without
        the declared physical bounds."""
        return dict(self._bounds)

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

    def coordinate_unit(self, local: str) -> str:
        """SI unit of the coordinate ``local`` (e.g. ``"rad"`` for ``"theta"``)."""
        return self.coordinate_units[local]

    def derived_values(self, v: Mapping[str, Any], *, gravity: Any | None,
                       hinge_stiffness: Any, hinge_damping: Any) -> dict[str, Any]:
        """Quantities derived from the parameter values ``v`` (by local name), by the names
        of :attr:`derived`, given ``gravity``, ``hinge_stiffness`` and ``hinge_damping``.

        Values may be floats, NumPy arrays (one entry per Monte Carlo draw) or CasADi
        expressions (for delta-method standard errors), so implementations use arithmetic
        and ``** 0.5`` only. ``gravity`` is the rig's uniform restoring acceleration (m/s^2,
        ``None`` on rigs whose restoring field is not uniform gravity, such as a spinning
        table); ``hinge_stiffness`` (N m/rad) and ``hinge_damping`` (N m s/rad) sum what the
        attachments on this component's hinge add at small amplitude. A quantity whose
        inputs are missing is left out.
        """
        return {}

    def hinge_terms(self, v: Mapping[str, Any]) -> tuple[Any, Any]:
        """Small-amplitude stiffness (N m/rad) and viscous damping (N m s/rad) this element
        adds to its host's hinge, from its parameter values ``v`` by local name."""
        return 0.0, 0.0

    def problems(self) -> list[str]:
        """Problems of this component on its own (bounds, defaults, coordinate units)."""
        out = []
        missing = [c for c in self.coordinates if c not in self.coordinate_units]
        if missing:
            out.append(f"{self.label}: no unit for coordinate(s) {', '.join(missing)}: declare "
                       "`coordinate_units = {" + ", ".join(f'\"{c}\": \"m\"' for c in missing)
                       + "}` (or \"rad\")")
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

        It holds the class, a hash of the source of its MRO and their modules
        (:func:`source_digest`), the name and :meth:`_extra_structure`; parameter values and
        bounds are left out because equations are symbolic in them. Raises
        :class:`SourceUnavailable` when a source cannot be read (then nothing may be cached).
        """
        cls = type(self)
        digest = source_digest(cls)
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

    Parameters
    ----------
    host : str
        Name of the component whose hinge the element attaches to (``"p1"``), passed to
        :class:`Component` as ``name``.
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

    def restoring_gravity(self, v: Mapping[str, Any]) -> Any | None:
        """The uniform gravity (m/s^2) that restores pendulums on this rig, from its
        parameter values ``v`` by local name; ``None`` when the tank frame rotates or
        accelerates so that no single ``g`` sets the slosh frequencies."""
        return None

    def declare(self, k: "Declaration") -> None:
        """Rigs add no generalized coordinates by default through the declaration ``k``
        (the dry mass is added by :meth:`declare_frame`)."""

    def declare_frame(self, f: "FrameDeclaration") -> None:
        """Set the tank frame's motion, the inputs and gravity on ``f``."""
        raise NotImplementedError(f"{type(self).__name__} must implement declare_frame(f)")

