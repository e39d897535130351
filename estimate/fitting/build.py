"""The named steps of :meth:`FitProblem.build <estimate.fitting.problem.FitProblem.build>`:
the arguments checked (every problem at once), the cases' experiments, the input mode's
carriage and noise, the first stage, the estimated names, their start values, bounds and
scales, the values held. Each step says what it adds; :func:`build_problem` runs them in
order.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from analogs import Model
from analogs.errors import InputError, UnknownNameError

from ..data.case import Case
from ..data.decimation import decimation_note
from ..data.experiment import Experiment, experiment
from ..data.models import model_for_case
from ..data.records import refuse_repeated
from .budget import liquid_budget, tank_ranges
from .free_decay import rest_holds
from .initial import length_bounds, nominal_scale, predicted_sources, source_notes
from .input_noise import input_estimation, noise_notes
from .starts import (
    LAG_MODES,
    container_guess,
    liquid_or_none,
    record_first_stage,
    spin_start,
    with_lag,
)
from .strategies import InputMode, StartPolicy, input_mode, record_cutoff, start_policy

__all__ = ["Arguments", "build_problem"]


@dataclass(frozen=True)
class Arguments:
    """The arguments of :meth:`FitProblem.build`, checked: the input mode and start policy
    as objects, the mappings copied."""

    cases: tuple[Case, ...]
    mode: InputMode
    start: StartPolicy
    hold: dict[str, float]
    initial: dict[str, float]
    bounds: dict[str, tuple[float, float]]
    channel_weights: dict[str, float]
    weights: tuple
    lag: str


def raise_all(problems: Sequence[InputError]) -> None:
    """Raise the problems found by a step as one error listing every one (the one error
    itself when there is one; its class when all share it, else :class:`InputError`)."""
    if not problems:
        return
    if len(problems) == 1:
        raise problems[0]
    kinds = {type(p) for p in problems}
    kind = kinds.pop() if len(kinds) == 1 else InputError
    raise kind(f"{len(problems)} problems with the fit problem:\n  - "
               + "\n  - ".join(str(p) for p in problems))


def checked_arguments(cases: Case | Sequence[Case], *, hold, initial, bounds, force_cutoff_hz,
                      weights, channel_weights, input, lag, start) -> Arguments:
    """The arguments, every problem reported at once."""
    cases = (cases,) if isinstance(cases, Case) else tuple(cases)
    if not cases:
        raise InputError("no cases to fit")
    problems: list[InputError] = []
    try:
        refuse_repeated(cases)
    except InputError as err:
        problems.append(err)
    mode = None
    try:
        mode = input_mode(input, record_cutoff(cases, input, force_cutoff_hz))
    except InputError as err:
        problems.append(err)
    policy = None
    try:
        policy = start_policy(start)
    except InputError as err:
        problems.append(err)
    cw = dict(channel_weights or {})
    bad = {k: v for k, v in cw.items()
           if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0
           or not math.isfinite(v)}
    if bad:
        problems.append(InputError("channel_weights: expected positive finite scales (N or N m), "
                                   "found " + ", ".join(f"`{k}` = {v!r}" for k, v in bad.items())))
    if weights is not None:
        w = tuple(weights)
    else:  # six-axis records low-passed: the force filter's ends left out
        from ..data.motion import edge_weights

        cutoff = mode.force_cutoff_hz if mode is not None else None
        w = tuple(edge_weights(c, cutoff) for c in cases)
    if len(w) != len(cases):
        problems.append(InputError(f"weights: expected one entry per case ({len(cases)}), "
                                   f"got {len(w)}"))
    if lag not in LAG_MODES:
        problems.append(InputError(f"lag must be one of {', '.join(map(repr, LAG_MODES))}, "
                                   f"got {lag!r}"))
    raise_all(problems)
    return Arguments(cases, mode, policy, dict(hold or {}), dict(initial or {}),
                     dict(bounds or {}), cw, w, lag)


def experiments(cases: Sequence[Case], model: Model) -> tuple[Experiment, ...]:
    """Each case with the model on its own rig (a measured and a crank case share
    the physical parameters)."""
    return tuple(experiment(c, model_for_case(model, c)) for c in cases)


def model_parameters(exps: Sequence[Experiment], measurement: Sequence) -> dict:
    """The parameters of the models and the measurement models, by name."""
    params = {p.name: p for e in exps for p in e.derived.parameters}
    for mm in measurement:
        params |= {n: _as_parameter(n, spec) for n, spec in mm.parameters.items()}
    return params


def name_problems(args: Arguments, estimate: Sequence[str] | None, params: Mapping,
                  exps: Sequence[Experiment], measurement: Sequence) -> list[InputError]:
    """The names the arguments give that the problem does not have (parameters,
    channels), parameters both estimated and held, cases that measure nothing the model
    outputs, lateral-force measurement models on multi-channel cases."""
    problems: list[InputError] = []
    unknown = sorted((set(args.hold) | set(args.initial) | set(args.bounds) | set(estimate or ()))
                     - set(params))
    if unknown:
        problems.append(UnknownNameError(
            f"unknown parameter{'s' if len(unknown) > 1 else ''} "
            f"{', '.join(f'`{u}`' for u in unknown)}; the model's parameters are "
            + ", ".join(params)))
    if estimate is not None:
        clash = sorted(set(estimate) & set(args.hold))
        if clash:
            problems.append(InputError(f"parameters both estimated and held: {', '.join(clash)}"))
    known_channels = {c for e in exps for c in e.channels}
    stray = sorted(set(args.channel_weights) - known_channels)
    if stray:
        problems.append(UnknownNameError(
            f"channel_weights: unknown channel{'s' if len(stray) > 1 else ''} "
            + ", ".join(f"`{c}`" for c in stray) + "; the cases measure "
            + ", ".join(sorted(known_channels))))
    missing_ch = [e.case.test.id for e in exps if not e.channels]
    if missing_ch:
        problems.append(InputError(f"cases {', '.join(missing_ch)} measure none of the model's "
                                   "outputs " + ", ".join(exps[0].derived.measured)))
    single = [type(mm).__name__ for mm in measurement if mm.channels is None]
    if single and any(len(e.channels) > 1 for e in exps):
        problems.append(InputError(
            f"measurement models {', '.join(single)} apply to the lateral force only; remove "
            "them for multi-channel cases (their channels' offsets and drifts: "
            "`ChannelOffsets()`)"))
    return problems


def estimated_names(estimate: Sequence[str] | None, args: Arguments,
                    exps: Sequence[Experiment], measurement: Sequence) -> tuple[list[str], list[str]]:
    """The parameters to estimate and notes: the user's, or every parameter the
    equations and the outputs each case measures need (a six-axis record may measure a
    subset of its rig's channels) less the rig values the case files fix, the held ones
    and the masses a free decay cannot determine."""
    if estimate is not None:
        return list(estimate), []
    rig_fixed = set().union(*(e.fixed for e in exps))
    needed = list(dict.fromkeys(n for e in exps
                                for n in e.derived.needed_parameters(e.channels or None)))
    names = [n for n in needed if n not in rig_fixed and n not in args.hold]
    names += [n for mm in measurement for n in mm.parameters if n not in args.hold]
    at_rest, rest_notes = rest_holds(exps, names)  # free decays: masses undetermined
    return [n for n in names if n not in at_rest], list(rest_notes)


def start_values(params: Mapping, args: Arguments, explicit: Mapping[str, float],
                 predicted: Mapping[str, float]) -> dict[str, float]:
    """Every parameter's start value: the user's initial value > a held value > a
    value given to a constructor > the prediction > the declared default."""
    start: dict[str, float] = {}
    for n in params:
        candidates = (args.initial.get(n), args.hold.get(n), explicit.get(n), predicted.get(n),
                      params[n].default)
        v = next((c for c in candidates if c is not None), None)
        if v is not None:
            start[n] = float(v)
    return start


@dataclass(frozen=True)
class Start:
    """Where the estimates start (:func:`starting_point`): the estimated names less the
    tied ones, every parameter's start value, the prediction, the liquid budget's ties and
    linear bounds, the names whose values the user or a constructor gave, and the first
    stage's values."""

    names: list[str]
    values: dict[str, float]
    predicted: dict[str, float]
    ties: tuple
    linear: tuple
    tied: set[str]
    given: set[str]
    stage_start: dict[str, float]
    #: The starts the first stage replaced, as they were (the prediction's).
    before_stage: dict[str, float]


def starting_point(args: Arguments, model: Model, exps: Sequence[Experiment], params: Mapping,
                   names: list[str], stage, stage_note: str | None, lag_note: str | None,
                   notes: list[str]) -> Start:
    """Where the estimates start: the prediction (tank modal analysis or
    ``[prediction]``, computed once per case), the values given, the liquid budget's ties,
    an unweighed container's guess, the first stage's values; raises naming every
    estimate without a start. Appends its notes to ``notes``."""
    cases, hold = args.cases, args.hold
    predicted, sources, failure = predicted_sources(cases[0], model, names)
    explicit = model.explicit_values()
    start = start_values(params, args, explicit, predicted)
    ties, linear, budget_notes = liquid_budget(cases, model, names, start)
    tied = {t.parameter for t in ties}
    names = [n for n in names if n not in tied]
    notes += budget_notes
    if "rig.dry_mass" in names and "rig.dry_mass" not in start:
        # an unweighed container: a start of the liquid's order (fit's first stage refines it)
        start["rig.dry_mass"] = container_guess(cases[0])
        sources = {**sources, "rig.dry_mass": "a guess (the liquid mass)"}
    given = set(args.initial) | set(hold) | set(explicit)
    stage_start, before_stage = {}, {}
    if stage is not None:
        from .first_stage import starting_values

        stage_start = {k: v for k, v in starting_values(
            stage, gravity=cases[0].rig.gravity, estimated=names,
            values={**start, **exps[0].fixed},
            liquid_mass=liquid_or_none(cases[0])).items() if k not in given}
        before_stage = {k: start[k] for k in stage_start if k in start}
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
    return Start(names, start, predicted, ties, linear, tied, given, stage_start, before_stage)


def estimates(names: Sequence[str], params: Mapping, args: Arguments, start: Mapping[str, float],
              predicted: Mapping[str, float], stage_start: Mapping[str, float], given: set,
              stage, exps: Sequence[Experiment], per_case_names: set, per_case: Sequence[str],
              gravity: float, notes: list[str]) -> list:
    """The :class:`~estimate.fitting.problem.Estimated` parameters with start,
    bounds (pendulum lengths within the prediction's band) and scale; per-case ones once
    per case that has them. Appends its notes to ``notes``."""
    from .problem import Estimated

    est = []
    for n in names:
        p = params[n]
        lo, hi = p.lower, p.upper
        band = False
        if n.endswith(".length") and n in predicted and n not in args.bounds:
            lo, hi = length_bounds(predicted[n])
            band = True
            notes.append(f"`{n}` bounded to +/-20 % of the predicted {predicted[n]:.4g} m")
            if n in stage_start and not lo < stage_start[n] < hi:
                # the anchor stays (a length pinned at it is the diagnosis's evidence of
                # a stiffness the liquid lacks); the start moves inside
                notes.append(f"the first stage's `{n}` ({stage_start[n]:.4g} m) lies "
                             "outside the prediction's +/-20 %: started at the bound")
        lo, hi = args.bounds.get(n, (lo, hi))
        x0 = min(max(start[n], lo), hi)
        scale = nominal_scale(n, x0, start, gravity)
        if n in per_case_names:
            targets = list(range(len(exps)))
        elif n in per_case:
            targets = [i for i, e in enumerate(exps) if n in e.derived.parameter_names]
        else:
            targets = [None]
        for i in targets:
            label = n if i is None else f"{args.cases[i].test.id}:{n}"
            x0_i = x0
            if n == "rig.lag" and stage is not None and n not in given:
                x0_i = min(max(stage.lags[i], lo), hi)
            est.append(Estimated(label, n, i, p.unit, x0_i, lo, hi, scale, band))
    return est


def build_problem(cls, cases: Case | Sequence[Case], model: Model, *,
                  estimate: Sequence[str] | None, hold, initial, bounds, force_cutoff_hz,
                  measurement: Sequence, weights, channel_weights, input, lag, start):
    """:meth:`FitProblem.build` (its docstring gives the arguments) in named steps:
    :func:`checked_arguments`, :func:`experiments`, the input mode's carriage and noise
    (:func:`~estimate.fitting.input_noise.input_estimation`), the first stage and the
    stream lag (:mod:`estimate.fitting.starts`), :func:`name_problems`,
    :func:`estimated_names`, :func:`starting_point`, :func:`estimates`, the spinning rig's
    stage, the values held; ``cls`` is the problem class."""
    from .problem import PER_CASE

    args = checked_arguments(cases, hold=hold, initial=initial, bounds=bounds,
                             force_cutoff_hz=force_cutoff_hz, weights=weights,
                             channel_weights=channel_weights, input=input, lag=lag, start=start)
    cases, hold, w = args.cases, args.hold, args.weights
    w, left_out, clip_notes = _without_bad_samples(cases, w)
    model = model.validate()
    exps = experiments(cases, model)
    measurement = _resolve_channels(tuple(measurement), exps)
    carriage, noise = input_estimation(exps, args.mode)
    stage = (record_first_stage(cases, model, exps, carriage, noise, w)
             if args.start.first_stage else None)
    stage_note = None
    if stage is not None and stage.failure is not None:
        stage_note = f"first stage not used: {stage.failure}; starting from the prediction"
        stage = None
    measurement, lag_note = with_lag(measurement, args.lag, stage, carriage, exps)
    per_case_names = {n for mm in measurement if mm.per_case for n in mm.parameters}
    params = model_parameters(exps, measurement)
    raise_all(name_problems(args, estimate, params, exps, measurement))
    notes = [n for c in cases for n in c.notes]  # what loading did to the records
    notes += clip_notes
    notes += [n for c in cases if (n := decimation_note(c))]
    six_axis = any(c.motion is not None for c in cases)
    if six_axis:
        from ..data.motion import input_note

        notes.append(input_note(args.mode.name, args.mode.force_cutoff_hz))
    names, rest_notes = estimated_names(estimate, args, exps, measurement)
    notes += rest_notes
    st = starting_point(args, model, exps, params, names, stage, stage_note, lag_note, notes)
    names, start, predicted, tied, given = st.names, st.values, st.predicted, st.tied, st.given
    if six_axis:  # heights and inertias: from the data or the tank?
        from ..data.motion import moments_note

        notes += [n for n in (moments_note(model, names, start),) if n]
    ties, linear, stage_start = st.ties, st.linear, st.stage_start
    g = cases[0].rig.gravity
    inside = tank_ranges(cases[0], model, names, {
        n: length_bounds(v)[1] for n, v in predicted.items() if n.endswith(".length")})
    est = estimates(names, params, args, start, predicted, stage_start, given, stage, exps,
                    per_case_names, PER_CASE, g, notes)
    if args.start.first_stage and stage is None:
        est, spun = spin_start(exps, w, est, {**start, **exps[0].fixed}, given,
                               args.mode.force_cutoff_hz, inside)
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
    notes += noise_notes(exps, carriage, noise)
    return cls(model, exps, tuple(est), tuple(fixed), tuple(notes), w, tuple(measurement),
               args.channel_weights, args.mode, carriage, noise, ties, linear, stage, inside,
               prediction_start={e.name: st.before_stage[e.parameter] for e in est
                                 if e.parameter in st.before_stage},
               left_out=left_out if any(m is not None for m in left_out) else ())


def _without_bad_samples(cases: Sequence[Case], weights: tuple
                         ) -> tuple[tuple, tuple, list[str]]:
    """The sample weights with every clipped sample's and spike's set to 0
    (:func:`estimate.data.bad_samples.bad_samples`), those samples per case (or None), and
    a warning per flagged channel (also returned as the fit's notes)."""
    from ..data.bad_samples import BadSamples, bad_samples

    out, masks, notes = list(weights), [], []
    for i, case in enumerate(cases):
        mask, found = bad_samples(case)
        masks.append(mask)
        if mask is None:
            continue
        base = np.ones(case.time.size) if out[i] is None else np.asarray(out[i], float)
        out[i] = np.where(mask, 0.0, base)
        for f in found:
            notes.append(f.describe(case.test.id))
            warnings.warn(notes[-1], BadSamples, stacklevel=3)
    return tuple(out), tuple(masks), notes


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


