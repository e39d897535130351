"""Diagnosis: show what the baseline analog gets wrong, name the physical cause, extend the
model with the component that represents it, and measure the gain on held-out data.

Greedy forward selection: every candidate (:mod:`estimate.diagnosis.candidates`) is refitted
warm-started from the current model on the fitted samples; its gain is the reduction of the
RMS residual on held-out segments (interleaved blocks left out of the fit, still simulated
through) and its BIC change on the fitted samples. The best plausible candidate is accepted
when both are significant; the loop repeats until no candidate helps. Nothing is accepted
when the current model already explains the data to within the measurement noise.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

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

__all__ = ["Diagnosis", "Finding", "CandidateOutcome", "diagnose", "baseline_model"]

#: Minimum held-out RMS reduction for accepting an extension.
MIN_GAIN = 0.10
#: Maximum BIC change (negative: better) for accepting an extension.
MAX_BIC_CHANGE = -10.0


@dataclass(frozen=True)
class CandidateOutcome:
    """A refitted candidate: held-out RMS before/after (N), gain, BIC change, and why it
    was not accepted (``None`` when it qualified)."""

    cause: str
    added: tuple[str, ...]
    rms_before: float
    rms_after: float
    gain: float
    bic_change: float
    rejected: str | None
    evidence: str
    result: FitResult = field(repr=False)


@dataclass(frozen=True)
class Finding:
    """An accepted extension with its cause and evidence."""

    cause: str
    evidence: str
    added: tuple[str, ...]
    rms_before: float
    rms_after: float
    gain: float
    bic_change: float

    def to_dict(self) -> dict[str, Any]:
        return {"cause": self.cause, "evidence": self.evidence, "added": list(self.added),
                "rms_before": self.rms_before, "rms_after": self.rms_after,
                "gain": self.gain, "bic_change": self.bic_change}


@dataclass(frozen=True)
class Diagnosis:
    """The outcome of :func:`diagnose`."""

    baseline: FitResult
    baseline_evidence: Evidence
    findings: tuple[Finding, ...]
    final: FitResult
    final_evidence: Evidence
    rounds: tuple[tuple[CandidateOutcome, ...], ...]
    candidate_fits: int
    seconds: float
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The fixed-key JSON form written by ``slosh diagnose``."""
        base = self.baseline.to_dict()
        fin = self.final.to_dict()
        return {
            "baseline": {"model": base["model"], "rms_residual": self.baseline.rms_residual,
                         "parameters": base["parameters"]},
            "findings": [f.to_dict() for f in self.findings],
            "final": {"model": fin["model"], "parameters": fin["parameters"],
                      "derived": fin["derived"], "rms_residual": self.final.rms_residual,
                      "measurement": _measurement_dict(self.final)},
            "evidence": _evidence_dict(self.baseline_evidence),
            "candidates": [[{"cause": c.cause, "added": list(c.added), "gain": c.gain,
                             "bic_change": c.bic_change, "rms_before": c.rms_before,
                             "rms_after": c.rms_after, "rejected": c.rejected}
                            for c in rnd] for rnd in self.rounds],
            "candidate_fits": self.candidate_fits,
            "seconds": self.seconds,
            "notes": list(self.notes),
        }


def _measurement_dict(res: FitResult) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for mm in res.problem.measurement:
        if isinstance(mm, SensorDelay):
            out["sensor_delay_s"] = mm.delay
    return out


def _evidence_dict(ev: Evidence) -> dict[str, Any]:
    return {
        "rms_residual": ev.rms_residual, "noise_rms": ev.noise_rms,
        "within_noise": ev.within_noise, "drive_frequency_hz": ev.drive_frequency,
        "sweep": ev.sweep,
        "residual_peaks": [{"frequency_hz": p.frequency, "amplitude": p.amplitude,
                            "coherence": p.coherence, "drive_harmonic": p.harmonic} for p in ev.peaks],
        "drive_harmonics": {str(k): v for k, v in ev.harmonics.items()},
        "ljung_box": {"q": ev.ljung_box_q, "p_value": ev.ljung_box_p},
        "timing_skew": {"correlation": ev.skew_correlation, "implied_delay_s": ev.skew_delay},
        "frequency_vs_prediction": ev.frequency_ratio,
        "pinned": list(ev.pinned),
        "segments": [{"start_s": s.start, "stop_s": s.stop, "rms_angle": s.rms_angle,
                      "damping_ratio": s.damping_ratio, "frequency_hz": s.frequency_hz}
                     for s in ev.segments],
    }


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


def holdout_weights(n: int, *, blocks: int = 10, held: Sequence[int] = (1, 4, 7)) -> np.ndarray:
    """Weights leaving out interleaved blocks (default 3 of 10) of an ``n``-sample record."""
    w = np.ones(n)
    edges = np.linspace(0, n, blocks + 1).astype(int)
    for b in held:
        w[edges[b]:edges[b + 1]] = 0.0
    return w


