"""What a component sees while it declares itself: frames, its symbols, and ``add_*`` calls.

This module imports SymPy; it is only loaded when a model is derived, never when a derived
model is loaded from the cache.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import sympy as sp
from sympy.physics import mechanics as me

from .errors import InputError

__all__ = ["Namespace", "Declaration", "FrameDeclaration", "PointMass", "Body", "Collected", "Frames", "TIME"]

#: Time (s), the variable of every dynamic symbol (SymPy's ``dynamicsymbols`` time: the same
#: cached symbol).
TIME: sp.Symbol = sp.Symbol("t")


class Namespace(Mapping[str, Any]):
    """Read-only attribute access to symbols by local name: ``k.p.length``, ``k.q["theta"]``."""

    def __init__(self, items: Mapping[str, Any], owner: str) -> None:
        self._items = dict(items)
        self._owner = owner

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._items[name]
        except KeyError:
            raise AttributeError(
                f"{self._owner} has no {name!r}; it has {', '.join(self._items) or 'nothing'}"
            ) from None

    def __getitem__(self, name: str) -> Any:
        return self.__getattr__(name)

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)


@dataclass
class PointMass:
    """A particle of mass ``mass`` (kg) at ``position`` (m) relative to the tank origin."""

    mass: sp.Expr
    position: me.Vector
    owner: str


@dataclass
class Body:
    """A rigid body: mass (kg), centre position (m, from the tank origin), body frame and
    inertia dyadic about the centre (kg m^2)."""

    mass: sp.Expr
    position: me.Vector
    frame: me.ReferenceFrame
    inertia: me.Dyadic
    owner: str


@dataclass
class Collected:
    """What the components of a model declare, gathered for the derivation
    (:mod:`derive`): point masses, rigid bodies, potential energy terms (J), Rayleigh
    dissipation terms (W / 2) and generalized forces ``(force, coordinate)``. A
    :class:`Declaration` appends to it; the derivation reads it."""

    particles: list[PointMass] = field(default_factory=list)
    bodies: list[Body] = field(default_factory=list)
    potential: list[sp.Expr] = field(default_factory=list)
    dissipation: list[sp.Expr] = field(default_factory=list)
    forces: list[tuple[sp.Expr, sp.Expr]] = field(default_factory=list)


class _Base:
    def __init__(self, owner: str, shared: "Frames", collected: Collected) -> None:
        self._owner = owner
        self._shared = shared
        self._collected = collected

    @property
    def t(self) -> sp.Symbol:
        """Time (s)."""
        return TIME

    @property
    def inertial(self) -> me.ReferenceFrame:
        """The inertial frame ``N``."""
        return self._shared.inertial

    @property
    def tank(self) -> me.ReferenceFrame:
        """The tank frame ``T``: z along the tank axis (up under gravity), x the lateral
        excitation direction."""
        return self._shared.tank

    def add_particle(self, mass: sp.Expr, position: me.Vector) -> None:
        """Add a point mass ``mass`` (kg) at ``position`` (m), a vector from the tank
        origin that may use the component's coordinates and parameters."""
        self._collected.particles.append(PointMass(sp.sympify(mass), position, self._owner))

    def add_body(
        self, mass: sp.Expr, position: me.Vector, frame: me.ReferenceFrame, inertia: me.Dyadic
    ) -> None:
        """Add a rigid body with centre at ``position`` (m, from the tank origin), attitude
        ``frame`` (oriented relative to :attr:`tank`) and central ``inertia`` (kg m^2)."""
        self._collected.bodies.append(Body(sp.sympify(mass), position, frame, inertia, self._owner))

    def frame(self, local: str) -> me.ReferenceFrame:
        """A new reference frame named after the component, to orient a body."""
        return me.ReferenceFrame(f"{self._owner}_{local}".replace(".", "_"))


