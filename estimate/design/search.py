"""The search: every drive family on a coarse grid of its design variables, a local solve
(SciPy) from the best grid point, then the best of the families and the standard
alternatives judged by the information the fit itself would have.

Every candidate is first scaled to the rig's limits, then down to the largest swing
allowed (the root of the predicted peak swing, SciPy's ``brentq``), and only then scored:
no candidate breaks a limit, and none is favoured by a swing the analog would not survive.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import brentq, minimize, minimize_scalar

from analogs.errors import InputError

from .drives import (
    LATERAL_FAMILIES,
    LIMIT_MARGIN,
    LateralDrive,
    LinearChirp,
    Peaks,
    SpinDrive,
    SteadySine,
)
from .information import (
    Prediction,
    Record,
    fit_information,
    motion_inputs,
    rig_inputs,
    sensitivities,
    swing_angles,
)
from .problem import DesignProblem, with_spin

__all__ = ["Candidate", "Runner", "Search", "band", "evaluate", "family_search", "judge", "search",
           "spin_bounds", "spin_case", "standard_alternatives", "LIMIT_MARGIN"]

#: Grid points of a 1-D family (2-D families: about 1.5 times as many pairs).
GRID = 14
#: Function evaluations of a local solve.
LOCAL_EVALUATIONS = 12


@dataclass(frozen=True)
class Candidate:
    """A ``drive`` scaled to the limits and the swing limit, with its predicted peak
    ``swing`` (rad), what its amplitude is ``limited_by``, its ``score`` (smaller is
    better), the ``surrogate`` prediction (drive exact, noise white) from its predicted
    ``record`` and ``noise`` per channel, and, once judged, the ``prediction`` from the
    fit's own information; ``label`` names it in reports (a family, an alternative)."""

    drive: LateralDrive | SpinDrive
    swing: float
    limited_by: str
    score: float
    surrogate: Prediction = field(repr=False)
    record: Record = field(repr=False)
    noise: np.ndarray = field(repr=False)
    prediction: Prediction | None = field(default=None, repr=False)
    label: str = ""

    @property
    def best(self) -> Prediction:
        """The fit's prediction when made, else the surrogate's."""
        return self.prediction if self.prediction is not None else self.surrogate


def spin_case(problem: DesignProblem, drive: SpinDrive):
    """The design case with the ``[rig.spin]`` schedule of ``drive``."""
    return with_spin(problem.case, rate=drive.spin_rate,
                     nutation_frequency=drive.nutation_frequency, nutation_angle=drive.cone_angle,
                     spin_up=drive.spin_up, nutation_ramp=drive.nutation_ramp,
                     nutation_start=drive.spin_up, spin_angle=None, spin_rate=None,
                     nutation_phase=None, cone_angle=None)


class Runner:
    """Simulations of one drive at any amplitude scale, for the problem's model or another
    (``derived`` with its parameter ``values`` and estimated ``names``). A lateral drive's
    motion is linear in its scale, so it is evaluated once, on the half-interval grid (the
    RK4 stage times, twice the rig's rate for the peaks); a spinning-rig drive's schedule is
    rebuilt."""

    def __init__(self, problem: DesignProblem, drive, *, derived=None, values=None,
                 names=None) -> None:
        self.problem, self.drive = problem, drive
        self.dm = problem.derived if derived is None else derived
        self.values = problem.values if values is None else values
        self.names = problem.names if names is None else tuple(names)
        if isinstance(drive, LateralDrive):
            t = problem.time
            self.unit = replace(drive, scale=1.0).motion(np.linspace(t[0], t[-1], 2 * t.size - 1))

    def inputs(self, scale: float):
        if isinstance(self.drive, LateralDrive):
            return motion_inputs(scale * self.unit)
        from ..data.experiment import experiment
        from ..data.models import model_for_case

        case = spin_case(self.problem, replace(self.drive, scale=scale))
        exp = experiment(case, model_for_case(self.problem.model, case))
        self.dm = exp.derived
        self.values = {k: v for k, v in self.problem.values.items()
                       if k in exp.derived.parameter_names}
        return rig_inputs(exp.excitation, self.problem.time, exp.derived.nu)

    def ratios(self) -> dict[str, float]:
        """Peaks of the unit-scale lateral motion over the limits."""
        return Peaks(*map(float, np.abs(self.unit).max(axis=1))).ratios(self.problem.limits)

    def _sens(self):
        n = self.problem.time.size - 1
        return sensitivities(self.dm, self.names, self.problem.channels, n)

    def swing(self, scale: float) -> float:
        u = self.inputs(scale)
        X = self._sens().states(self.values, u, self.problem.time)
        return _peak_swing(self.dm, X)

    def record(self, scale: float) -> Record:
        u = self.inputs(scale)
        return self._sens()(self.values, u, self.problem.time)


