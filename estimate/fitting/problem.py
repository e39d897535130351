"""The estimation problem: cases, model, which parameters are estimated (shared or per
case), their initial values, bounds and scales. Built once, never mutated."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from analogs import Model
from analogs.errors import InputError, UnknownNameError

from ..data.case import Case
from ..data.experiment import Experiment, experiment
from ..data.models import model_for_case
from ..data.records import refuse_repeated
from .budget import LinearBound, Tie, liquid_budget, tank_ranges
from .carriage import CarriageInput, RecordNoise, carriage_input, record_noise
from .free_decay import rest_holds
from .initial import length_bounds, nominal_scale, predicted_sources, source_notes

__all__ = ["FitProblem", "Estimated", "PER_CASE", "INPUT_MODES"]

#: How a measured carriage displacement enters the fit: ``"estimated"`` (the carriage motion
#: is estimated with the parameters, :mod:`estimate.fitting.carriage`) or ``"filtered"``
#: (zero-phase smoothed and differentiated beforehand, then treated as exact).
INPUT_MODES = ("estimated", "filtered")
#: Force low-pass of the filtered-input mode [Hz] (the seed's workflow).
FILTERED_FORCE_CUTOFF_HZ = 10.0

#: Floor of the displacement noise [m]: no lab measurement of a carriage's travel is known
#: to better than a micrometre, and a planned path (the command, smooth to 1e-7 m above
#: the band) is no measurement of the motion at all; its error (servo lag and ripple) shows
#: only in the fit (:mod:`estimate.fitting.balance` rescales it then).
DISPLACEMENT_FLOOR = 1e-6

#: ``lag="auto"`` estimates a stream lag only where the first stage finds one of at least
#: this much [s]: a record without one keeps the parameters it always had (a lag the NLP
#: is free to move otherwise bends around what the model lacks; a sample at 500 Hz).
LAG_MIN = 0.002

#: How a stream lag between motion and force is treated (see :meth:`FitProblem.build`).
LAG_MODES = ("auto", "estimate", "none")

#: Rig parameters estimated separately for every case (crank phase and speed).
PER_CASE = ("rig.omega_correction", "rig.flywheel_angle")


@dataclass(frozen=True)
class Estimated:
    """One estimated parameter: ``name`` (with ``"<case id>:"`` prefix for per-case ones),
    the model parameter it sets, its case index (``None`` when shared), unit, initial
    value, bounds and scale."""

    name: str
    parameter: str
    case: int | None
    unit: str
    initial: float
    lower: float
    upper: float
    scale: float


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
    force_cutoff_hz: float | None = FILTERED_FORCE_CUTOFF_HZ
    notes: tuple[str, ...] = field(default=())
    #: Per-case sample weights (``None``: all 1); 0 leaves a sample out of the cost.
    weights: tuple[np.ndarray | None, ...] = field(default=(), repr=False)
    #: Measurement models (friction, sensor delay) applied to every case.
    measurement: tuple = field(default=())
    #: Residual scale of a channel by output name, over the default (see :meth:`channel_scales`).
    channel_weights: Mapping[str, float] = field(default_factory=dict)
    #: ``"estimated"`` or ``"filtered"`` (:data:`INPUT_MODES`).
    input: str = "filtered"
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
              input: str = "estimated", lag: str = "auto",
              first_stage: bool = True) -> "FitProblem":
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
            Zero-phase low-pass of the measured force before fitting [Hz]. ``"auto"``: none
            with the estimated input (the residuals stay white, so the covariance holds),
            10 Hz with the filtered input (the seed's workflow).
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
        input : {"estimated", "filtered"}, default "estimated"
            How a measured carriage displacement enters (lateral rig): estimated with the
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
            than from the tank prediction (lateral measured cases).

        Examples
        --------
        >>> prob = FitProblem.build(case, model, channel_weights={"torque_z": 0.01})  # doctest: +SKIP
        """
        cases = (cases,) if isinstance(cases, Case) else tuple(cases)
        if not cases:
            raise InputError("no cases to fit")
        refuse_repeated(cases)
        if input not in INPUT_MODES:
            raise InputError(f"input must be one of {', '.join(map(repr, INPUT_MODES))}, "
                             f"got {input!r}")
        six_axis = all(c.motion is not None for c in cases)
        if force_cutoff_hz == "auto":
            # six-axis records: the channels unfiltered (a 10 Hz filter cut the harmonics
            # of 0.6 rad swings and biased the masses by 1.7 %; see estimate.data.motion)
            force_cutoff_hz = None if input == "estimated" or six_axis else \
                FILTERED_FORCE_CUTOFF_HZ
        cw = dict(channel_weights or {})
        bad = {k: v for k, v in cw.items()
               if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0
               or not math.isfinite(v)}
        if bad:
            raise InputError("channel_weights: expected positive finite scales (N or N m), found "
                             + ", ".join(f"`{k}` = {v!r}" for k, v in bad.items()))
        model = model.validate()
        hold, initial_user, bounds_user = dict(hold or {}), dict(initial or {}), dict(bounds or {})
        # each case on its own rig (a measured and a crank case share the physical parameters)
        exps = tuple(experiment(c, model_for_case(model, c)) for c in cases)
        measurement = _resolve_channels(tuple(measurement), exps)
        w = tuple(weights) if weights is not None else tuple(None for _ in exps)
        if weights is None:  # six-axis records: the force filter's ends left out
            from ..data.motion import edge_weights

            w = tuple(edge_weights(e.case, force_cutoff_hz) for e in exps)
        if len(w) != len(exps):
            raise InputError(f"weights: expected one entry per case ({len(exps)}), got {len(w)}")
        if lag not in LAG_MODES:
            raise InputError(f"lag must be one of {', '.join(map(repr, LAG_MODES))}, got {lag!r}")
        carriage, noise = _input_estimation(exps, input, force_cutoff_hz)
        stage = _first_stage(cases, model, exps, carriage, noise, w) if first_stage else None
        stage_note = None
        if stage is not None and stage.failure is not None:
            stage_note = f"first stage not used: {stage.failure}; starting from the prediction"
            stage = None
        measurement, lag_note = _with_lag(measurement, lag, stage, carriage, exps)
        per_case_names = {n for mm in measurement if mm.per_case for n in mm.parameters}
        params = {p.name: p for e in exps for p in e.derived.parameters}
        for mm in measurement:
            params |= {n: _as_parameter(n, spec) for n, spec in mm.parameters.items()}
        unknown = sorted((set(hold) | set(initial_user) | set(bounds_user) | set(estimate or ()))
                         - set(params))
        if unknown:
            raise UnknownNameError(f"unknown parameter{'s' if len(unknown) > 1 else ''} "
                           f"{', '.join(f'`{u}`' for u in unknown)}; the model's parameters are "
                           + ", ".join(params))
        rig_fixed = set().union(*(e.fixed for e in exps))
        # what the equations and the channels each case measures depend on (a six-axis
        # record may measure a subset of its rig's channels)
        needed = list(dict.fromkeys(n for e in exps
                                    for n in e.derived.needed_parameters(e.channels or None)))
        notes = [n for c in cases for n in c.notes]  # what loading did to the records
        if any(c.motion is not None for c in cases):
            from ..data.motion import input_note

            notes.append(input_note(input, force_cutoff_hz))
        if estimate is None:
            names = [n for n in needed if n not in rig_fixed and n not in hold]
            names += [n for mm in measurement for n in mm.parameters if n not in hold]
            at_rest, rest_notes = rest_holds(exps, names)  # free decays: masses undetermined
            names = [n for n in names if n not in at_rest]
            notes += rest_notes
        else:
            names = list(estimate)
            clash = sorted(set(names) & set(hold))
            if clash:
                raise InputError(f"parameters both estimated and held: {', '.join(clash)}")
        predicted, sources, failure = predicted_sources(cases[0], model, names)
        explicit = model.explicit_values()
        start: dict[str, float] = {}
        for n in params:
            # user's initial value > value given to a constructor > prediction > declared default
            candidates = (initial_user.get(n), hold.get(n), explicit.get(n), predicted.get(n),
                          params[n].default)
            v = next((c for c in candidates if c is not None), None)
            if v is not None:
                start[n] = float(v)
        ties, linear, budget_notes = liquid_budget(cases, model, names, start)
        tied = {t.parameter for t in ties}
        names = [n for n in names if n not in tied]
        notes += budget_notes
        if "rig.dry_mass" in names and "rig.dry_mass" not in start:
            # an unweighed container: a start of the liquid's order (fit's first stage refines it)
            start["rig.dry_mass"] = _container_guess(cases[0])
            sources = {**sources, "rig.dry_mass": "a guess (the liquid mass)"}
        given = set(initial_user) | set(hold) | set(explicit)
        stage_start = {}
        if stage is not None:
            from .first_stage import starting_values

            stage_start = {k: v for k, v in starting_values(
                stage, gravity=cases[0].rig.gravity, estimated=names,
                values={**start, **exps[0].fixed},
                liquid_mass=_liquid(cases[0])).items() if k not in given}
            start |= stage_start
            sources = {**sources, **dict.fromkeys(stage_start, "the first stage")}
            notes.append(stage.describe())
        notes += [n for n in (stage_note, lag_note) if n]
        missing = [n for n in names if n not in start]
        if missing:
            why = failure or ("neither `[prediction]` nor the tank modal analysis supplies "
                              "them (they give masses, lengths, heights and inertias of the "
                              "fixed mass and the pendulums)")
            raise InputError(
                f"no initial value for {', '.join(f'`{n}`' for n in missing)}: {why}; give them "
                f"with `initial` (e.g. `FitProblem.build(..., initial={{'{missing[0]}': ...}})`)")
        notes += source_notes(sources, [n for n in names if n not in given])
        if any(c.motion is not None for c in cases):  # heights and inertias: data or tank?
            from ..data.motion import moments_note

            notes += [n for n in (moments_note(model, names, start),) if n]
        g = cases[0].rig.gravity
        inside = tank_ranges(cases[0], model, names, {
            n: length_bounds(v)[1] for n, v in predicted.items() if n.endswith(".length")})
        est = []
        for n in names:
            p = params[n]
            lo, hi = p.lower, p.upper
            if n.endswith(".length") and n in predicted and n not in bounds_user:
                lo, hi = length_bounds(predicted[n])
                notes.append(f"`{n}` bounded to +/-20 % of the predicted {predicted[n]:.4g} m")
                if n in stage_start and not lo < stage_start[n] < hi:
                    # the anchor stays (a length pinned at it is the diagnosis's evidence of
                    # a stiffness the liquid lacks); the start moves inside
                    notes.append(f"the first stage's `{n}` ({stage_start[n]:.4g} m) lies "
                                 "outside the prediction's +/-20 %: started at the bound")
            lo, hi = bounds_user.get(n, (lo, hi))
            x0 = min(max(start[n], lo), hi)
            scale = nominal_scale(n, x0, start, g)
            if n in per_case_names:
                targets = list(range(len(exps)))
            elif n in PER_CASE:
                targets = [i for i, e in enumerate(exps) if n in e.derived.parameter_names]
            else:
                targets = [None]
            for i in targets:
                label = n if i is None else f"{cases[i].test.id}:{n}"
                x0_i = x0
                if n == "rig.lag" and stage is not None and n not in given:
                    x0_i = min(max(stage.lags[i], lo), hi)
                est.append(Estimated(label, n, i, p.unit, x0_i, lo, hi, scale))
        if first_stage and stage is None:
            est, spun = _spin_start(exps, w, est, {**start, **exps[0].fixed}, given,
                                    force_cutoff_hz, inside)
            if spun is not None:
                stage = spun
                notes.append(spun.describe())
        labels = [e.name for e in est]
        if len(set(labels)) != len(labels):
            raise InputError("case ids must be unique when per-case parameters are estimated")
        fixed = []
        for e in exps:
            vals = {n: v for n, v in start.items() if n not in names and n not in tied}
            vals |= {n: v for n, v in hold.items()}
            vals |= dict(e.fixed)
            fixed.append(vals)
        known_channels = {c for e in exps for c in e.channels}
        stray = sorted(set(cw) - known_channels)
        if stray:
            raise UnknownNameError(f"channel_weights: unknown channel{'s' if len(stray) > 1 else ''} "
                           + ", ".join(f"`{c}`" for c in stray) + "; the cases measure "
                           + ", ".join(sorted(known_channels)))
        missing_ch = [e.case.test.id for e in exps if not e.channels]
        if missing_ch:
            raise InputError(f"cases {', '.join(missing_ch)} measure none of the model's outputs "
                             + ", ".join(exps[0].derived.measured))
        single = [type(mm).__name__ for mm in measurement if mm.channels is None]
        if single and any(len(e.channels) > 1 for e in exps):
            raise InputError(f"measurement models {', '.join(single)} apply to the lateral "
                             "force only; remove them for multi-channel cases (their channels' "
                             "offsets and drifts: `ChannelOffsets()`)")
        notes += _noise_notes(exps, carriage, noise)
        return cls(model, exps, tuple(est), tuple(fixed), force_cutoff_hz, tuple(notes), w,
                   tuple(measurement), cw, input, carriage, noise, ties, linear, stage,
                   inside)

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
            Estimated(e.name, e.parameter, e.case, e.unit,
                      min(max(float(values.get(e.name, e.initial)), e.lower), e.upper),
                      e.lower, e.upper, e.scale)
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
        """Raise if an initial value is not finite."""
        bad = [e.name for e in self.estimated if not math.isfinite(e.initial)]
        if bad:
            raise InputError(f"initial values are not finite: {', '.join(bad)}")


