"""The diagnosis's fits: every problem built with the diagnosed cases' held-out weights and
input mode, every fit under an iteration and CPU-time budget that scales with the record,
and a log of what each fit was for, how long it took and which budget, if any, ended it."""

from __future__ import annotations

import time
from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np

from analogs import Model

from ..data.case import Case
from ..fitting.measurement import MeasurementModel
from ..fitting.nlp import fit
from ..fitting.problem import FitProblem
from ..fitting.result import FitResult
from ..fitting.stability import RK4_MARGIN
from .scoring import far_from_noise

__all__ = ["Budget", "FitRecord", "Fitter", "BUDGETS", "SECONDS_PER_SAMPLE",
           "SECONDS_PER_SPINNING_SAMPLE"]


@dataclass(frozen=True)
class Budget:
    """What one kind of fit may spend: IPOPT iterations, and CPU seconds per fitted sample
    (all cases and channels), at least ``min_seconds``."""

    kind: str
    iterations: int
    seconds_per_sample: float
    min_seconds: float = 2.0

    def seconds(self, samples: int) -> float:
        """The CPU-time budget (s) of a fit of ``samples`` samples."""
        return max(self.min_seconds, self.seconds_per_sample * samples)

    def options(self, samples: int) -> dict[str, object]:
        """IPOPT options of this budget."""
        return {"ipopt.max_iter": self.iterations, "ipopt.max_cpu_time": self.seconds(samples)}


#: The budgets: a cold fit (the baseline, a start from the prediction) converges in 10-60
#: iterations; a candidate warm-started on the same states at the current fit and the
#: point its score gives converges in well under 40 (one that does not is not what the data
#: want) unless the current fit is itself far from the data (``"far"``: more than twice the
#: noise, where a missing element has bent the estimates); a candidate with new states
#: (another mode) starts from a simulation and needs 20-60; six-channel spinning-rig fits
#: have six times the residuals and start farther.
#: The time budgets are 5-10 times what such fits take on 3001 samples (0.5-2 s).
BUDGETS = {
    "cold": Budget("cold", 300, 6e-3),
    "warm": Budget("warm", 40, 3e-3),
    "far": Budget("far", 100, 5e-3),
    "new states": Budget("new states", 100, 5e-3),
    "spinning": Budget("spinning", 150, 1e-2),
}
#: CPU-time budget of a whole diagnosis per fitted sample (s), at least 20 s: 45 s for 30 s
#: at 100 Hz; when it is spent, the candidates not yet fitted are not tried (the report
#: says so). CPU time, not wall time: the same record gets the same diagnosis on a busy
#: machine.
SECONDS_PER_SAMPLE = 0.015
#: The same for the six channels of a spinning-rig record, per sample and channel: its fits
#: take 5-10 times longer per residual (a rotary oscillator's diagnosis of 20 s took
#: minutes): 480 s for 20 s at 100 Hz.
SECONDS_PER_SPINNING_SAMPLE = 0.04
#: A pendulum's mass is kept above this share of its initial one in a fit from a
#: prediction or a scan (:func:`_stable`): a pendulum whose mass goes to zero leaves its
#: damper free, and a heavy damper on a tiny bob is a stiff system RK4 cannot step (a
#: baseline without the spring of a diaphragm record went there, its RK4 states
#: overflowed and MUMPS reallocated memory for minutes).
MIN_MASS_SHARE = 0.1
#: ... and its damper below the value where one RK4 step of the sample interval ``h`` on
#: the lightest, shortest pendulum the bounds allow has ``h c / (m L^2)`` =
#: :data:`~estimate.fitting.stability.RK4_MARGIN` (the rotor's bound uses the same; RK4 is
#: stable below ~2.8 on a real eigenvalue). On the 8-inch sphere at 100 Hz that is a
#: damping ratio of about 0.5 at the predicted mass of the first mode.
#: IPOPT statuses that mean a budget ended the fit.
_ENDED_BY = {"Maximum_Iterations_Exceeded": "iterations", "Maximum_CpuTime_Exceeded": "time"}