def _peak_swing(dm, states: np.ndarray) -> float:
    return max((float(s.max()) for s in swing_angles(dm, states).values()), default=0.0)


def evaluate(problem: DesignProblem, drive, *, label: str = "",
             scale: float | None = None) -> Candidate | None:
    """``drive`` scaled to the limits (or to ``scale``, if smaller) and then to the swing
    limit, scored by the surrogate information; ``None`` when even a thousandth of that
    amplitude swings beyond the limit."""
    run = Runner(problem, drive)
    if isinstance(drive, SpinDrive):
        top, limited = 1.0 if scale is None else min(scale, 1.0), "cone_angle"
    else:
        limited, worst = max(run.ratios().items(), key=lambda kv: kv[1])
        if not worst > 0:
            return None
        top = (1 - LIMIT_MARGIN) / worst
        if scale is not None and scale < top:
            top, limited = scale, "given"
    s, cap = top, problem.max_swing
    peak = run.swing(top)
    if peak > cap:
        # the swing grows about in proportion with the amplitude: try that first, and
        # solve for the root only when it misses by more than 5 %
        s = 0.99 * top * cap / peak
        at = run.swing(s)
        if not 0.95 * cap <= at <= cap:
            lo = 1e-3 * top
            if at < cap:
                lo, hi = s, top
            else:
                hi = s
                if run.swing(lo) >= cap:
                    return None
            s = 0.99 * brentq(lambda x: run.swing(x) - cap, lo, hi, xtol=0.02 * s,
                              rtol=0.02, maxiter=12)
            while run.swing(s) > cap:  # brentq's last point may lie above
                s *= 0.99
        limited = "swing"
    record = run.record(s)
    noise = problem.new_noise(record.rms())
    pred = Prediction.of(problem.names, problem.theta, problem.prior,
                         record.information(noise), problem.targets, problem.scales)
    return Candidate(replace(drive, scale=s), _peak_swing(run.dm, record.states), limited,
                     pred.criterion(problem.criterion), pred, record, noise, label=label)


def judge(problem: DesignProblem, cand: Candidate) -> Candidate:
    """``cand`` with the prediction from the information the fit would have
    (:func:`~.information.fit_information`)."""
    drive = cand.drive
    if isinstance(drive, SpinDrive):
        from ..data.models import model_for_case

        case = spin_case(problem, drive)
        model = model_for_case(problem.model, case)
        x = None
    else:
        case, model = problem.case, problem.model
        x = drive.motion(problem.time)[0]
    known = {p.name for p in model.parameters}
    values = {k: v for k, v in problem.values.items() if k in known}
    F = fit_information(case, model, values, problem.names, cand.record, x, cand.noise,
                        problem.record_displacement_noise)
    pred = Prediction.of(problem.names, problem.theta, problem.prior, F, problem.targets,
                         problem.scales)
    return replace(cand, prediction=pred)


def spin_bounds(problem: DesignProblem) -> list[tuple[float, float]]:
    """Bounds of the spinning-rig search: spin rate from a fifth of the limit to the limit
    (rad/s), coning frequency within +/- its limit (Hz)."""
    lim = problem.limits
    return [(0.2 * lim.spin_rate, lim.spin_rate),
            (-lim.nutation_frequency, lim.nutation_frequency)]


def band(problem: DesignProblem) -> tuple[float, float]:
    """Frequency band of the lateral search (Hz): from a fifth of the lowest mode to three
    times the highest (0.2-5 Hz without a mode), below a tenth of the rig's rate."""
    f = list(problem.frequencies.values())
    lo, hi = (0.2 * min(f), 3.0 * max(f)) if f else (0.2, 5.0)
    return lo, min(hi, problem.rate / 10)


@dataclass(frozen=True)
class Search:
    """The outcome: the finalists ``ranked`` by the fit's prediction (best first), the
    standard ``alternatives``, the prediction ``before`` a new record, the ``evaluations``
    (drives simulated) and the ``seconds`` taken."""

    ranked: tuple[Candidate, ...]
    alternatives: tuple[Candidate, ...]
    before: Prediction
    evaluations: int
    seconds: float