def _liquid(case: Case) -> float | None:
    try:
        return float(case.liquid_mass)
    except (ValueError, ArithmeticError):
        return None


def _first_stage(cases, model: Model, exps, carriage, noise, weights):
    """The first stage (:func:`estimate.fitting.first_stage.record_stage`) of lateral
    measured cases fitted with a first-mode pendulum, else ``None``."""
    from .first_stage import record_stage
    from .initial import predicted_values

    if not any(p.name == "p1.length" for p in model.parameters):
        return None
    g = cases[0].rig.gravity
    try:
        pred = predicted_values(cases[0], model)
        L, m = pred["p1.length"], pred["p1.mass"]
        f = math.sqrt(g / L + pred.get("p1.stiffness", 0.0) / (m * L**2)) / (2 * math.pi)
    except (KeyError, InputError, ValueError, ArithmeticError):
        f = math.nan
    return record_stage((exps, carriage, noise, weights), frequency_hz=f, gravity=g)


def _spin_start(exps, weights, est: list, start: Mapping[str, float], given,
                cutoff: float | None, inside: Mapping[str, tuple[float, float]]):
    """``est`` started from the spinning rig's first stage
    (:func:`estimate.fitting.spin_stage.spin_stage`, searching within the estimates'
    bounds and the tank, ``inside``) where it applies (the values the user gave kept), and
    the stage (``None``: not run)."""
    if exps[0].case.test.rig != "spinning" or any(e.case is not None for e in est):
        return est, None
    from .spin_stage import spin_stage

    box = {e.parameter: (max(e.lower, inside.get(e.parameter, (-math.inf,))[0]),
                         min(e.upper, inside.get(e.parameter, (0, math.inf))[1])) for e in est}
    stage = spin_stage(exps, weights, [e.parameter for e in est], start, box, cutoff_hz=cutoff)
    if stage is None:
        return est, None
    out = [replace(e, initial=min(max(stage.values[e.parameter], e.lower), e.upper))
           if e.parameter in stage.values and e.parameter not in given else e for e in est]
    return out, stage