@dataclass(frozen=True)
class FitRecord:
    """One fit of a diagnosis: what it was for, its budget's kind, iterations, seconds,
    IPOPT status and which budget ended it (``"iterations"``, ``"time"`` or ``None``)."""

    purpose: str
    budget: str
    iterations: int
    seconds: float
    status: str
    ended_by: str | None

    def text(self) -> str:
        ended = f", ended by its {self.ended_by} budget" if self.ended_by else ""
        return (f"{self.purpose}: {self.iterations} iterations, {self.seconds:.1f} s "
                f"({self.budget} budget){ended}")


def _stable(prob: FitProblem, hold: dict[str, float], pendulums: Collection[str]
            ) -> FitProblem:
    """``prob`` with the mass and damper of each pendulum named in ``pendulums`` bounded
    (:data:`MIN_MASS_SHARE` of its initial mass, :data:`RK4_MARGIN`) on the
    lateral rig: a cold start's initial values are the prediction, a new mode's its scan's.
    Without them a second mode's candidate started from a poor scan (4.8 Hz, 0.089 kg for
    a 3.8 Hz, 0.06 kg mode) took its bob towards the mass's lower bound under a free
    damper and its fit ran 23 minutes of IPOPT iterations over a 15 s budget (the budget
    is checked between iterations)."""
    from dataclasses import replace

    from analogs import Pendulum

    est = {e.name: e for e in prob.estimated}
    h = min(e.case.sample_interval for e in prob.experiments)
    new = {}
    for comp in prob.model.components:
        if not isinstance(comp, Pendulum) or comp.name not in pendulums:
            continue
        m, c = est.get(f"{comp.name}.mass"), est.get(f"{comp.name}.damping")
        length = est.get(f"{comp.name}.length")
        L = length.lower if length is not None else hold.get(f"{comp.name}.length")
        if m is None or L is None or c is None:
            continue
        m_lo = max(m.lower, MIN_MASS_SHARE * m.initial)
        c_hi = min(c.upper, RK4_MARGIN * m_lo * L**2 / h)
        if c_hi > c.lower:
            new |= {m.name: replace(m, lower=m_lo),
                    c.name: replace(c, upper=c_hi, initial=min(c.initial, c_hi))}
    if not new:
        return prob
    return replace(prob, estimated=tuple(new.get(e.name, e) for e in prob.estimated))


def _new_pendulums(model: Model, warm: FitResult | None) -> set[str]:
    """The pendulums of ``model`` whose mass ``warm`` did not estimate (a new mode; every
    pendulum of a cold start, ``warm`` None)."""
    from analogs import Pendulum

    fitted = set(warm.names) if warm is not None else set()
    return {c.name for c in model.components if isinstance(c, Pendulum)
            and f"{c.name}.mass" not in fitted}


