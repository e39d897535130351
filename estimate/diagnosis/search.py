"""Diagnosis: show what the baseline analog gets wrong, name the physical cause, extend the
model with the component that represents it, measure the gain on held-out data, and say
honestly what stays unexplained.

Each round screens every family at once by its score statistic
(:mod:`estimate.diagnosis.screening`: one linearisation, no fits) and adds the candidates
the screening cannot rank (another slosh mode from a matched scan, a diaphragm's spring
with the length held, a sensor delay, a rotor). Candidates with a significant score and
physically signed parameters are refitted, warm-started from the current fit, with 3 of 10
interleaved blocks held out; one is accepted when it lowers the held-out objective, the BIC
strongly and its parameters are physical. When no named family does, the best term of a
small hinge-torque library may. The loop ends when nothing helps; the verdict compares the
final residual with the measurement noise.

With a measured carriage displacement the fits estimate the carriage motion
(:mod:`estimate.fitting.carriage`), so the residual floor is the measurement noise and small
effects stand out; their residuals are in units of the noise levels.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
from scipy.optimize import minimize_scalar

from analogs import FixedMass, HingeDamper, LateralRig, Model, Pendulum

from ..data.case import Case
from ..fitting.initial import predicted_values
from ..fitting.measurement import MeasurementModel, SensorDelay
from ..fitting.nlp import fit
from ..fitting.problem import FitProblem
from ..fitting.result import FitResult
from .candidates import Proposal, propose
from .evidence import Evidence, collect_evidence, segment_damping
from .families import family_proposal
from .outcome import CandidateOutcome, Diagnosis, Finding, Verdict
from .scoring import bic, heldout, holdout_weights, poor_start
from .screening import families, screen

__all__ = ["Diagnosis", "Finding", "CandidateOutcome", "diagnose", "baseline_model"]

#: Maximum BIC change (negative: better) for accepting an extension ("very strong").
MAX_BIC_CHANGE = -10.0
#: Minimum held-out chi-square reduction (residuals in noise units) for accepting one.
MIN_HELDOUT_CHI2 = 9.0
#: Score statistic a screened candidate needs to be fitted (5 standard deviations for one
#: new parameter: a dozen candidates are screened each round).
MIN_SCORE = 25.0
#: A library term is fitted besides accepted named families when its score is this many
#: times the best named family's.
LIBRARY_DOMINANCE = 2.0
#: Screened candidates fitted per round, best scores first.
MAX_SCREENED_FITS = 2


def baseline_model(case: Case) -> Model:
    """Fixed mass + first-mode pendulum with a linear hinge damper and no hinge spring.

    A free liquid surface has no restoring stiffness besides gravity; a hinge spring is
    what a diaphragm adds, so it is a candidate (``diaphragm_stiffness``), not part of the
    baseline. The pendulum length is anchored to the prediction (+/-20 %). On the spinning
    rig the pendulum is spherical (:class:`analogs.SphericalPendulum`) on the rig of
    :func:`estimate.data.models.rig_for`.
    """
    if case.test.rig == "spinning":
        from analogs import SphericalPendulum

        from ..data.models import rig_for

        return (Model((rig_for(case),)) + FixedMass("fixed") + SphericalPendulum("p1")
                + HingeDamper("p1"))
    return (LateralRig(excitation=case.test.excitation) + FixedMass("fixed") + Pendulum("p1")
            + HingeDamper("p1"))



# candidates start at the current fit and the step their score points to: a good one
# converges in well under 40 iterations
_CANDIDATE_SOLVER = {"ipopt.max_iter": 40, "ipopt.max_cpu_time": 30.0}
# new states (another mode) start from a simulation: a right candidate converges in 20-60
_NEW_STATES_SOLVER = {"ipopt.max_iter": 100, "ipopt.max_cpu_time": 60.0}
_SPINNING_SOLVER = {"ipopt.max_iter": 150, "ipopt.max_cpu_time": 120.0}


class _Fitter:
    """Builds and fits problems of the diagnosed cases with fixed held-out weights and
    counts the fits."""

    def __init__(self, cases: Sequence[Case], weights: Sequence[np.ndarray] | None,
                 input_mode: str, cutoff: float | None, bar=None) -> None:
        self.cases, self.weights, self.count = list(cases), weights, 0
        self.input, self.cutoff = input_mode, cutoff
        self.bar = bar  # a progress bar counting the fits, or None

    def problem(self, model: Model, measurement: Sequence[MeasurementModel], initial,
                bounds=None, *, weights="default") -> FitProblem:
        w = self.weights if weights == "default" else weights
        cutoff = self.cutoff if self.input == "filtered" else "auto"
        prob = FitProblem.build(self.cases, model, measurement=tuple(measurement), weights=w,
                                bounds=bounds, force_cutoff_hz=cutoff, input=self.input)
        known = {e.name for e in prob.estimated}
        return prob.with_initial({k: v for k, v in initial.items() if k in known})

    def __call__(self, model: Model, measurement: Sequence[MeasurementModel], initial,
                 bounds=None, *, weights="default", warm: FitResult | None = None) -> FitResult:
        self.count += 1
        if self.bar is not None:
            self.bar.update()
        prob = self.problem(model, measurement, initial, bounds, weights=weights)
        # candidates that do not converge quickly are not what the data want; six-channel
        # spinning-rig fits have six times the residuals and start farther (no input)
        if not all(len(e.channels) == 1 for e in prob.experiments):
            opts = _SPINNING_SOLVER
        elif warm is None:  # the baseline and starts from the prediction
            opts = {}
        elif all(a.derived.coordinates == b.derived.coordinates
                 for a, b in zip(prob.experiments, warm.problem.experiments)):
            opts = _CANDIDATE_SOLVER  # warm on the same states: a good one is quick
        else:
            opts = _NEW_STATES_SOLVER  # new states (another mode) start from a simulation
        return fit(prob, progress=False, solver_options=opts, warm_start=warm)


def _profile_delay(fitter: _Fitter, proposal: Proposal, start: dict[str, float],
                   reference_cost: float, warm: FitResult) -> FitResult:
    lo, hi = proposal.delay_range
    cache: dict[float, FitResult] = {}

    def run(tau: float) -> FitResult:
        tau = round(float(tau), 5)
        if tau not in cache:
            cache[tau] = fitter(proposal.model, proposal.measurement + (SensorDelay(tau),),
                                start, proposal.bounds, warm=warm)
        return cache[tau]

    grid = np.array([0.1, 0.3, 0.6]) * (hi - lo) + lo
    costs = [run(tau).objective for tau in grid]
    i = int(np.argmin(costs))
    if costs[i] > 0.99 * reference_cost:  # no delay lowers the cost: not worth refining
        return run(float(grid[i]))
    a = lo if i == 0 else grid[i - 1]
    b = grid[i + 1] if i + 1 < grid.size else hi
    best = minimize_scalar(lambda tau: run(tau).objective, bounds=(a, b), method="bounded",
                           options={"xatol": 1e-3})
    tau = round(float(best.x), 5) if best.fun <= costs[i] else round(float(grid[i]), 5)
    return run(tau)


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


def _input_mode(cases: Sequence[Case]) -> str:
    """Estimated input for lateral-rig cases (the residual floor is then the noise); the
    spinning rig's motion is prescribed, its six channels fitted filtered as before."""
    return "estimated" if all(c.test.rig == "lateral" for c in cases) else "filtered"