def _with_lag(measurement: tuple, mode: str, stage, carriage, exps) -> tuple[tuple, str | None]:
    """``measurement`` with a :class:`StreamLag` where ``mode`` asks for one, and a note."""
    from .measurement import SensorDelay, StreamLag

    if mode == "none" or any(isinstance(m, (StreamLag, SensorDelay)) for m in measurement):
        return measurement, None
    estimable = bool(carriage) and all(c is not None for c in carriage)
    if not estimable:
        if mode == "estimate":
            raise InputError("a stream lag is estimated with the estimated carriage motion: "
                             "build with input='estimated' and measured displacements")
        return measurement, None
    if mode == "auto" and (stage is None or not stage.lag_identified):
        why = ("no first stage" if stage is None else "the first stage determines it to "
               + ", ".join(f"{1e3 * s:.3g} ms" for s in stage.lag_stderr))
        return measurement, f"stream lag not estimated: not identifiable from the record ({why})"
    if mode == "auto" and all(abs(t) < LAG_MIN for t in stage.lags):
        return measurement, ("stream lag not estimated: the first stage puts it at "
                             + ", ".join(f"{1e3 * t:.2f} +/- {1e3 * s:.2g} ms" for t, s in
                                         zip(stage.lags, stage.lag_stderr))
                             + f", below {1e3 * LAG_MIN:g} ms")
    return measurement + (StreamLag(),), ("stream lag between the displacement and the force "
                                          "estimated (`rig.lag`, per case)")