def family_search(problem: DesignProblem, family, bounds, counter: list[int],
                  score=evaluate):
    """A grid over the design variables of ``family`` within ``bounds``, then a local solve
    from its best point: SciPy's bounded Brent between the neighbours of the best point
    (1-D) or Powell within the bounds (2-D). ``score(problem, drive, label=...)`` returns a
    candidate with a ``score`` (smaller is better) or ``None``; ``counter[0]`` counts the
    drives scored. Returns the best candidate seen, or ``None``."""
    nvar = len(family.variables)
    found: dict[tuple, Candidate] = {}

    def objective(v) -> float:
        counter[0] += 1
        v = tuple(float(x) for x in np.atleast_1d(v))
        drive = family(problem.limits, problem.duration, **dict(zip(family.variables, v)))
        c = score(problem, drive, label=family.title)
        if c is None:
            return math.inf
        found[v] = c
        return c.score

    if nvar == 1:
        ((lo, hi),) = bounds
        grid = [(x,) for x in np.geomspace(lo, hi, GRID)]
    else:
        k = max(int(round(math.sqrt(GRID * 2.5))), 4)
        axes = [np.geomspace(lo, hi, k) if lo > 0 else np.linspace(lo, hi, k)
                for lo, hi in bounds]
        grid = [(a, b) for a in axes[0] for b in axes[1] if not math.isclose(a, b)]
        if family.family == "stepped":  # the order of two held frequencies hardly matters
            grid = [(a, b) for a, b in grid if a < b]
    scores = [objective(v) for v in grid]
    if not found:
        return None
    i = int(np.argmin(scores))
    if nvar == 1:
        a, b = grid[max(i - 1, 0)][0], grid[min(i + 1, len(grid) - 1)][0]
        minimize_scalar(lambda x: objective([x]), bounds=(a, b), method="bounded",
                        options={"maxiter": LOCAL_EVALUATIONS, "xatol": 2e-3 * grid[i][0]})
    else:
        minimize(objective, np.array(grid[i], float), method="Powell", bounds=bounds,
                 options={"maxfev": LOCAL_EVALUATIONS, "xtol": 1e-3})
    return min(found.values(), key=lambda c: c.score)


def search(problem: DesignProblem, *, families: tuple[str, ...] | None = None,
           finalists: int = 3) -> Search:
    """Search every drive family of the rig of the design ``problem`` (lateral:
    ``families``, default all of
    :data:`~.drives.LATERAL_FAMILIES`), judge the best ``finalists`` and the standard
    alternatives by the fit's information, and rank them (best first)."""
    t0 = time.perf_counter()
    counter = [0]
    best: list[Candidate] = []
    if problem.case.test.rig == "spinning":
        c = family_search(problem, SpinDrive, spin_bounds(problem), counter)
        best += [c] if c is not None else []
    else:
        names = tuple(families or LATERAL_FAMILIES)
        unknown = [f for f in names if f not in LATERAL_FAMILIES]
        if unknown:
            raise InputError(f"--families: unknown {', '.join(map(repr, unknown))}; known: "
                             + ", ".join(LATERAL_FAMILIES))
        lo, hi = band(problem)
        for name in names:
            fam = LATERAL_FAMILIES[name]
            c = family_search(problem, fam, [(lo, hi)] * len(fam.variables), counter)
            best += [c] if c is not None else []
    if not best:
        raise InputError("no drive keeps every pendulum's swing below the swing limit "
                         f"{problem.max_swing:g} rad on this rig, even at a thousandth of "
                         "the amplitude its limits allow")
    best.sort(key=lambda c: c.score)
    judged = sorted((judge(problem, c) for c in best[:finalists]),
                    key=lambda c: c.prediction.criterion(problem.criterion))
    alts = tuple(judge(problem, c) for c in standard_alternatives(problem, judged[0]))
    before = Prediction.of(problem.names, problem.theta, problem.prior, None, problem.targets,
                           problem.scales)
    return Search(tuple(judged), alts, before, counter[0], time.perf_counter() - t0)


def standard_alternatives(problem: DesignProblem, recommended: Candidate) -> list[Candidate]:
    """What a test engineer runs by habit, by the same rules (limits, swing limit): a 1-5 Hz
    linear sweep of the same duration and peak acceleration as the recommendation, and a
    sine at the predicted first-mode frequency (lateral rig only)."""
    if problem.case.test.rig != "lateral":
        return []
    out = []
    peak = recommended.drive.peaks(problem.rate).acceleration
    sweep = LinearChirp(problem.limits, problem.duration, start=1.0, end=5.0)
    unit = sweep.peaks(problem.rate).acceleration
    c = evaluate(problem, sweep, scale=peak / unit, label="1-5 Hz sweep, same peak acceleration")
    out += [c] if c is not None else []
    if problem.frequencies:
        f1 = min(problem.frequencies.values())
        c = evaluate(problem, SteadySine(problem.limits, problem.duration, frequency=f1),
                     label="sine at the predicted frequency")
        out += [c] if c is not None else []
    return out