def _heldout_rms(res: FitResult) -> float:
    num = sum(float(np.sum(res.scaled_residuals(i)[w == 0] ** 2)) for i, w in enumerate(res.weights))
    cnt = sum(int(np.sum(w == 0)) * (len(res.channels[i]) if res.channels else 1)
              for i, w in enumerate(res.weights))
    return math.sqrt(num / cnt) if cnt else res.rms_residual


def _bic(res: FitResult, extra_params: int = 0) -> float:
    n = res.n_samples
    k = len(res.names) + extra_params
    return n * math.log(res.cost / n) + k * math.log(n)


def _start_values(current: FitResult, proposal: Proposal) -> dict[str, float]:
    values = {n: v for n, v in zip(current.names, current.values) if ":" not in n}
    return {**values, **proposal.initial}


_CANDIDATE_SOLVER = {"ipopt.max_iter": 80, "ipopt.max_cpu_time": 20.0}
_SPINNING_SOLVER = {"ipopt.max_iter": 150, "ipopt.max_cpu_time": 120.0}


class _Fitter:
    """Counts fits and builds problems for the cases with fixed held-out weights."""

    def __init__(self, cases: Sequence[Case], weights: Sequence[np.ndarray] | None,
                 cutoff: float | None = 10.0) -> None:
        self.cases, self.weights, self.count, self.cutoff = list(cases), weights, 0, cutoff

    def __call__(self, model: Model, measurement: Sequence[MeasurementModel], initial, bounds=None,
                 *, weights="default") -> FitResult:
        self.count += 1
        w = self.weights if weights == "default" else weights
        prob = FitProblem.build(self.cases, model, measurement=tuple(measurement), weights=w,
                                bounds=bounds, force_cutoff_hz=self.cutoff, input="filtered")
        known = set(e.name for e in prob.estimated)
        prob = prob.with_initial({k: v for k, v in initial.items() if k in known})
        # candidates that do not converge quickly are not what the data want; six-channel
        # spinning-rig fits have six times the residuals and start farther (no input)
        opts = _CANDIDATE_SOLVER if all(len(e.channels) == 1 for e in prob.experiments) \
            else _SPINNING_SOLVER
        return fit(prob, progress=False, solver_options=opts)


def _profile_delay(fitter: _Fitter, proposal: Proposal, start: dict[str, float],
                   reference_cost: float) -> FitResult:
    lo, hi = proposal.delay_range
    cache: dict[float, FitResult] = {}

    def run(tau: float) -> FitResult:
        tau = round(float(tau), 5)
        if tau not in cache:
            cache[tau] = fitter(proposal.model, proposal.measurement + (SensorDelay(tau),),
                                start, proposal.bounds)
        return cache[tau]

    grid = np.array([0.1, 0.3, 0.6]) * (hi - lo) + lo
    costs = [run(tau).cost for tau in grid]
    i = int(np.argmin(costs))
    if costs[i] > 0.99 * reference_cost:  # no delay lowers the cost: not worth refining
        return run(float(grid[i]))
    a = lo if i == 0 else grid[i - 1]
    b = grid[i + 1] if i + 1 < grid.size else hi
    best = minimize_scalar(lambda tau: run(tau).cost, bounds=(a, b), method="bounded",
                           options={"xatol": 1e-3})
    tau = round(float(best.x), 5) if best.fun <= costs[i] else round(float(grid[i]), 5)
    return run(tau)


def force_cutoff(cases: Sequence[Case]) -> float:
    """Force low-pass for diagnosis (Hz): the seed's 10 Hz, raised to four times the top
    drive frequency. A lightly damped higher mode crossed by a sweep swings far and puts odd
    harmonics into the force; filtering them out of the data but not out of the model
    biases its mass (a 3.8 Hz mode came out 17 % light at 10 Hz, within 0.2 % at 20 Hz)."""
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


