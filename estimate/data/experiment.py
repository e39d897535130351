"""A test case ready to simulate: its model, derived equations and excitation."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from analogs import Model
from analogs.errors import InputError
from derive import DerivedModel, Excitation, Sampled, Simulation, derive, simulate

from .case import Case
from .models import rig_values
from .signals import displacement_derivatives

__all__ = ["Experiment", "experiment"]


@dataclass(frozen=True)
class Experiment:
    """A case with its derived model and the excitation taken from its data: ``case``, its
    ``model`` and that model ``derived``.

    ``fixed`` holds the parameter values the case file sets (dry mass, gravity, crank).
    ``make_excitation`` builds :attr:`excitation` when it is first asked for (a fit that
    estimates the carriage motion never needs the filtered one).
    """

    case: Case
    model: Model
    derived: DerivedModel
    make_excitation: Callable[[], Excitation | None] = field(repr=False)
    fixed: Mapping[str, float]

    @cached_property
    def excitation(self) -> Excitation | None:
        """The rig's inputs from the case's data, ``None`` when the model takes none from
        it (a crank drive, a spinning rig at constant rates)."""
        return self.make_excitation()

    def with_excitation(self, excitation: Excitation | None) -> "Experiment":
        """This experiment driven by ``excitation`` instead (e.g. an exact carriage motion)."""
        return replace(self, make_excitation=lambda: excitation)

    def simulate(self, params: Mapping[str, float], *, x0: Mapping[str, float] | None = None,
                 **options) -> Simulation:
        """Simulate on the case's time grid; ``params`` over the case's rig values, from the
        case's initial state (:meth:`initial_state`) unless ``x0`` gives it; ``options``
        are those of :func:`derive.simulate` (``integrator``, ...)."""
        values = {**self.fixed, **params}
        if x0 is None:
            x0 = self.initial_state(values)
        return simulate(self.derived, values, self.case.time, self.excitation, x0=x0, **options)

    @property
    def initial_state_kind(self) -> str:
        """``[test] initial_state`` of the case (``"rest"`` when absent)."""
        return self.case.test.initial_state or "rest"

    def initial_state(self, params: Mapping[str, float]) -> dict[str, float] | None:
        """The state at the first sample for parameter values ``params``: ``None`` (rest)
        for ``"rest"``; for ``"steady"`` the relative equilibrium of the analog under the rig
        motion at the first sample (:func:`derive.equilibrium.relative_equilibrium`).
        ``"free"`` states are estimated by a fit, not known here: raises."""
        kind = self.initial_state_kind
        if kind == "rest":
            return None
        if kind == "free":
            raise InputError(f"{self.case.path}: [test] initial_state = \"free\" is estimated "
                             "with the parameters; give the fitted initial state (a fit "
                             "result's `initial_states`) to simulate this case")
        from derive.equilibrium import relative_equilibrium

        dm = self.derived
        t = np.asarray(self.case.time[:2], float)
        u = (self.excitation.values(t) if self.excitation is not None and dm.nu
             else np.zeros((dm.nu, 2)))
        x = relative_equilibrium(dm, dm.parameter_vector({**self.fixed, **params}), t, u)
        return dict(zip(dm.states, map(float, x)))

    @property
    def measured(self) -> np.ndarray:
        """The measured force (N) of a lateral case; for several channels see
        :attr:`channels`."""
        return self.case.force

    @property
    def channels(self) -> tuple[str, ...]:
        """The model outputs the case measures (in the model's order)."""
        have = self.case.channels
        return tuple(c for c in self.derived.measured if c in have)


def experiment(case: Case, model: Model) -> Experiment:
    """Derive ``model`` and build the excitation of ``case``.

    A measured displacement becomes a zero-phase smoothed displacement, velocity and
    acceleration (:func:`estimate.data.signals.displacement_derivatives`) interpolated by
    cubic B-splines, and so does each measured axis of a six-axis record
    (:func:`estimate.data.motion.motion_excitation`); a spinning rig spun up or coned in
    drives its input signals from the measured rig angles or schedules
    (:func:`estimate.data.spin.spin_excitation`); a crank drive and a spinning rig at
    constant rates (explicit functions of time) need none.
    """
    dm = derive(model)
    if getattr(case, "motion", None) is not None:  # six-axis: every measured axis filtered alike
        from .motion import motion_excitation

        def exc() -> Excitation | None:
            return motion_excitation(case)
    elif case.test.rig == "lateral" and case.test.excitation == "measured":
        if case.displacement is None:
            raise InputError(f"{case.path}: excitation = 'measured' needs a displacement column")

        def exc() -> Excitation | None:
            x, xd, xdd = displacement_derivatives(case.time, case.displacement,
                                                  motion_band_hz=case.test.motion_band_hz)
            return Sampled(case.time, np.vstack([x, xd, xdd]))
    elif case.spin is not None and case.spin.motion == "input":
        from .spin import spin_excitation

        spin = spin_excitation(case)  # built now: its errors belong to loading the case

        def exc() -> Excitation | None:
            return spin
    else:
        def exc() -> Excitation | None:
            return None
    return Experiment(case, model, dm, exc, rig_values(case))
