"""The estimation problem: cases, model, which parameters are estimated (shared or per
case), their initial values, bounds and scales. Built once (:meth:`FitProblem.build`, whose
named steps are in :mod:`estimate.fitting.build`), never mutated."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from analogs import Model
from analogs.errors import InputError, UnknownNameError

from ..data.case import Case
from ..data.experiment import Experiment
from .budget import LinearBound, Tie
from .carriage import CarriageInput, RecordNoise
from .input_noise import DISPLACEMENT_FLOOR
from .starts import LAG_MIN, LAG_MODES
from .strategies import (
    DEFAULT_INPUT,
    FILTERED_FORCE_CUTOFF_HZ,
    INPUT_MODES,
    InputMode,
    StartPolicy,
)

__all__ = ["FitProblem", "Estimated", "PER_CASE", "INPUT_MODES", "DISPLACEMENT_FLOOR", "LAG_MIN",
           "LAG_MODES", "FILTERED_FORCE_CUTOFF_HZ"]

#: Rig parameters estimated separately for every case (crank phase and speed).
PER_CASE = ("rig.omega_correction", "rig.flywheel_angle")


@dataclass(frozen=True)
class Estimated:
    """One estimated parameter: ``name`` (with ``"<case id>:"`` prefix for per-case ones),
    the model parameter it sets, its case index (``None`` when shared), unit, initial
    value, bounds and scale.

    ``band``: the bounds are a plausibility band around a prediction (a pendulum length's
    +/-20 %), not limits of the physics. A physical bound can be the truth (no hinge
    spring without a diaphragm), so an estimate on it is held there in the covariance; an
    estimate on a band's edge is not, or the others' intervals would be conditional on a
    value nothing supports (a spring that took up the frequency a length pinned at the
    band left: 0.202 +/- 0.002 N m/rad for a true 0)."""

    name: str
    parameter: str
    case: int | None
    unit: str
    initial: float
    lower: float
    upper: float
    scale: float
    band: bool = False


@dataclass(frozen=True)
class FitProblem:
    """Cases and a model with the parameters to estimate.

    Use :meth:`build`. ``fixed[i]`` are the values case ``i`` fixes (rig values, and
    parameters the user holds), ``estimated`` the decision parameters.
    """

    model: Model
    experiments: tuple[Experiment, ...]
    estimated: tuple[Estimated, ...]
    fixed: tuple[Mapping[str, float], ...]
    notes: tuple[str, ...] = field(default=())
    #: Per-case sample weights (``None``: all 1); 0 leaves a sample out of the cost.
    weights: tuple[np.ndarray | None, ...] = field(default=(), repr=False)
    #: Measurement models (friction, sensor delay) applied to every case.
    measurement: tuple = field(default=())
    #: Residual scale of a channel by output name, over the default (see :meth:`channel_scales`).
    channel_weights: Mapping[str, float] = field(default_factory=dict)
    #: How a measured carriage displacement enters (:mod:`estimate.fitting.strategies`).
    input_mode: InputMode = DEFAULT_INPUT
    #: Per case, the estimated carriage motion's spline and noise levels (``None``: the
    #: case's excitation is used as given: filtered measurement, crank or spinning rig).
    carriage: tuple[CarriageInput | None, ...] = field(default=(), repr=False)
    #: Per case, the force as the estimated-input mode fits it (tones above the mechanics
    #: removed) and its noise level, which divides the residuals (``None``: the force as
    #: recorded, residuals divided by the default channel scales).
    noise: tuple[RecordNoise | None, ...] = field(default=(), repr=False)
    #: Model parameters that follow the estimates (:class:`~estimate.fitting.budget.Tie`):
    #: the fixed liquid of a tank whose container is not weighed.
    ties: tuple[Tie, ...] = ()
    #: Linear bounds over the estimates: the masses within the liquid
    #: (:mod:`estimate.fitting.budget`).
    linear_bounds: tuple[LinearBound, ...] = ()
    #: The first stage that started the fit (:class:`~estimate.fitting.first_stage.FirstStage`),
    #: or ``None``.
    first_stage: object = field(default=None, repr=False)
    #: The ranges of the estimated model parameters that keep the analog inside its tank
    #: (:func:`~estimate.fitting.budget.tank_ranges`), by parameter name: checked after the
    #: fit (:attr:`FitResult.outside_tank`), not bounds of the NLP.
    tank_ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    #: The starts the first stage replaced, as the prediction gave them (by label): a second
    #: start when the first stage's masses are far from them (:func:`~estimate.fitting.nlp.fit`).
    prediction_start: Mapping[str, float] = field(default_factory=dict, repr=False)
    #: Per case, the samples left out because they are no measurements (clipped, spikes:
    #: :mod:`estimate.data.bad_samples`; weight 0), as opposed to held out (``None``: none).
    left_out: tuple[np.ndarray | None, ...] = field(default=(), repr=False)

    def held_out(self, case: int, weights: np.ndarray | None = None) -> np.ndarray:
        """The samples of case ``case`` with weight 0 (in ``weights``, default the
        problem's) that were not :attr:`left_out`: held out of the cost (a diagnosis's
        blocks, a six-axis record's filter ends)."""
        n = self.experiments[case].case.time.size
        if weights is None and self.weights:
            weights = self.weights[case]
        held = np.zeros(n, bool) if weights is None else np.asarray(weights) == 0
        bad = self.left_out[case] if self.left_out else None
        if bad is None:
            return held
        from ..data.bad_samples import runs

        out = held & ~bad
        # a left-out run inside a held-out block (held samples on both sides) is the block's
        for s, e in zip(*runs(bad & held)):
            if s > 0 and e < n and out[s - 1] and out[e]:
                out[s:e] = True
        return out

    @classmethod
    def build(cls, cases: Case | Sequence[Case], model: Model, *,
              estimate: Sequence[str] | None = None,
              hold: Mapping[str, float] | None = None,
              initial: Mapping[str, float] | None = None,
              bounds: Mapping[str, tuple[float, float]] | None = None,
              force_cutoff_hz: float | None | str = "auto",
              measurement: Sequence = (),
              weights: Sequence[np.ndarray | None] | None = None,
              channel_weights: Mapping[str, float] | None = None,
              input: InputMode | str | None = None, lag: str = "auto",
              first_stage: bool = True, start: StartPolicy | None = None) -> "FitProblem":
        """Set up the estimation of ``model`` on ``cases``.

        Parameters
        ----------
        cases : Case or sequence of Case
            Test cases; physical parameters are shared, crank phase and speed corrections
            (:data:`PER_CASE`) are estimated per case.
        model : analogs.Model
            The analog model (its rig must match the cases' excitation).
        estimate : sequence of str, optional
            Parameters to estimate. Default: every parameter the equations of motion and
            the measured force depend on, except the rig values the case file fixes.
        hold : mapping, optional
            Values of parameters held fixed (not estimated).
        initial : mapping, optional
            Initial values over the prediction (``[prediction]`` or tank modal analysis).
        bounds : mapping, optional
            Bounds over the defaults (physical bounds; pendulum lengths +/-20 % of the
            prediction).
        force_cutoff_hz : float or None, default "auto"
            Zero-phase low-pass of the measured force before fitting [Hz]. ``"auto"``: the
            input mode's (none with the estimated input: the residuals stay white, so the
            covariance holds; 10 Hz with ``"filtered"``, the seed's workflow); a number or
            None sets a filtered input's (``FilteredInput(cutoff_hz=...)`` says the same).
        measurement : sequence of MeasurementModel
            Friction or sensor delay between the analog and the recording; their
            parameters are estimated with the others.
        weights : sequence of arrays, optional
            Per-case sample weights (0 leaves samples out, e.g. held-out segments).
        channel_weights : mapping of str to float, optional
            Residual scale per measured channel (``"torque_y": 0.05`` in N m): each
            channel's residual is divided by it. Default: 1 when a case measures one
            channel (the lateral force, cost in N^2), else the RMS of the measured channel,
            so that forces (N) and torques (N m) weigh alike. A smaller scale weighs a
            channel more.
        input : InputMode, {"estimated", "filtered"} or None
            How a measured carriage displacement enters (lateral rig;
            :mod:`estimate.fitting.strategies`; None: :data:`~estimate.fitting.strategies.DEFAULT_INPUT`,
            ``EstimatedInput()``): estimated with the
            parameters, its residual weighted by the displacement noise and the force
            residual by the force noise, both read from the spectra
            (:mod:`estimate.fitting.carriage`); or smoothed and differentiated beforehand
            (:func:`estimate.data.signals.displacement_derivatives`) and treated as exact.
        lag : {"auto", "estimate", "none"}, default "auto"
            A constant lag of the force stream behind the motion stream
            (:class:`~estimate.fitting.measurement.StreamLag`, ``<case>:rig.lag`` in s),
            estimated with the estimated input: ``"auto"`` where the first stage
            determines it (:data:`~estimate.fitting.first_stage.LAG_IDENTIFIED`) at
            :data:`LAG_MIN` or more (else its profile's value and standard error are in
            the notes), ``"estimate"`` always, ``"none"`` never.
        first_stage : bool, default True
            Start the first slosh mode, the rigid mass and the lag from a linear
            identification of the records (:mod:`estimate.fitting.first_stage`) rather
            than from the tank prediction (lateral measured cases); the former spelling of
            ``start`` (True: ``FirstStageStart()``, False: ``PredictionStart()``).
        start : StartPolicy, optional
            Where the estimates start (:mod:`estimate.fitting.strategies`); overrides
            ``first_stage``. Default: :data:`~estimate.fitting.strategies.DEFAULT_START`
            (``FirstStageStart()``).

        Examples
        --------
        >>> prob = FitProblem.build(case, model, channel_weights={"torque_z": 0.01})  # doctest: +SKIP
        """
        from .build import build_problem

        return build_problem(cls, cases, model, estimate=estimate, hold=hold, initial=initial,
                             bounds=bounds, force_cutoff_hz=force_cutoff_hz,
                             measurement=measurement, weights=weights,
                             channel_weights=channel_weights, input=input, lag=lag,
                             start=start if start is not None else first_stage)

    @property
    def input(self) -> str:
        """The input mode's name, ``"estimated"`` or ``"filtered"`` (:data:`INPUT_MODES`)."""
        return self.input_mode.name

    @property
    def force_cutoff_hz(self) -> float | None:
        """Zero-phase low-pass of the measured force before fitting [Hz] (None: none), as
        the input mode sets it."""
        return self.input_mode.force_cutoff_hz

    def channels(self, i: int) -> tuple[str, ...]:
        """Output names fitted for case ``i``: the model's measured outputs the case has."""
        return self.experiments[i].channels

    def channel_scales(self, i: int) -> dict[str, float]:
        """Divisor of each fitted channel's residual in the cost of case ``i`` (see
        ``channel_weights`` of :meth:`build`): the user's weight; else, with the estimated
        input, the force noise (so force and displacement residuals are in units of their
        noise); else :meth:`report_scale`."""
        out = {}
        for c in self.channels(i):
            if c in self.channel_weights:
                out[c] = float(self.channel_weights[c])
            elif self.noise and self.noise[i] is not None:
                out[c] = float(self.noise[i].force_noise)
            else:
                out[c] = self.report_scale(i, c)
        return out

    def report_scale(self, i: int, channel: str) -> float:
        """Scale of a channel's residual in reports: 1 (N) when case ``i`` measures one
        channel, else the RMS of the raw measured channel (forces and torques alike), or
        the user's ``channel_weights``."""
        if channel in self.channel_weights:
            return float(self.channel_weights[channel])
        if len(self.channels(i)) == 1:
            return 1.0
        y = np.asarray(self.experiments[i].case.channels[channel], float)
        return float(np.sqrt(np.mean(y**2))) or 1.0

    @property
    def names(self) -> tuple[str, ...]:
        """Labels of the estimated parameters, in decision-vector order."""
        return tuple(e.name for e in self.estimated)

    def case_values(self, i: int, theta: np.ndarray, *, model_only: bool = True) -> dict[str, float]:
        """Parameter values of case ``i`` for estimates ``theta`` (unscaled): the model's
        (default) or also the measurement models' parameters."""
        vals = dict(self.fixed[i])
        for e, v in zip(self.estimated, theta):
            if e.case is None or e.case == i:
                vals[e.parameter] = float(v)
        if self.ties:
            by_label = {e.name: float(v) for e, v in zip(self.estimated, theta)}
            vals |= {t.parameter: t.value(by_label) for t in self.ties}
        if model_only:
            known = set(self.experiments[i].derived.parameter_names)
            vals = {k: v for k, v in vals.items() if k in known}
        return vals

    def with_displacement_noise(self, levels: Sequence[float | None]) -> "FitProblem":
        """A copy whose estimated carriage motions weigh their displacement residuals by
        other noise levels [m] (``None``: unchanged)."""
        carriage = tuple(ci if ci is None or lv is None else replace(ci, displacement_noise=lv)
                         for ci, lv in zip(self.carriage, levels))
        return replace(self, carriage=carriage)

    def with_initial(self, values: Mapping[str, float]) -> "FitProblem":
        """A copy with other initial values for some estimated parameters (by label)."""
        est = tuple(
            replace(e, initial=min(max(float(values.get(e.name, e.initial)), e.lower), e.upper))
            for e in self.estimated)
        return replace(self, estimated=est)

    def holding(self, label: str, value: float) -> "FitProblem":
        """A copy in which the shared estimate ``label`` is held at ``value``."""
        hit = [e for e in self.estimated if e.name == label]
        if not hit or hit[0].case is not None:
            raise UnknownNameError(f"{label!r} is not a shared estimated parameter; estimated: "
                           + ", ".join(self.names))
        est = tuple(e for e in self.estimated if e.name != label)
        fixed = tuple({**f, hit[0].parameter: float(value)} for f in self.fixed)
        return replace(self, estimated=est, fixed=fixed,
                       ties=tuple(_held_tie(t, label, value) for t in self.ties),
                       linear_bounds=tuple(b for b in (_held_bound(b, label, value)
                                                       for b in self.linear_bounds) if b))

    @property
    def initial(self) -> np.ndarray:
        return np.array([e.initial for e in self.estimated])

    def check(self) -> None:
        """Raise if an initial value is not finite, or when the fit needs more memory than
        the budget (:func:`estimate.data.budget.check_fit`: by its cases' samples and
        measured channels)."""
        from ..data.budget import check_fit

        bad = [e.name for e in self.estimated if not math.isfinite(e.initial)]
        if bad:
            raise InputError(f"initial values are not finite: {', '.join(bad)}")
        check_fit([(x.case.path.name, int(x.case.time.size), len(self.channels(i)))
                   for i, x in enumerate(self.experiments)])


def _held_tie(tie: Tie, label: str, value: float) -> Tie:
    """``tie`` with the estimate ``label`` held at ``value`` (a constant)."""
    c = dict(tie.terms).get(label)
    if c is None:
        return tie
    return replace(tie, constant=tie.constant + c * value,
                   terms=tuple((n, k) for n, k in tie.terms if n != label))


def _held_bound(bound: LinearBound, label: str, value: float) -> LinearBound | None:
    """``bound`` with the estimate ``label`` held at ``value``; ``None`` when nothing
    estimated is left in it."""
    c = dict(bound.terms).get(label)
    if c is None:
        return bound
    terms = tuple((n, k) for n, k in bound.terms if n != label)
    return replace(bound, terms=terms, upper=bound.upper - c * value) if terms else None
