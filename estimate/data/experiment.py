"""A test case ready to simulate: its model, derived equations and excitation."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

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
    """A case with its derived model and the excitation taken from its data.

    ``fixed`` holds the parameter values the case file sets (dry mass, gravity, crank).
    """

    case: Case
    model: Model
    derived: DerivedModel
    excitation: Excitation | None
    fixed: Mapping[str, float]

    def simulate(self, params: Mapping[str, float], **options) -> Simulation:
        """Simulate on the case's time grid; ``params`` over the case's rig values."""
        values = {**self.fixed, **params}
        return simulate(self.derived, values, self.case.time, self.excitation, **options)

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
    cubic B-splines; a crank drive and the spinning rig (whose motion is an explicit function
    of time) need no input signal.
    """
    dm = derive(model)
    if case.test.rig == "lateral" and case.test.excitation == "measured":
        if case.displacement is None:
            raise InputError(f"{case.path}: excitation = 'measured' needs a displacement column")
        x, xd, xdd = displacement_derivatives(case.time, case.displacement)
        exc: Excitation | None = Sampled(case.time, np.vstack([x, xd, xdd]))
    else:
        exc = None
    return Experiment(case, model, dm, exc, rig_values(case))