def diagnose(cases: Case | Sequence[Case], *, max_bic_change: float = MAX_BIC_CHANGE,
             max_rounds: int = 3, segments: int = 4,
             force_cutoff_hz: float | None = None, progress: bool | None = None) -> Diagnosis:
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
    """
    from .._progress import progress as bar

    with bar(total=None, desc="diagnose", unit="fit", enabled=progress) as b:
        return _diagnose(cases, max_bic_change, max_rounds, segments, force_cutoff_hz, b)


def _diagnose(cases, max_bic_change: float, max_rounds: int, segments: int,
              force_cutoff_hz: float | None, bar) -> Diagnosis:
    t0 = time.perf_counter()
    cases = [cases] if isinstance(cases, Case) else list(cases)
    mode = _input_mode(cases)
    model = baseline_model(cases[0])
    weights = [holdout_weights(c.time.size) for c in cases]
    fitter = _Fitter(cases, weights, mode, force_cutoff_hz or force_cutoff(cases), bar)
    bar.set_postfix_str("baseline")
    base = fitter(model, (), {})
    if not base.converged:
        # a lightly damped start next to a resonance can swing over the top: restart damped
        g = cases[0].rig.gravity
        m, L = (base.problem.initial[base.names.index(n)] for n in ("p1.mass", "p1.length"))
        base = fitter(model, (), {"p1.damping": 2 * 0.05 * m * L**2 * math.sqrt(g / L)})
    evidence = collect_evidence(base, segments=segment_damping(base, n_segments=segments))
    fitter.count += segments
    base_evidence = evidence
    predicted = predicted_values(cases[0], model + Pendulum("p2"))
    notes = []
    if cases[0].tank.diaphragm:
        notes.append("the case file says the tank has a diaphragm; the diagnosis starts from the "
                     "free-surface analog and looks for the diaphragm's signature in the data")
    current = base
    findings: list[Finding] = []
    rounds: list[tuple[CandidateOutcome, ...]] = []
    lateral = all(c.test.rig == "lateral" for c in cases)
    measured = all(c.test.excitation == "measured" for c in cases)
    for i in range(max_rounds):
        bar.set_postfix_str(f"round {i + 1}: candidates")
        outcomes = _round(fitter, current, evidence, predicted, cases[0].rig.gravity,
                          lateral=lateral, measured=measured, max_bic_change=max_bic_change)
        rounds.append(tuple(outcomes))
        accepted = [o for o in outcomes if o.rejected is None]
        if not accepted:
            break
        best = accepted[0]
        findings.append(_finding(best, [o for o in outcomes if o is not best]))
        current = best.result
        evidence = collect_evidence(current, segments=segment_damping(current, n_segments=segments))
        fitter.count += segments
    start = {n: v for n, v in zip(current.names, current.values)}
    bar.set_postfix_str("final fit")
    final = fitter(current.problem.model, current.problem.measurement, start,
                   _bounds_of(current), weights=None, warm=current)
    final_evidence = collect_evidence(final, segments=evidence.segments)
    verdict = Verdict.of(final_evidence, tuple(rounds), tuple(findings))
    return Diagnosis(base, base_evidence, tuple(findings), final, final_evidence,
                     tuple(rounds), fitter.count, time.perf_counter() - t0, tuple(notes),
                     verdict)


def _round(fitter: _Fitter, current: FitResult, evidence: Evidence, predicted, gravity: float,
           *, lateral: bool, measured: bool, max_bic_change: float) -> list[CandidateOutcome]:
    """One round: screen, fit the promising candidates, score them; best first."""
    measurement = tuple(current.problem.measurement)
    rms0, chi0 = heldout(current)
    delays = sum(isinstance(m, SensorDelay) for m in measurement)
    bic0 = bic(current, delays)
    outcomes: list[CandidateOutcome] = []
    proposals: list[tuple[Proposal, float]] = []
    single = all(len(e.channels) == 1 for e in current.problem.experiments)
    inertia = predicted.get("p1.mass", math.nan) * predicted.get("p1.length", math.nan) ** 2
    inertia = inertia if math.isfinite(inertia) and inertia > 0 else None
    if lateral and single:
        scores = screen(current, families(current.problem.model, measurement, "p1",
                                          measured_excitation=measured),
                        host="p1", build=lambda m, mm, init: fitter.problem(m, mm, init))
        named = [sc for sc in scores if sc.family.cause != "hinge_torque"]
        library = [sc for sc in scores if sc.family.cause == "hinge_torque"]
        for sc in named:
            text = f"score {sc.statistic:.0f} (chi-square, {sc.dof} dof)"
            if sc.statistic >= MIN_SCORE and sc.unphysical is None and \
                    sum(1 for _, s in proposals if math.isfinite(s)) < MAX_SCREENED_FITS:
                proposals.append((family_proposal(sc, current, evidence, text,
                                                  inertia=inertia), sc.statistic))
            elif sc.statistic >= MIN_SCORE:
                outcomes.append(_not_fitted(sc, current, rms0, f"screened: {sc.unphysical}"))
        proposals += [(p, math.nan) for p in propose(
            current.problem.model, measurement, current, evidence, gravity=gravity,
            predicted=predicted)]
    else:
        proposals += [(p, math.nan) for p in propose(
            current.problem.model, measurement, current, evidence, gravity=gravity,
            predicted=predicted)]
        named, library = [], []
    for prop, score in proposals:
        outcomes.append(_try(fitter, prop, current, score, rms0, chi0, bic0, delays,
                             max_bic_change))
    if lateral and not any(o.cause == "sensor_delay" for o in outcomes) and not delays:
        outcomes.append(CandidateOutcome(
            "sensor_delay", ("sensor_delay",), rms0, math.nan, 0.0, 0.0,
            f"not tried: no timing skew in the residual (correlation with dF/dt "
            f"{evidence.skew_correlation:+.2f}, implied delay {1e3 * evidence.skew_delay:.1f} ms)",
            "", current))
    named_best = max((sc.statistic for sc in named if sc.unphysical is None), default=0.0)
    if not any(o.rejected is None for o in outcomes) or \
            (library and library[0].statistic > LIBRARY_DOMINANCE * named_best):
        # the library route: a hinge torque term no named family describes (also when its
        # score dwarfs every named family's, which then only bends around the effect)
        for sc in library[:1]:
            if sc.statistic >= MIN_SCORE:
                text = f"score {sc.statistic:.0f} (chi-square, {sc.dof} dof)"
                outcomes.append(_try(fitter, family_proposal(sc, current, evidence, text,
                                                             inertia=inertia),
                                     current, sc.statistic, rms0, chi0, bic0, delays,
                                     max_bic_change))
    outcomes.sort(key=lambda o: (o.rejected is not None,
                                 -(o.heldout_chi2 if math.isfinite(o.heldout_chi2) else -1e300),
                                 -(o.gain if math.isfinite(o.gain) else -1e300)))
    return outcomes


def _not_fitted(sc, current: FitResult, rms0: float, why: str) -> CandidateOutcome:
    return CandidateOutcome(sc.family.cause, (sc.family.label,), rms0, math.nan, -math.inf,
                            math.inf, why, "", current, score=sc.statistic)


def _try(fitter: _Fitter, prop: Proposal, current: FitResult, score: float, rms0: float,
         chi0: float, bic0: float, delays: int, max_bic_change: float) -> CandidateOutcome:
    start = {n: v for n, v in zip(current.names, current.values) if ":" not in n}
    start |= dict(prop.initial)
    try:
        if prop.delay_range is not None:
            res = _profile_delay(fitter, prop, start, current.objective, current)
            extra = 1
        else:
            res = fitter(prop.model, prop.measurement, start, prop.bounds, warm=current)
            extra = 0
            if poor_start(current, res) and prop.cold_start is not None:
                # a strong effect the current model cannot carry bends its estimates
                # into another basin (a hardening hinge made a 13 kg fixed mass): start
                # again from the prediction, with the effect read off the amplitude trend
                cold = fitter(prop.model, prop.measurement, dict(prop.cold_start),
                              prop.bounds)
                if (cold.converged, -cold.objective) > (res.converged, -res.objective):
                    res = cold
    except (ValueError, RuntimeError) as err:
        return CandidateOutcome(prop.cause, prop.added, rms0, math.nan, -math.inf, math.inf,
                                f"fit failed: {err}", "", current, score=score)
    rms1, chi1 = heldout(res)
    gain = 1 - rms1 / rms0
    dchi = chi0 - chi1
    dbic = bic(res, extra + delays) - bic0
    if not res.converged:
        reason = f"the fit did not converge ({res.status})"
    elif not dchi >= MIN_HELDOUT_CHI2:
        reason = (f"held-out chi-square fell by {dchi:.1f} (needs {MIN_HELDOUT_CHI2:.0f}; "
                  f"held-out RMS gain {100 * gain:.1f} %)")
    elif dbic > max_bic_change:
        reason = f"BIC change {dbic:+.1f} is not below {max_bic_change:+.0f}"
    else:
        reason = prop.plausible(res)
    try:
        text = prop.describe(res)
    except (KeyError, ValueError, StopIteration):
        text = prop.cause
    return CandidateOutcome(prop.cause, prop.added, rms0, rms1, gain, dbic, reason, text, res,
                            heldout_chi2=dchi, score=score)


def _finding(best: CandidateOutcome, others: list[CandidateOutcome]) -> Finding:
    text = (f"{best.evidence}: cut the held-out RMS residual by {100 * best.gain:.0f} % "
            f"({best.rms_before:.3g} -> {best.rms_after:.3g}, BIC {best.bic_change:+.0f})")
    runner = next((o for o in others if math.isfinite(o.gain) or o.rejected), None)
    if runner is not None:
        why = runner.rejected or "its held-out gain was smaller"
        gain = f"{100 * runner.gain:.0f} % held-out gain" if math.isfinite(runner.gain) \
            else "not fitted"
        text += f"; runner-up {runner.cause} ({gain}) not chosen: {why}"
    return Finding(best.cause, text, best.added, best.rms_before, best.rms_after, best.gain,
                   best.bic_change)


def _bounds_of(res: FitResult) -> dict[str, tuple[float, float]]:
    return {e.name: (e.lower, e.upper) for e in res.problem.estimated if e.case is None}
