"""Diagnosis: show what the baseline analog gets wrong, name the physical cause, extend the
model with the component that represents it, measure the gain on held-out data, and say
honestly what stays unexplained.

This module is the policy only; the families (:mod:`estimate.diagnosis.families`) say what
each cause adds, how it is screened or scanned and when its fit is physical. Each round
linearises the current model with every screened term at its null value
(:mod:`estimate.diagnosis.screening`), asks every family for its candidate fits, fits the
promising ones (warm-started, 3 of 10 interleaved blocks held out, under budgets that
scale with the record: :mod:`estimate.diagnosis.fitter`) and accepts the best by
:func:`rejection` (the acceptance rule). When no named family is accepted, the best term
of a small hinge-torque library may be. The loop ends when nothing helps; the verdict
compares the final residual with the measurement noise.

With a measured carriage displacement the fits estimate the carriage motion
(:mod:`estimate.fitting.carriage`), so the residual floor is the measurement noise and small
effects stand out; their residuals are in units of the noise levels.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from analogs import FixedMass, HingeDamper, LateralRig, Model, Pendulum

from ..data.case import Case
from ..fitting.initial import predicted_values
from ..fitting.measurement import SensorDelay
from ..fitting.result import FitResult
from .evidence import collect_evidence, segment_damping
from .families import FAMILIES, Context, Proposal, Score
from .fitter import Fitter
from .outcome import CandidateOutcome, Diagnosis, Finding, Verdict
from .scoring import MIN_SCORE, bic, far_from_noise, heldout, holdout_weights, noise_figure, poor_start
from .screening import screen

__all__ = ["Diagnosis", "Finding", "CandidateOutcome", "diagnose", "baseline_model",
           "fit_candidate", "rejection", "force_cutoff"]

#: Maximum BIC change (negative: better) for accepting an extension ("very strong").
MAX_BIC_CHANGE = -10.0
#: Minimum held-out chi-square reduction (residuals in noise units) for accepting one.
MIN_HELDOUT_CHI2 = 9.0
#: Share of the objective's excess over the noise (``objective - dof``, residuals in noise
#: units) an extension must remove: when the current model is far from the data, a held-out
#: chi-square drop of 9 is lenient (a 15 N transducer saturation left 1.4x the noise, and
#: dry friction cut the held-out chi-square by 37 but removed 2 % of the excess, 0.3 % of
#: the held-out RMS); a real effect removes most of the excess it causes (friction_a: 87 %).
MIN_EXCESS_SHARE = 0.1
#: A library term is fitted besides accepted named families when its score is this many
#: times the best named family's.
LIBRARY_DOMINANCE = 2.0
#: Screened named terms fitted per round, best scores first; when the current fit is far
#: from the data its linearisation ranks them poorly (a hardening hinge's large swings
#: put quadratic damping, rig friction and a library term ahead of the cubic spring, all
#: within 20 % of each other), and more are fitted.
MAX_SCREENED_FITS = 2
MAX_SCREENED_FITS_FAR = 4
#: A candidate is not fitted in a round when its score predicts less than this fraction
#: (1/DOMINATED) of the objective reduction an accepted candidate of the round achieved:
#: only one candidate is accepted per round, and it is screened again in the next.
DOMINATED = 5.0


def baseline_model(case: Case) -> Model:
    """Fixed mass + first-mode pendulum with a linear hinge damper and no hinge spring.

    A free liquid surface has no restoring stiffness besides gravity; a hinge spring is
    what a diaphragm adds, so it is a candidate (``diaphragm_stiffness``), not part of the
    baseline. The pendulum length is anchored to the prediction (+/-20 %). On the spinning
    rig the pendulum is spherical (:class:`analogs.SphericalPendulum`) on the rig of
    :func:`estimate.data.models.rig_for`; on a six-axis record too when its drive is not
    planar (:data:`~.families.swirl.PLANAR_DRIVE`), else planar: liquid that moves across
    a planar drive is swirl, a candidate (:mod:`.families.swirl`).
    """
    if case.test.rig == "spinning":
        from analogs import SphericalPendulum

        from ..data.models import rig_for

        return (Model((rig_for(case),)) + FixedMass("fixed") + SphericalPendulum("p1")
                + HingeDamper("p1"))
    from .families.swirl import PLANAR_DRIVE, transverse_drive

    pendulum = Pendulum("p1")
    if transverse_drive(case) > PLANAR_DRIVE:
        from analogs import SphericalPendulum

        pendulum = SphericalPendulum("p1")
    return (LateralRig(excitation=case.test.excitation) + FixedMass("fixed") + pendulum
            + HingeDamper("p1"))


def force_cutoff(cases: Sequence[Case]) -> float:
    """Force low-pass for diagnosis with the filtered input (Hz): the seed's 10 Hz, raised to
    four times the top drive frequency. A lightly damped higher mode crossed by a sweep
    swings far and puts odd harmonics into the force; filtering them out of the data but
    not out of the model biases its mass (a 3.8 Hz mode came out 17 % light at 10 Hz, within
    0.2 % at 20 Hz)."""
    from ..data.signals import significant_frequencies

    tops = []
    for c in cases:
        fs = 1.0 / float(np.median(np.diff(c.time)))
        if c.spin is not None:
            top = abs(c.spin.rate) / (2 * math.pi)
        elif c.displacement is not None:
            top = max(significant_frequencies(c.time, c.displacement))
        else:
            top = c.crank.frequency if c.crank is not None else 2.5
        tops.append(min(max(10.0, 4.0 * top), 0.4 * fs))
    return max(tops)


def diagnose(cases: Case | Sequence[Case], *, max_bic_change: float = MAX_BIC_CHANGE,
             max_rounds: int = 3, segments: int = 4,
             force_cutoff_hz: float | None = None, progress: bool | None = None,
             screen_decimated: bool = True) -> Diagnosis:
    """Diagnose the baseline analog on ``cases`` and extend it greedily.

    Parameters
    ----------
    cases : Case or sequence of Case
        Test cases (physical parameters shared).
    max_bic_change : float, default -10
        An extension must lower the BIC by at least this much ("very strong" evidence).
    max_rounds : int, default 3
        At most this many extensions.
    segments : int, default 4
        Time segments for the amplitude dependence of damping and frequency.
    force_cutoff_hz : float, optional
        Low-pass of the measured force when the input is filtered (spinning rig); default
        :func:`force_cutoff`.
    progress : bool, optional
        Show a bar counting the fits and naming the stage; default: on a terminal only.
    screen_decimated : bool, default True
        A long record sampled far above the slosh band
        (:func:`~estimate.data.decimation.slosh_band_factor`: 10,000 samples or more at
        200 Hz or more, on the lateral rig) is searched on a copy decimated to about 100 Hz;
        only the baseline (from the prediction, as without it) and the final model (from
        the search's estimates) are fitted on every sample. ``[test] decimate = 1`` or
        ``False`` here: every fit on every sample.
    """
    from .._progress import progress as bar

    with bar(total=None, desc="diagnose", unit=" fits", enabled=progress) as b:
        return _diagnose(cases, max_bic_change, max_rounds, segments, force_cutoff_hz, b,
                         screen_decimated)


def _diagnose(cases, max_bic_change: float, max_rounds: int, segments: int,
              force_cutoff_hz: float | None, bar, screen_decimated: bool = True) -> Diagnosis:
    t0 = time.perf_counter()
    cases = [cases] if isinstance(cases, Case) else list(cases)
    lateral = all(c.test.rig == "lateral" for c in cases)
    full_cases, cases, notes = cases, *_screening_cases(cases, screen_decimated)
    # estimated input on the lateral rig (the residual floor is then the noise); the
    # spinning rig's motion is prescribed, its six channels fitted filtered
    cutoff = force_cutoff_hz or force_cutoff(full_cases)
    fitter = Fitter(cases, [holdout_weights(c.time.size) for c in cases],
                    "estimated" if lateral else "filtered", cutoff, bar)
    model = baseline_model(cases[0])
    bar.set_postfix_str("baseline")
    base = _baseline(fitter, model)
    segs = segment_damping(base, n_segments=segments)
    fitter.extra += len(segs)
    evidence = base_evidence = collect_evidence(base, segments=segs)
    predicted = predicted_values(cases[0], model + Pendulum("p2"))
    if cases[0].tank.diaphragm:
        notes.append("the case file says the tank has a diaphragm; the diagnosis starts from the "
                     "free-surface analog and looks for the diaphragm's signature in the data")
    current, findings, rounds = base, [], []
    measured = all(c.test.excitation == "measured" for c in cases)
    for i in range(max_rounds):
        bar.set_postfix_str(f"round {i + 1}: candidates")
        ctx = Context(current, evidence, predicted, cases[0].rig.gravity, fitter, lateral,
                      measured, segments)
        outcomes = _round(ctx, max_bic_change)
        rounds.append(tuple(outcomes))
        accepted = [o for o in outcomes if o.rejected is None]
        if not accepted:
            break
        findings.append(_finding(accepted[0], [o for o in outcomes if o is not accepted[0]]))
        current = accepted[0].result
        fitter.accept(current)
        # the segment refits (amplitude trends) are made when a candidate needs them
        evidence = collect_evidence(current, segments=())
    bar.set_postfix_str("final fit")
    search = fitter
    if full_cases is not cases:
        fitter = Fitter(full_cases, [holdout_weights(c.time.size) for c in full_cases],
                        fitter.input, cutoff, bar)
        fitter.held, fitter.started = dict(search.held), search.started
        # from the prediction, as without the screening: the decimated baseline's
        # estimates were no better a start (60 s, 500 Hz hardware-like record of
        # benchmarks/bench_diagnose.py: 21 iterations, 8.4 s from them, 23, 7.6 s cold)
        base = _baseline(fitter, model, " (every sample)")
        base_evidence = collect_evidence(base, segments=segs)
        fitter.log[:0], fitter.extra = search.log, search.extra
    notes += _bound_notes("baseline", base)
    # a candidate's bounds stay; the first mode's stability bounds of a cold start do not
    bounds = {e.name: (e.lower, e.upper) for e in current.problem.estimated
              if e.case is None and e.name not in ("p1.mass", "p1.damping")}
    start = dict(zip(current.names, current.values))
    final = fitter(current.problem.model, current.problem.measurement, start, bounds,
                   weights=None, warm=current, purpose="final (whole record)")
    if not final.converged:
        # the warm start's held-out blocks carry a carriage motion from the displacement
        # alone; from a simulation at the estimates instead (chirp_mode2: the warm final
        # fit wandered off a mode it had, 40 iterations)
        again = fitter(current.problem.model, current.problem.measurement, start, bounds,
                       weights=None, purpose="final (whole record), from a simulation")
        final = again if _better(again, final) else final
    for fam in FAMILIES:
        final, note = fam.finish(fitter, final)
        notes += [note] if note else []
    if search.time_left() <= 0:
        notes.append(f"the diagnosis's time budget ({search.budget:.0f} s of CPU time for "
                     f"{search.samples} samples) was spent: candidates not yet fitted were not "
                     "tried (see the candidates table)")
    final_evidence = collect_evidence(final, segments=evidence.segments)
    verdict = Verdict.of(final_evidence, tuple(rounds), tuple(findings))
    notes += _bound_notes("final model", final)
    # one noise figure per record: the final model's, the residual nearest the noise
    return Diagnosis(base, base_evidence.against(final_evidence.noise), tuple(findings), final,
                     final_evidence, tuple(rounds), fitter.count, time.perf_counter() - t0, tuple(notes),
                     verdict, tuple(fitter.log))


def _screening_cases(cases: list[Case], decimated: bool) -> tuple[list[Case], list[str]]:
    """The cases the diagnosis's search fits: ``cases``, or (``decimated``) those that are
    long and sampled far above the slosh band decimated to about 100 Hz
    (:func:`~estimate.data.decimation.slosh_band_factor`), with a note saying so."""
    from ..data.decimation import decimate_case, slosh_band_factor

    factors = [slosh_band_factor(c) if decimated else None for c in cases]
    if not any(factors):
        return cases, []
    out = [decimate_case(c, k, "the diagnosis's screening") if k else c
           for c, k in zip(cases, factors)]
    which = "; ".join(f"{c.data_path.name} by {k} ({c.sample_rate:.6g} -> "
                      f"{c.sample_rate / k:.6g} Hz)" for c, k in zip(cases, factors) if k)
    return out, [f"the candidates were screened and fitted on the record decimated to the slosh "
                 f"band ({which}; their residuals in the candidates table are the decimated "
                 f"record's); the baseline and the final model are fitted on every sample"]


def _baseline(fitter: Fitter, model: Model, what: str = "") -> FitResult:
    """The baseline fit of ``fitter``'s cases from the prediction; when it does not
    converge, again from a damped start (a lightly damped start next to a resonance can
    swing over the top), the better of the two kept."""
    base = fitter(model, (), {}, purpose="baseline" + what)
    if not base.converged:
        g = fitter.cases[0].rig.gravity
        m, L = (base.problem.initial[base.names.index(n)] for n in ("p1.mass", "p1.length"))
        again = fitter(model, (), {"p1.damping": 2 * 0.05 * m * L**2 * math.sqrt(g / L)},
                       purpose=f"baseline{what}, damped restart")
        if (again.converged, -again.objective) > (base.converged, -base.objective):
            base = again  # else the first attempt, closer to the data, stays the baseline
    return base


def _bound_notes(label: str, res: FitResult) -> list[str]:
    """A note when ``res`` ends at a bound (a mass, a length, the liquid mass budget)."""
    reached = res.bounds_reached
    return [f"the {label} ends at a bound: {'; '.join(reached)}"] if reached else []


def _proposals(ctx: Context) -> tuple[list[Proposal], list[CandidateOutcome], Proposal | None]:
    """The round's candidate fits (best score first), the candidates screened out, and the
    best library term's fit (``None``: no library term is significant)."""
    fams = [f for f in FAMILIES if f.applies(ctx)]
    terms = {f.cause: f.terms(ctx) for f in fams}
    scores: list[Score] = []
    if any(terms.values()) or (ctx.lateral and ctx.single_channel and not ctx.six_axis):
        ctx.linearisation, ctx.base_names, scores = screen(
            ctx.current, [t for ts in terms.values() for t in ts],
            build=lambda m, mm, init: ctx.fitter.problem(m, mm, init))
    rms0, _ = heldout(ctx.current)
    out: list[CandidateOutcome] = []
    proposals: list[Proposal] = []
    screened, most = 0, MAX_SCREENED_FITS_FAR if far_from_noise(ctx.current) else MAX_SCREENED_FITS
    named_best, library = 0.0, None
    for sc in scores:  # best first
        fam = next(f for f in fams if f.cause == sc.term.cause)
        if sc.statistic < MIN_SCORE:
            continue
        if sc.unphysical is not None:
            out.append(CandidateOutcome.not_fitted(sc.term.cause, (sc.term.label,), ctx.current,
                                                   rms0, f"screened: {sc.unphysical}", sc.statistic))
        elif fam.library:
            library = library or fam.propose(ctx, [sc])[0]
        elif screened < most:
            named_best = max(named_best, sc.statistic)
            proposals += fam.propose(ctx, [sc])
            screened += 1
        else:
            out.append(CandidateOutcome.not_fitted(
                sc.term.cause, (sc.term.label,), ctx.current, rms0,
                f"not tried: {most} screened candidates with higher scores were fitted", sc.statistic))
    for fam in fams:
        if not terms[fam.cause]:
            found = fam.propose(ctx, [])
            proposals += found
            why = fam.why_not(ctx) if not found else None
            if why:
                out.append(CandidateOutcome.not_fitted(fam.cause, (fam.cause,), ctx.current,
                                                       rms0, f"not tried: {why}"))
    if library is not None and library.score > LIBRARY_DOMINANCE * named_best:
        # the library route ahead of the named families: a term whose score dwarfs every
        # named family's (which then only bend around the effect)
        proposals.append(library)
        library = None
    # best score first; a candidate the family asks to fit first before them (what proposes
    # it is evidence of its own, and when it reaches the noise the others need no fit),
    # other candidates without a score after them
    proposals.sort(key=lambda p: (not p.first, -p.score if math.isfinite(p.score) else math.inf))
    return proposals, out, library


def _round(ctx: Context, max_bic_change: float) -> list[CandidateOutcome]:
    """One round: screen, fit the promising candidates best score first, score them; the
    outcomes best first. A candidate is not fitted when an accepted one of this round
    already leaves the residual at the noise (none can explain significantly more), when
    its score predicts a small fraction of what an accepted one achieved (only one is
    accepted per round; the others are screened again in the next), or when the
    diagnosis's time budget is spent."""
    current, fitter = ctx.current, ctx.fitter
    proposals, outcomes, library = _proposals(ctx)
    rms0, _ = heldout(current)
    achieved, floor = 0.0, None
    for prop in proposals:
        predicted_gain = prop.score * current.residual_variance
        why = None
        if floor is not None:
            why = (f"{floor.cause} already leaves the residual at "
                   f"{noise_figure(floor.result).ratio:.2f} times the noise")
        elif math.isfinite(prop.score) and predicted_gain * DOMINATED < achieved:
            why = (f"its score {prop.score:.0f} predicts an objective reduction of "
                   f"{predicted_gain:.3g}, under 1/{DOMINATED:.0f} of the {achieved:.3g} an "
                   f"accepted candidate achieved")
        elif fitter.time_left() <= 0:
            why = "the diagnosis's time budget is spent"
        if why is not None:
            outcomes.append(CandidateOutcome.not_fitted(
                prop.cause, prop.added, current, rms0,
                f"not tried this round: {why} (screened again next round)", prop.score))
            continue
        out = _try(fitter, prop, current, max_bic_change)
        outcomes.append(out)
        if out.rejected is None:
            achieved = max(achieved, current.objective - out.result.objective)
            if noise_figure(out.result).within:
                floor = out
    if library is not None and not any(o.rejected is None for o in outcomes) \
            and fitter.time_left() > 0:
        # the library route: a hinge torque term no named family describes
        outcomes.append(_try(fitter, library, current, max_bic_change))
    outcomes.sort(key=lambda o: (o.rejected is not None,
                                 -(o.heldout_chi2 if o.fitted else -1e300),
                                 -(o.gain if o.fitted else -1e300)))
    return outcomes


def _better(a: FitResult, b: FitResult | None) -> bool:
    return b is None or (a.converged, -a.objective) > (b.converged, -b.objective)


def fit_candidate(fitter: Fitter, prop: Proposal, current: FitResult) -> FitResult:
    """Fit a candidate from the current estimates and the proposal's start. A strong effect
    the current model cannot carry bends its estimates into another basin (a hardening hinge
    made a 13 kg fixed mass): when the current fit is far from the data and the proposal
    has a start read off the evidence, that start (from the prediction) comes first, the
    warm one only if it falls short; a proposal's other start is tried when the fit does
    not converge or stays far from the noise."""
    start = {n: v for n, v in zip(current.names, current.values) if ":" not in n}
    start |= dict(prop.initial)
    if prop.fit is not None:
        return prop.fit(fitter, start, current)

    def cold() -> FitResult:
        return fitter(prop.model, prop.measurement, dict(prop.cold_start), prop.bounds,
                      purpose=f"{prop.cause} from the prediction", hold=prop.hold)

    first = cold() if prop.cold_start is not None and far_from_noise(current) else None
    if first is not None and not poor_start(current, first):
        return first
    res = fitter(prop.model, prop.measurement, start, prop.bounds, warm=current,
                 purpose=prop.cause, hold=prop.hold)
    if first is None and prop.cold_start is not None and poor_start(current, res):
        first = cold()
    if first is not None and _better(first, res):
        res = first
    if prop.retry is not None and (not res.converged or poor_start(current, res)):
        again = fitter(prop.model, prop.measurement, start | dict(prop.retry), prop.bounds,
                       warm=current, purpose=f"{prop.cause}, second start", hold=prop.hold)
        res = again if _better(again, res) else res
    return res


def rejection(current: FitResult, res: FitResult, prop: Proposal, *, heldout_chi2: float,
              gain: float, bic_change: float, max_bic_change: float = MAX_BIC_CHANGE
              ) -> str | None:
    """The acceptance rule: why the candidate fit ``res`` of ``prop`` is not accepted over
    the current fit, or ``None`` when it is. It must converge; cut the held-out chi-square
    by :data:`MIN_HELDOUT_CHI2`; with noise-weighted residuals, remove
    :data:`MIN_EXCESS_SHARE` of the objective's excess over the noise; lower the BIC by
    ``max_bic_change``; and have physical parameters (inside the tank, and the family's
    rule)."""
    weighted = bool(current.problem.noise) and all(n is not None for n in current.problem.noise)
    drop, excess = current.objective - res.objective, current.objective - current.dof
    if not res.converged:
        return f"the fit did not converge ({res.status})"
    if res.outside_tank:
        return "it puts the analog outside its tank: " + "; ".join(res.outside_tank)
    if not heldout_chi2 >= MIN_HELDOUT_CHI2:
        return (f"held-out chi-square fell by {heldout_chi2:.1f} (needs {MIN_HELDOUT_CHI2:.0f}; "
                f"held-out RMS gain {100 * gain:.1f} %)")
    if weighted and excess > 0 and not drop >= MIN_EXCESS_SHARE * excess:
        return (f"it removed {drop:.0f} of the {excess:.0f} the objective exceeds the noise by "
                f"({100 * drop / excess:.1f} %, needs {100 * MIN_EXCESS_SHARE:.0f} %; held-out RMS "
                f"gain {100 * gain:.1f} %): it bends around an effect it does not describe")
    if bic_change > max_bic_change:
        return f"BIC change {bic_change:+.1f} is not below {max_bic_change:+.0f}"
    return prop.plausible(res)


def _try(fitter: Fitter, prop: Proposal, current: FitResult,
         max_bic_change: float) -> CandidateOutcome:
    rms0, chi0 = heldout(current)
    try:
        res = fit_candidate(fitter, prop, current)
    except (ValueError, RuntimeError) as err:
        return CandidateOutcome.not_fitted(prop.cause, prop.added, current, rms0,
                                           f"fit failed: {err}", prop.score)
    rms1, chi1 = heldout(res)
    delays = sum(isinstance(m, SensorDelay) for m in current.problem.measurement)
    dbic = bic(res, prop.extra_parameters + delays) - bic(current, delays)
    gain = 1 - rms1 / rms0
    reason = rejection(current, res, prop, heldout_chi2=chi0 - chi1, gain=gain,
                       bic_change=dbic, max_bic_change=max_bic_change)
    try:
        text = prop.describe(res)
    except (KeyError, ValueError, StopIteration):
        text = prop.cause
    return CandidateOutcome(prop.cause, prop.added, rms0, res, rejected=reason, evidence=text,
                            score=prop.score if math.isfinite(prop.score) else None,
                            rms_after=rms1, gain=gain, bic_change=dbic, heldout_chi2=chi0 - chi1)


def _finding(best: CandidateOutcome, others: list[CandidateOutcome]) -> Finding:
    text = (f"{best.evidence}: cut the held-out RMS residual by {100 * best.gain:.0f} % "
            f"({best.rms_before:.3g} -> {best.rms_after:.3g}, BIC {best.bic_change:+.0f})")
    runner = next((o for o in others if o.fitted or o.rejected), None)
    if runner is not None:
        why = runner.rejected or "its held-out gain was smaller"
        gain = f"{100 * runner.gain:.0f} % held-out gain" if runner.fitted else "not fitted"
        text += f"; runner-up {runner.cause} ({gain}) not chosen: {why}"
    return Finding(best.cause, text, best.added, best.rms_before, best.rms_after, best.gain,
                   best.bic_change)