def diagnose(cases: Case | Sequence[Case], *, min_gain: float = MIN_GAIN,
             max_bic_change: float = MAX_BIC_CHANGE, max_rounds: int = 3,
             segments: int = 4, force_cutoff_hz: float | None = None) -> Diagnosis:
    """Diagnose the baseline analog on ``cases`` and extend it greedily.

    Parameters
    ----------
    cases : Case or sequence of Case
        Lateral-rig test cases (physical parameters shared).
    min_gain : float, default 0.10
        Minimum reduction of the held-out RMS residual for accepting an extension.
    max_bic_change : float, default -10
        An extension must lower the BIC by at least this much ("very strong" evidence).
    max_rounds : int, default 3
        At most this many extensions.
    segments : int, default 4
        Time segments for the amplitude-dependence check of damping.
    force_cutoff_hz : float, optional
        Low-pass of the measured force; default :func:`force_cutoff`.
    """
    t0 = time.perf_counter()
    cases = [cases] if isinstance(cases, Case) else list(cases)
    model = baseline_model(cases[0])
    weights = [holdout_weights(c.time.size) for c in cases]
    fitter = _Fitter(cases, weights, force_cutoff_hz or force_cutoff(cases))
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
    current, measurement = base, ()
    findings: list[Finding] = []
    rounds: list[tuple[CandidateOutcome, ...]] = []
    measured = all(c.test.excitation == "measured" for c in cases)
    lateral = all(c.test.rig == "lateral" for c in cases)
    for _ in range(max_rounds):
        if evidence.within_noise:
            notes.append(f"the model explains the data to within the noise (RMS residual "
                         f"{evidence.rms_residual:.3g} N, noise {evidence.noise_rms:.3g} N): no "
                         "extension is considered")
            break
        rms0 = _heldout_rms(current)
        bic0 = _bic(current, sum(isinstance(m, SensorDelay) for m in measurement))
        outcomes = []
        for prop in propose(current.problem.model, tuple(measurement), current, evidence,
                            gravity=cases[0].rig.gravity, predicted=predicted,
                            measured_excitation=measured):
            start = _start_values(current, prop)
            try:
                if prop.delay_range is not None:
                    res = _profile_delay(fitter, prop, start, current.cost)
                    extra = 1
                else:
                    res = fitter(prop.model, prop.measurement, start, prop.bounds)
                    extra = 0
            except (ValueError, RuntimeError) as err:
                outcomes.append(CandidateOutcome(prop.cause, prop.added, rms0, math.nan, -math.inf,
                                                 math.inf, f"fit failed: {err}", "", current))
                continue
            extra += sum(isinstance(m, SensorDelay) for m in measurement)
            rms1 = _heldout_rms(res)
            gain = 1 - rms1 / rms0
            dbic = _bic(res, extra) - bic0
            reason = None
            if not res.converged:
                reason = f"the fit did not converge ({res.status})"
            elif gain < min_gain:
                reason = f"held-out gain {100 * gain:.1f} % is below {100 * min_gain:.0f} %"
            elif dbic > max_bic_change:
                reason = f"BIC change {dbic:+.1f} is not below {max_bic_change:+.0f}"
            else:
                reason = prop.plausible(res)
            try:
                text = prop.describe(res)
            except (KeyError, ValueError, StopIteration):
                text = prop.cause
            outcomes.append(CandidateOutcome(prop.cause, prop.added, rms0, rms1, gain, dbic,
                                             reason, text, res))
        if lateral and not any(o.cause == "sensor_delay" for o in outcomes) and not any(
                isinstance(m, SensorDelay) for m in measurement):
            outcomes.append(CandidateOutcome(
                "sensor_delay", ("sensor_delay",), rms0, math.nan, 0.0, 0.0,
                f"not tried: no timing skew in the residual (correlation with dF/dt "
                f"{evidence.skew_correlation:+.2f}, implied delay {1e3 * evidence.skew_delay:.1f} ms)",
                "", current))
        outcomes.sort(key=lambda o: -o.gain)
        rounds.append(tuple(outcomes))
        accepted = [o for o in outcomes if o.rejected is None]
        if not accepted:
            break
        best = accepted[0]
        others = [o for o in outcomes if o is not best]
        runner = others[0] if others else None
        evidence_text = (f"{best.evidence}: cut the held-out RMS residual by {100 * best.gain:.0f} % "
                         f"({best.rms_before:.3g} -> {best.rms_after:.3g} N, BIC {best.bic_change:+.0f})")
        if runner is not None:
            why = runner.rejected or "its gain was smaller"
            evidence_text += (f"; runner-up {runner.cause} ({100 * runner.gain:.0f} % held-out gain) "
                              f"not chosen: {why}")
        findings.append(Finding(best.cause, evidence_text, best.added, best.rms_before,
                                best.rms_after, best.gain, best.bic_change))
        current = best.result
        measurement = current.problem.measurement
        evidence = collect_evidence(current, segments=segment_damping(current, n_segments=segments))
        fitter.count += segments
    start = {n: v for n, v in zip(current.names, current.values)}
    final = fitter(current.problem.model, measurement, start, _bounds_of(current), weights=None)
    final_evidence = collect_evidence(final)
    return Diagnosis(base, base_evidence, tuple(findings), final, final_evidence,
                     tuple(rounds), fitter.count, time.perf_counter() - t0, tuple(notes))


def _bounds_of(res: FitResult) -> dict[str, tuple[float, float]]:
    return {e.name: (e.lower, e.upper) for e in res.problem.estimated if e.case is None}
