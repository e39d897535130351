"""An analog model: a rig plus components, composed with ``+`` and validated as a whole."""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping
from typing import Any

from .component import Attachment, Component, Rig
from .errors import InputError, UnknownNameError
from .parameter import Parameter

__all__ = ["Model", "ModelError"]


class ModelError(InputError):
    """A model declaration with problems; ``problems`` lists every one of them."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = list(problems)
        n = len(self.problems)
        super().__init__(
            f"the model has {n} problem{'s' if n != 1 else ''}:\n  - " + "\n  - ".join(self.problems)
        )


class Model:
    """An immutable assembly of one rig and analog components.

    Build it with ``+``::

        model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")

    Adding returns a new model; the operands are not changed.

    Parameters
    ----------
    components : iterable of Component, default ()
        The rig and components, in order (``+`` builds the same).
    spec : str, optional
        The model specification these components were built from
        (:func:`analogs.spec.model_from_spec` gives it); :meth:`spec` returns it. A model
        made from this one (``+``, :meth:`replace`) reads its specification from its
        components instead.
    """

    def __init__(self, components: Iterable[Component] = (), *, spec: str | None = None) -> None:
        comps = tuple(components)
        for c in comps:
            if not isinstance(c, Component):
                raise TypeError(f"a Model holds components, got {type(c).__name__}: {c!r}")
        self._components = comps
        self._spec = spec

    def spec(self) -> str | None:
        """The model specification (``"fixed,p1:quadratic"``, :mod:`analogs.spec`) that
        builds this model: as given to :func:`analogs.spec.model_from_spec`, else read from
        the components (:func:`analogs.spec.spec_of`); None when a component has no token
        in the grammar.

        Examples
        --------
        >>> from analogs import LateralRig, FixedMass, Pendulum, HingeDamper
        >>> (LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")).spec()
        'fixed,p1:nospring'
        """
        if self._spec is not None:
            return self._spec
        from .spec import spec_of

        return spec_of(self)

    # -- composition -----------------------------------------------------------------------
    def __add__(self, other: "Component | Model") -> "Model":
        if isinstance(other, Model):
            return Model(self._components + other._components)
        if isinstance(other, Component):
            return Model(self._components + (other,))
        return NotImplemented

    def __radd__(self, other: Component) -> "Model":
        if isinstance(other, Component):
            return Model((other,) + self._components)
        return NotImplemented

    def without(self, *names: str) -> "Model":
        """A copy without the components (and their attachments) called ``names``."""
        return Model(c for c in self._components if c.name not in names)

    def replace(self, component: Component) -> "Model":
        """A copy where the component of the same class and name as ``component`` is
        replaced by it."""
        return Model(
            component if (type(c) is type(component) and c.name == component.name) else c
            for c in self._components
        )

    # -- views -----------------------------------------------------------------------------
    @property
    def components(self) -> tuple[Component, ...]:
        """All components in the order they were added."""
        return self._components

    @property
    def rig(self) -> Rig:
        """The model's rig (validated first)."""
        self.validate()
        return next(c for c in self._components if isinstance(c, Rig))

    @property
    def names(self) -> list[str]:
        """Names of the analog components that are neither rig nor attachment."""
        return [
            c.name
            for c in self._components
            if not isinstance(c, (Rig, Attachment))
        ]

    def component(self, name: str) -> Component:
        """The non-attachment component called ``name``."""
        for c in self._components:
            if c.name == name and not isinstance(c, Attachment):
                return c
        raise UnknownNameError(f"the model has no component {name!r}; it has {self.names}")

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """Every parameter of the model, in component order."""
        self.validate()
        return tuple(p for c in self._components for p in c.bound_parameters())

    def parameter(self, name: str) -> Parameter:
        """The parameter with dotted name ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise UnknownNameError(
            f"the model has no parameter {name!r}; its parameters are "
            + ", ".join(p.name for p in self.parameters)
        )

    # -- validation ------------------------------------------------------------------------
    def problems(self) -> list[str]:
        """Every problem of the declaration (empty when the model is valid)."""
        out: list[str] = []
        rigs = [c for c in self._components if isinstance(c, Rig)]
        if not rigs:
            out.append("no rig: add one, e.g. `LateralRig() + ...`")
        elif len(rigs) > 1:
            out.append(f"{len(rigs)} rigs ({', '.join(r.label for r in rigs)}): a model has exactly one")
        hosts: dict[str, Component] = {}
        for c in self._components:
            if isinstance(c, (Attachment, Rig)):
                continue
            if c.name in hosts:
                out.append(f"duplicate component name {c.name!r}: {hosts[c.name].label} and {c.label}")
            else:
                hosts[c.name] = c
        for r in rigs:
            if r.name in hosts:
                out.append(f"component name {r.name!r} is taken by the rig {r.label}")
        for c in self._components:
            if isinstance(c, Attachment):
                host = hosts.get(c.host)
                if host is None:
                    out.append(
                        f"{c.label}: unknown attachment target {c.host!r}; components are "
                        + (", ".join(repr(n) for n in hosts) or "none")
                    )
                elif not host.hinge_angles:
                    out.append(f"{c.label}: {host.label} has no hinge to attach to")
            out.extend(c.problems())
        seen: dict[str, Component] = {}
        for c in self._components:
            for p in c.bound_parameters():
                if p.name in seen:
                    out.append(
                        f"duplicate parameter `{p.name}` declared by {seen[p.name].label} and {c.label}"
                    )
                else:
                    seen[p.name] = c
        return out

    def validate(self) -> "Model":
        """Raise :class:`ModelError` listing every problem, or return the model."""
        problems = self.problems()
        if problems:
            raise ModelError(problems)
        return self

    def explicit_values(self) -> dict[str, float]:
        """Parameter values given explicitly to component constructors (not declared defaults)."""
        return {f"{c.prefix}.{k}": v for c in self._components for k, v in c.given_values.items()}

    def resolve(self, values: Mapping[str, float] | None = None) -> dict[str, float | None]:
        """Parameter values: ``values`` over defaults, checked against names and bounds.

        Raises ``KeyError`` naming unknown parameters and ``ValueError`` for values outside
        bounds. Parameters without value map to ``None``.
        """
        params = {p.name: p for p in self.parameters}
        values = dict(values or {})
        unknown = sorted(set(values) - set(params))
        if unknown:
            raise UnknownNameError(
                f"unknown parameter{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))}; "
                f"the model's parameters are {', '.join(params)}"
            )
        out: dict[str, float | None] = {}
        bad = []
        for name, p in params.items():
            v = values.get(name, p.default)
            if v is not None:
                v = float(v)
                if msg := p.check(v):
                    bad.append(msg)
            out[name] = v
        if bad:
            raise InputError("; ".join(bad))
        return out

    def coordinate_units(self) -> dict[str, str]:
        """SI unit of every generalized coordinate by full name (``"p1.theta": "rad"``)."""
        self.validate()
        return {f"{c.prefix}.{q}": c.coordinate_unit(q)
                for c in self._components if not isinstance(c, Attachment) for q in c.coordinates}

    def derived_quantities(self, values: Mapping[str, Any]) -> dict[str, tuple[Any, str]]:
        """Quantities the components derive from parameter ``values`` (by dotted name):
        ``{"p1.frequency_hz": (value, "Hz"), ...}``.

        Each component declares its own (:meth:`Component.derived_values`); attachments
        contribute their small-amplitude hinge stiffness and damping to their host, and the
        rig says which gravity restores pendulums. Values may be floats, NumPy arrays or
        CasADi expressions; quantities whose inputs are missing (``None``) are left out.
        """
        def local(c: Component) -> dict[str, Any]:
            out = {}
            for k in c.parameters:
                v = values.get(f"{c.prefix}.{k}")
                if v is not None:
                    out[k] = v
            return out

        rig = self.rig
        gravity = rig.restoring_gravity(local(rig))
        hinge: dict[str, list[Any]] = {}
        for c in self._components:
            if isinstance(c, Attachment):
                k, d = c.hinge_terms(local(c))
                acc = hinge.setdefault(c.host, [0.0, 0.0])
                acc[0], acc[1] = acc[0] + k, acc[1] + d
        out: dict[str, tuple[Any, str]] = {}
        for c in self._components:
            if isinstance(c, (Attachment, Rig)) or not c.derived:
                continue
            k, d = hinge.get(c.name, (0.0, 0.0))
            for name, value in c.derived_values(local(c), gravity=gravity, hinge_stiffness=k,
                                                hinge_damping=d).items():
                out[f"{c.prefix}.{name}"] = (value, c.derived[name])
        return out

    def structure_key(self) -> str:
        """Hash of the declaration: equal for models that derive to the same equations.

        Raises :class:`analogs.component.SourceUnavailable` when a component's source cannot
        be read (such a model is derived without the cache)."""
        text = "|".join(c.structure() for c in self._components)
        return hashlib.sha256(text.encode()).hexdigest()

    def __repr__(self) -> str:
        return " + ".join(repr(c) for c in self._components) or "Model()"