def _container_guess(case: Case) -> float:
    """Start value of an unweighed container's mass [kg]: the liquid's, when the tank
    geometry gives it, else 1 kg."""
    try:
        return float(case.liquid_mass)
    except (ValueError, ArithmeticError):
        return 1.0


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


def _resolve_channels(measurement: tuple, exps: Sequence[Experiment]) -> tuple:
    """Measurement models with their channels filled in: a multi-channel model declared
    with ``channels=None`` (:class:`~estimate.fitting.measurement.ChannelOffsets`) takes the
    channels the cases measure, which must then be the same in every case; one with
    channels names only channels every case measures, in the model's order."""
    from .measurement import ChannelOffsets

    out = []
    for mm in measurement:
        if isinstance(mm, ChannelOffsets):
            measured = {e.channels for e in exps}
            if mm.channels is None:
                if len(measured) > 1:
                    raise InputError("ChannelOffsets(): the cases measure different channels ("
                                     + "; ".join(", ".join(c) for c in sorted(measured))
                                     + "); name them: `ChannelOffsets(channels=(...))`")
                mm = replace(mm, channels=exps[0].channels)
            for e in exps:
                if tuple(mm.channels) != e.channels:
                    raise InputError(f"ChannelOffsets: channels {', '.join(mm.channels)} are not "
                                     f"the channels case {e.case.test.id} fits, in order: "
                                     f"{', '.join(e.channels)}")
        out.append(mm)
    return tuple(out)


