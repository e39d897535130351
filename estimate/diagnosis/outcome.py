"""What a diagnosis concludes: the candidates tried, the findings accepted, and the verdict
on the residual that remains."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..fitting.measurement import SensorDelay
from ..fitting.result import FitResult
from .evidence import Evidence
from .fitter import FitRecord
from .scoring import NOISE_MARGIN

__all__ = ["CandidateOutcome", "Finding", "Verdict", "Diagnosis"]


@dataclass(frozen=True)
class CandidateOutcome:
    """A candidate of a round: what it adds, the held-out RMS residual before it (N, or
    channel scales), its score statistic (``None``: it has none), why it was not accepted
    (``None`` when it qualified), its evidence in words, and the fit it ended with (the
    current fit when it was not fitted). A fitted candidate also has the held-out RMS
    after it, the gain (relative RMS reduction), the held-out chi-square reduction and the
    BIC change; those are ``None`` for a candidate that was not fitted."""

    cause: str
    added: tuple[str, ...]
    rms_before: float
    result: FitResult = field(repr=False)
    rejected: str | None = None
    evidence: str = ""
    score: float | None = None
    rms_after: float | None = None
    gain: float | None = None
    bic_change: float | None = None
    heldout_chi2: float | None = None

    @property
    def fitted(self) -> bool:
        """The candidate was fitted (it has a held-out gain)."""
        return self.gain is not None

    @classmethod
    def not_fitted(cls, cause: str, added: tuple[str, ...], current: FitResult,
                   rms_before: float, why: str, score: float | None = None) -> "CandidateOutcome":
        """A candidate screened out or not tried, and why."""
        return cls(cause, added, rms_before, current, rejected=why,
                   score=None if score is None or not math.isfinite(score) else score)


@dataclass(frozen=True)
class Finding:
    """An accepted extension with its cause and evidence."""

    cause: str
    evidence: str
    added: tuple[str, ...]
    #: held-out RMS residual before and after (N, or channel scales) and the relative gain
    rms_before: float
    rms_after: float
    gain: float
    bic_change: float

    def to_dict(self) -> dict[str, Any]:
        return {"cause": self.cause, "evidence": self.evidence, "added": list(self.added),
                "rms_before": self.rms_before, "rms_after": self.rms_after,
                "gain": self.gain, "bic_change": self.bic_change}


@dataclass(frozen=True)
class Verdict:
    """Whether the final model explains the data: its residual over the measurement noise
    (``ratio``, explained when at most :data:`~estimate.diagnosis.scoring.NOISE_MARGIN`),
    and when it does not, where the residual concentrates and the best candidates that
    were rejected, in one sentence."""

    explained: bool
    ratio: float
    text: str
    concentrated: tuple[str, ...] = ()
    rejected: tuple[str, ...] = ()

    @classmethod
    def of(cls, evidence: Evidence, rounds: tuple[tuple[CandidateOutcome, ...], ...],
           findings: tuple[Finding, ...]) -> "Verdict":
        noise = evidence.noise
        ratio = noise.ratio
        figure = (f"the residual ({noise.residual:.3g} {noise.unit}) is {ratio:.2f} times the "
                  f"measurement noise ({noise.noise:.3g} {noise.unit})")
        if noise.within:
            model = "The extended analog" if findings else "The baseline analog"
            return cls(True, ratio, f"{model} explains the data: {figure}, within "
                                    f"{NOISE_MARGIN:.2f}.")
        where = [f"{f:.3g} Hz" for f in evidence.residual_frequencies]
        tried = [o for rnd in rounds for o in rnd if o.rejected is not None and o.fitted]
        tried += [o for rnd in rounds for o in rnd if o.rejected is not None and not o.fitted
                  and o.rejected.startswith("screened")]
        tried.sort(key=lambda o: -(o.gain if o.fitted else -1.0))
        rejected = tuple(f"{o.cause} ({o.rejected})" for o in tried[:3])
        text = (f"Unexplained: {figure}, more than {NOISE_MARGIN:.2f}"
                + (f", concentrated at {', '.join(where)}" if where else "")
                + ("; best rejected candidates: " + "; ".join(rejected) if rejected
                   else "; no candidate family or library term fits it")
                + ". Something the analog families do not describe is in the data.")
        return cls(False, ratio, text, tuple(where), rejected)


@dataclass(frozen=True)
class Diagnosis:
    """The outcome of :func:`estimate.diagnose`: the baseline and final fits with their
    evidence, the findings, every round's candidates, the fits made and the verdict."""

    baseline: FitResult
    baseline_evidence: Evidence
    findings: tuple[Finding, ...]
    final: FitResult
    final_evidence: Evidence
    rounds: tuple[tuple[CandidateOutcome, ...], ...]
    candidate_fits: int
    seconds: float
    notes: tuple[str, ...] = ()
    verdict: Verdict | None = None
    #: every fit of the diagnosis with its purpose, time and the budget that ended it
    fits: tuple[FitRecord, ...] = ()

    @property
    def budget_ended(self) -> tuple[FitRecord, ...]:
        """The fits a budget (iterations or time) ended."""
        return tuple(f for f in self.fits if f.ended_by)

    @property
    def unexplained(self) -> bool:
        """The final residual stays above the noise (see :class:`Verdict`)."""
        return self.verdict is not None and not self.verdict.explained

    def to_dict(self) -> dict[str, Any]:
        """The fixed-key JSON form written by ``slosh diagnose``."""
        base = self.baseline.to_dict()
        fin = self.final.to_dict()
        return {
            "baseline": {"model": base["model"], "rms_residual": self.baseline.rms_residual,
                         "parameters": base["parameters"]},
            "findings": [f.to_dict() for f in self.findings],
            "unexplained": self.unexplained,
            "verdict": None if self.verdict is None else {
                "explained": self.verdict.explained, "noise_ratio": self.verdict.ratio,
                "text": self.verdict.text, "concentrated": list(self.verdict.concentrated),
                "rejected": list(self.verdict.rejected)},
            "final": {"model": fin["model"], "parameters": fin["parameters"],
                      "derived": fin["derived"], "rms_residual": self.final.rms_residual,
                      "measurement": _measurement_dict(self.final)},
            "evidence": _evidence_dict(self.baseline_evidence),
            "candidates": [[{"cause": c.cause, "added": list(c.added), "gain": c.gain,
                             "bic_change": c.bic_change, "rms_before": c.rms_before,
                             "rms_after": c.rms_after, "rejected": c.rejected,
                             "score": c.score, "heldout_chi2_reduction": c.heldout_chi2}
                            for c in rnd] for rnd in self.rounds],
            "candidate_fits": self.candidate_fits,
            "seconds": self.seconds,
            "fits": [{"purpose": f.purpose, "budget": f.budget, "iterations": f.iterations,
                      "seconds": f.seconds, "status": f.status, "ended_by": f.ended_by}
                     for f in self.fits],
            "notes": list(self.notes),
        }