class FrameDeclaration(_Base):
    """What a rig declares: the tank frame's motion, its input signals and gravity."""

    def __init__(self, owner: str, params: Mapping[str, sp.Symbol], shared: "Frames",
                 collected: Collected) -> None:
        super().__init__(owner, shared, collected)
        self.p = Namespace(params, f"rig {owner!r}")

    @property
    def origin_position(self) -> me.Vector:
        """Position of the tank origin ``O`` in the inertial frame (m)."""
        return self._shared.origin_position

    @origin_position.setter
    def origin_position(self, value: me.Vector) -> None:
        self._shared.origin_position = value

    @property
    def gravity(self) -> me.Vector:
        """Gravity (or thrust) acceleration vector (m/s^2)."""
        return self._shared.gravity

    @gravity.setter
    def gravity(self, value: me.Vector) -> None:
        self._shared.gravity = value

    def set_transducer(self, point: me.Vector, frame: me.ReferenceFrame) -> None:
        """Where the transducer measures: its reference ``point`` (m, a vector from the tank
        origin, the point its torques are about) and its axes ``frame`` (oriented from
        :attr:`tank`); the outputs ``force_*`` and ``torque_*`` are then components in
        ``frame``. Without this call they are tank-frame components, torques about ``O``."""
        self._shared.transducer = (point, frame)

    def add_input(self, local: str, unit: str, *, derivatives: int = 2,
                  derivative_of: sp.Function | None = None) -> sp.Function:
        """Declare a prescribed signal (a function of time) that the excitation supplies.

        The signal and its first ``derivatives`` time derivatives (default 2) become model
        inputs called ``"<rig>.<local>"``, ``"<rig>.<local>_dot"`` and
        ``"<rig>.<local>_ddot"``. With ``derivative_of=s`` (``s`` a signal declared with
        ``derivatives=0``), the input ``"<rig>.<local>"`` is the time derivative of ``s``
        (e.g. an angular acceleration given alongside the angular velocity); the returned
        expression is ``s.diff(t)``. Derivation fails if the equations need a derivative of
        a signal that is not an input.
        """
        if derivatives not in (0, 1, 2):
            raise InputError(f"add_input derivatives must be 0, 1 or 2, got {derivatives!r}")
        name = f"{self._owner}.{local}"
        if derivative_of is not None:
            if derivatives:
                raise InputError("add_input(derivative_of=...) declares a single input; "
                                 "pass derivatives=0")
            sym = derivative_of.diff(self.t)
        else:
            sym = me.dynamicsymbols(name)
        self._shared.inputs.append((sym, name, unit, derivatives))
        return sym


class Declaration(_Base):
    """What a component declares: bodies, potential energy, Rayleigh dissipation and
    generalized forces, in terms of its coordinates ``q``/``qd`` and parameters ``p``.

    For attachments (hinge elements), ``host`` gives the host's coordinates and
    ``hinge`` the hinge angles it acts on.
    """

    def __init__(self, owner: str, coordinates: Mapping[str, sp.Function],
                 params: Mapping[str, sp.Symbol], shared: "Frames", collected: Collected,
                 host: "Declaration | None" = None, hinge: tuple[str, ...] = ()) -> None:
        super().__init__(owner, shared, collected)
        t = TIME
        self.q = Namespace(coordinates, f"component {owner!r}")
        self.qd = Namespace({k: v.diff(t) for k, v in coordinates.items()}, f"component {owner!r}")
        self.p = Namespace(params, f"component {owner!r}")
        self.host = host
        self.hinge = tuple(host.q[a] for a in hinge) if host is not None else ()
        self.hinge_rates = tuple(host.qd[a] for a in hinge) if host is not None else ()

    def add_potential(self, energy: sp.Expr) -> None:
        """Add a potential energy term (J): springs, not gravity (gravity is automatic)."""
        self._collected.potential.append(sp.sympify(energy))

    def add_dissipation(self, rayleigh: sp.Expr) -> None:
        """Add a Rayleigh dissipation function term (W/2), e.g. ``c * qd**2 / 2``."""
        self._collected.dissipation.append(sp.sympify(rayleigh))

    def add_force(self, coordinate: sp.Function, force: sp.Expr) -> None:
        """Add a generalized force (N or N m) acting on ``coordinate``."""
        self._collected.forces.append((coordinate, sp.sympify(force)))


@dataclass
class Frames:
    """The frames a model's declarations share: the inertial frame ``N``, the tank frame
    ``T``, the tank origin's position in ``N`` (m), gravity (m/s^2) and the rig's input
    signals ``(symbol, name, unit, order)``; the rig sets them, the components read them."""

    inertial: me.ReferenceFrame
    tank: me.ReferenceFrame
    origin_position: me.Vector
    gravity: me.Vector
    inputs: list[tuple[sp.Expr, str, str, int]] = field(default_factory=list)
    #: ``(reference point, axes)`` of the transducer (:meth:`FrameDeclaration.set_transducer`);
    #: ``None``: the tank origin and the tank axes.
    transducer: tuple[me.Vector, me.ReferenceFrame] | None = None