class Fitter:
    """Builds and fits problems of the diagnosed cases with fixed held-out weights, under
    the budgets of :data:`BUDGETS`, and logs every fit (:attr:`log`)."""

    def __init__(self, cases: Sequence[Case], weights: Sequence[np.ndarray] | None,
                 input_mode: str, cutoff: float | None, bar=None) -> None:
        self.cases, self.weights = list(cases), weights
        self.input, self.cutoff = input_mode, cutoff
        self.bar = bar  # a progress bar counting the fits, or None
        self.log: list[FitRecord] = []
        #: parameters held in every problem (an accepted candidate's, e.g. a diaphragm's
        #: pendulum length) and what each fit held, by the fit's id
        self.held: dict[str, float] = {}
        self._holds: dict[int, dict[str, float]] = {}
        self.extra = 0  # fits made elsewhere (segment refits)
        # fitted residuals: six channels on the spinning rig
        self.samples = sum(int(c.time.size) * (6 if c.test.rig == "spinning" else 1)
                           for c in cases)
        self.lateral = all(c.test.rig == "lateral" for c in cases)
        self.started = time.process_time()

    @property
    def count(self) -> int:
        """Fits made so far."""
        return len(self.log) + self.extra

    @property
    def budget(self) -> float:
        """The diagnosis's CPU-time budget (s, :data:`SECONDS_PER_SAMPLE`)."""
        rate = SECONDS_PER_SAMPLE if self.lateral else SECONDS_PER_SPINNING_SAMPLE
        return max(20.0, rate * self.samples)

    def time_left(self) -> float:
        """CPU seconds left of the diagnosis's budget."""
        return self.budget - (time.process_time() - self.started)

    def accept(self, result: FitResult) -> None:
        """Hold from now on what the accepted fit ``result`` held."""
        self.held = dict(self._holds.get(id(result), self.held))

    def problem(self, model: Model, measurement: Sequence[MeasurementModel], initial,
                bounds=None, *, weights="default", hold=None,
                stable: Collection[str] = ()) -> FitProblem:
        """The fit problem of the diagnosed cases (held-out weights unless ``weights`` is
        given; what an accepted candidate holds held); ``stable``: the pendulums that get
        the stability bounds (:data:`MIN_MASS_SHARE`, :data:`RK4_MARGIN`). No stream lag: the
        sensor-delay family names one (:mod:`.families.delay`)."""
        w = self.weights if weights == "default" else weights
        cutoff = self.cutoff if self.input == "filtered" else "auto"
        hold = {**self.held, **(hold or {})}
        bounds = {k: v for k, v in (bounds or {}).items() if k not in hold}
        prob = FitProblem.build(self.cases, model, measurement=tuple(measurement), weights=w,
                                bounds=bounds, hold=hold, force_cutoff_hz=cutoff,
                                input=self.input, lag="none")
        known = {e.name for e in prob.estimated}
        prob = prob.with_initial({k: v for k, v in initial.items() if k in known})
        return _stable(prob, hold, stable) if stable else prob

    def __call__(self, model: Model, measurement: Sequence[MeasurementModel], initial,
                 bounds=None, *, weights="default", warm: FitResult | None = None,
                 purpose: str = "fit", hold=None) -> FitResult:
        if self.bar is not None:
            self.bar.update()
        # a cold start may wander where RK4 cannot step: bounded; a warm start is near a
        # fit, and the bounds cost it (a whole-record fit warm-started from a second mode's
        # ran 40 iterations off it with the damper's bound, 5 without)
        prob = self.problem(model, measurement, initial, bounds, weights=weights, hold=hold,
                            stable=_new_pendulums(model, warm))
        if not all(len(e.channels) == 1 for e in prob.experiments):
            budget = BUDGETS["spinning"]
        elif warm is None:
            budget = BUDGETS["cold"]
        elif all(a.derived.coordinates == b.derived.coordinates
                 for a, b in zip(prob.experiments, warm.problem.experiments)):
            budget = BUDGETS["far" if far_from_noise(warm) else "warm"]
        else:
            budget = BUDGETS["new states"]
        # a warm start is in the current fit's valley, whose own fit (the baseline, cold)
        # had the refit without the liquid bound: a candidate that ends on the bound is not
        # fitted again without it (a record whose analog holds all the liquid spent 0.8 s
        # per candidate on refits it discarded). A candidate the record does not determine
        # is judged as fitted, not refitted with parts of it held or from a part of the
        # record.
        res = fit(prob, progress=False, solver_options=budget.options(self.samples),
                  warm_start=warm, unbounded_retry=warm is None, hold_undetermined=False,
                  segment_start=False)
        self.log.append(FitRecord(purpose, budget.kind, res.iterations, res.seconds, res.status,
                                  _ENDED_BY.get(res.status)))
        self._holds[id(res)] = {**self.held, **(hold or {})}
        return res