def _measurement_dict(res: FitResult) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for mm in res.problem.measurement:
        if isinstance(mm, SensorDelay):
            out["sensor_delay_s"] = mm.delay
    for name in ("rig.force_offset", "rig.force_drift", "rig.friction_viscous",
                 "rig.friction_coulomb"):
        if name in res.names:
            out[name] = res.value(name)
    lags = [n for n in res.names if n.split(":")[-1] == "rig.lag"]
    for name in lags:  # a stream lag per case ("<case>:rig.lag", s): the force stream late
        out[name] = res.value(name)
    if len(lags) == 1 and "sensor_delay_s" not in out:
        out["sensor_delay_s"] = res.value(lags[0])
    return out


def _evidence_dict(ev: Evidence) -> dict[str, Any]:
    trends = {t.quantity: {"amplitudes_rad": list(t.amplitudes), "values": list(t.values),
                           "slope": t.slope, "slope_stderr": t.slope_se, "text": t.text()}
              for t in (ev.damping_trend, ev.frequency_trend) if t is not None}
    return {
        "rms_residual": ev.rms_residual, "noise_rms": ev.noise_rms,
        "noise_ratio": ev.noise_ratio, "within_noise": ev.within_noise,
        "drive_frequency_hz": ev.drive_frequency, "sweep": ev.sweep,
        "residual_peaks": [{"frequency_hz": p.frequency, "amplitude": p.amplitude,
                            "coherence": p.coherence, "drive_harmonic": p.harmonic}
                           for p in ev.peaks],
        "drive_harmonics": {str(k): v for k, v in ev.harmonics.items()},
        "ljung_box": {"q": ev.ljung_box_q, "p_value": ev.ljung_box_p},
        "timing_skew": {"correlation": ev.skew_correlation, "implied_delay_s": ev.skew_delay},
        "frequency_vs_prediction": ev.frequency_ratio,
        "pinned": list(ev.pinned),
        "segments": [{"start_s": s.start, "stop_s": s.stop, "rms_angle": s.rms_angle,
                      "damping_ratio": s.damping_ratio, "damping_ratio_stderr": s.damping_se,
                      "frequency_hz": s.frequency_hz, "frequency_stderr": s.frequency_se}
                     for s in ev.segments],
        "amplitude_trends": trends,
    }
