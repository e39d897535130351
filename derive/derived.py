"""A derived model: CasADi functions plus the names, units and parameter metadata."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from analogs.errors import InputError, UnknownNameError
from analogs.model import Model
from analogs.parameter import Parameter

__all__ = ["DerivedModel", "ParameterError", "OUTPUT_NAMES", "OUTPUT_UNITS"]

#: The outputs of every derived model, in order: the transducer's force and torque about
#: the tank origin in tank-frame components, then kinetic and potential energy.
OUTPUT_NAMES = (
    "force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z",
    "kinetic_energy", "potential_energy",
)
#: SI unit of each of :data:`OUTPUT_NAMES`.
OUTPUT_UNITS = ("N", "N", "N", "N m", "N m", "N m", "J", "J")


#: Maps kept per derived structure (:meth:`DerivedModel.mapped`): a fit makes five or six,
#: so a process fitting records of several lengths keeps the latest few lengths' maps.
_MAPS_KEPT = 32


class ParameterError(InputError):
    """Parameter values that are unknown to the model, missing, or out of bounds."""


@dataclass(frozen=True)
class DerivedModel:
    """Equations of motion and outputs of a model as CasADi functions.

    States are ``x = [q; qd]`` (coordinates, then their rates). Functions take
    ``(x, u, p, t)``: states, inputs, parameters in :attr:`parameter_names` order, time (s).

    - ``rhs`` -> ``xdot``; the mass matrix is solved numerically inside.
    - ``outputs`` -> ``y`` in :data:`OUTPUT_NAMES` order: the force (N) and torque about
      the tank origin (N m) that the transducer applies to the tank assembly, in tank-frame
      components (for a rigid tank, force = total mass x (acceleration - gravity)), then
      kinetic and potential energy (J); a rig that places its transducer
      (:class:`analogs.MotionRig`) gives them in the transducer's axes, torques about its
      reference point.
    - ``mass_matrix`` -> ``M(q, p)`` and ``forcing`` -> ``f(x, u, p, t)`` of
      ``M qdd = f``, kept apart (no symbolic inverse).

    Attributes
    ----------
    model : analogs.Model
        The declared model.
    coordinates : tuple of str
        The generalized coordinates (``"p1.theta"``); the states are these then their rates.
    inputs, input_units : tuple of str
        The rig's input signals and their SI units.
    parameter_names : tuple of str
        The parameters in the order of ``p``.
    measured : tuple of str
        The outputs the rig's transducer measures.
    dependencies : mapping
        Per output, the parameters it depends on.
    from_cache : bool
        Whether the functions were loaded from the disk cache.
    _memo : dict
        Functions built from these (maps, steps), kept with them (:meth:`memo`).
    """

    model: Model
    coordinates: tuple[str, ...]
    inputs: tuple[str, ...]
    input_units: tuple[str, ...]
    parameter_names: tuple[str, ...]
    measured: tuple[str, ...]
    rhs: ca.Function
    outputs: ca.Function
    mass_matrix: ca.Function
    forcing: ca.Function
    dependencies: Mapping[str, tuple[str, ...]]
    from_cache: bool = field(default=False, compare=False)
    _memo: dict = field(default_factory=dict, compare=False, repr=False)

    def memo(self, key: tuple, build: Callable[[], Any]) -> Any:
        """``build()``, called once per ``key`` and kept with the model's functions (shared
        by every derive of the same structure in this thread).

        Parameters
        ----------
        key : tuple
            What the built object depends on besides the model (its kind first, e.g.
            ``("rk4_step", substeps)``).
        build : callable
            Makes the object (a CasADi function, a table) when ``key`` is new.

        Examples
        --------
        >>> step = dm.memo(("rk4_step", 2), lambda: make_step(dm, 2))  # doctest: +SKIP
        """
        if key not in self._memo:
            self._memo[key] = build()
        return self._memo[key]

    #: The former name of :meth:`memo`.
    memoized = memo

    def mapped(self, key: tuple, fn: ca.Function, n: int) -> ca.Function:
        """``fn.map(n)`` (``n`` parallel evaluations), kept with the model's functions
        under ``key`` (which must name ``fn``): CasADi builds a map's sparsity patterns when
        it is created, milliseconds for a long record, and a fit creates several."""
        k = ("map", key, n)
        if k not in self._memo:
            maps = [m for m in self._memo if m[0] == "map"]
            if len(maps) >= _MAPS_KEPT:  # many record lengths in one process: oldest out
                del self._memo[maps[0]]
        return self.memo(k, lambda: fn.map(n))

    @property
    def states(self) -> tuple[str, ...]:
        """State names: coordinates then ``<coordinate>_dot``."""
        return self.coordinates + tuple(f"{c}_dot" for c in self.coordinates)

    @cached_property
    def state_units(self) -> tuple[str, ...]:
        """SI units of the states, as the components declare them (``rad``, ``m``, then
        ``rad/s``, ``m/s``)."""
        units = self.model.coordinate_units()
        base = tuple(units[c] for c in self.coordinates)
        return base + tuple(f"{u}/s" for u in base)

    @property
    def nx(self) -> int:
        return 2 * len(self.coordinates)

    @property
    def nu(self) -> int:
        return len(self.inputs)

    @property
    def output_names(self) -> tuple[str, ...]:
        return OUTPUT_NAMES

    @cached_property
    def parameters(self) -> tuple[Parameter, ...]:
        """Parameter metadata (unit, default, bounds) from the model declaration."""
        by_name = {p.name: p for p in self.model.parameters}
        return tuple(by_name[n] for n in self.parameter_names)

    def needed_parameters(self, outputs: tuple[str, ...] | None = None) -> tuple[str, ...]:
        """Parameters that the equations of motion and ``outputs`` (default: the measured
        channels) depend on."""
        outputs = self.measured if outputs is None else outputs
        need = set(self.dependencies["eom"])
        for o in outputs:
            need |= set(self.dependencies[o])
        return tuple(n for n in self.parameter_names if n in need)

    def parameter_vector(self, values: Mapping[str, float] | None = None, *,
                         outputs: tuple[str, ...] | None = None) -> np.ndarray:
        """Parameter values in model order: ``values`` over the declared defaults.

        Parameters that nothing computed depends on may stay without a value (NaN).

        Raises
        ------
        ParameterError
            Naming unknown parameters, values outside bounds, and parameters needed by the
            equations of motion or ``outputs`` that have no value.
        """
        values = dict(values or {})
        known = {p.name: p for p in self.parameters}
        problems = []
        unknown = sorted(set(values) - set(known))
        if unknown:
            problems.append(
                f"unknown parameter{'s' if len(unknown) > 1 else ''} "
                f"{', '.join(f'`{u}`' for u in unknown)}; the model's parameters are "
                + ", ".join(known)
            )
        vec = np.full(len(self.parameter_names), np.nan)
        for i, name in enumerate(self.parameter_names):
            p = known[name]
            v = values.get(name, p.default)
            if v is None:
                continue
            try:
                v = float(v)
            except (TypeError, ValueError):
                problems.append(f"parameter `{name}` must be a number, got {v!r}")
                continue
            if msg := p.check(v):
                problems.append(msg)
            vec[i] = v
        missing = [n for n in self.needed_parameters(outputs)
                   if math.isnan(vec[self.parameter_names.index(n)])]
        for n in missing:
            problems.append(f"missing parameter `{n}` ({known[n].unit}): {known[n].description}")
        if problems:
            raise ParameterError("; ".join(problems))
        return vec

    def output_index(self, name: str) -> int:
        """Position of the output ``name`` (``"force_x"``) in :data:`OUTPUT_NAMES`."""
        try:
            return OUTPUT_NAMES.index(name)
        except ValueError:
            raise UnknownNameError(f"no output {name!r}; outputs are {', '.join(OUTPUT_NAMES)}") from None