def _as_parameter(name: str, spec):
    from analogs import Parameter

    return Parameter(name, spec.unit, spec.default, spec.lower, spec.upper, spec.description)


def _input_estimation(exps: Sequence[Experiment], mode: str, cutoff: float | None
                      ) -> tuple[tuple[CarriageInput | None, ...], tuple[RecordNoise | None, ...]]:
    """Per case, the carriage spline (measured lateral cases) and the force noise, when the
    input is estimated; ``None`` otherwise."""
    if mode != "estimated":
        return tuple(None for _ in exps), tuple(None for _ in exps)
    if cutoff is not None:
        raise InputError("the estimated input weighs the force by its white-noise level: "
                         "leave `force_cutoff_hz` at its default (no force filter), or use "
                         "input='filtered'")
    carriage, noise = [], []
    for e in exps:
        case = e.case
        if case.test.rig != "lateral" or case.force is None:
            carriage.append(None)
            noise.append(None)
        elif case.test.excitation == "measured":
            ci, rn = carriage_input(case.time, case.displacement, force=case.force,
                                    at_rest=case.test.starts_at_rest,
                                    motion_band_hz=case.test.motion_band_hz)
            if ci.displacement_noise < DISPLACEMENT_FLOOR:
                ci = replace(ci, displacement_noise=DISPLACEMENT_FLOOR)
            carriage.append(ci)
            noise.append(rn)
        else:  # crank: the motion is a parametric model; the force's noise weighs it
            carriage.append(None)
            noise.append(record_noise(case.time, case.force, 2 * case.crank.frequency))
    return tuple(carriage), tuple(noise)


def _noise_notes(exps, carriage, noise) -> tuple[str, ...]:
    notes = []
    for e, ci, rn in zip(exps, carriage, noise):
        if rn is None:
            continue
        cid = e.case.test.id
        fig = rn.figure
        text = (f"{cid}: force residuals weighed by the force noise {rn.force_noise:.3g} N ("
                + (fig.detail if fig is not None else "") + ")"
                + (f", displacement residuals by {ci.displacement_noise:.3g} m" if ci else ""))
        if ci is not None:
            text += (f"; carriage motion estimated (quintic spline, knots "
                     f"{1e3 * ci.spline.spacing:.3g} ms apart"
                     + (", at rest at the first sample)" if ci.at_rest else ")")
                     + ("; the displacement noise is not white (a drifting or integrated "
                        "displacement): its level is the start spline's misfit"
                        if ci.coloured_noise else ""))
        notes.append(text)
        for label, tones, unit in (("force", rn.tones, "N"),
                                   ("displacement", ci.displacement_tones if ci else (), "m")):
            if tones:
                notes.append(f"{cid}: removed {label} tones " + ", ".join(
                    f"{f:.4g} Hz ({a:.3g} {unit})" for f, a in tones))
    return tuple(notes)
