"""A late force recording: a sensor delay (measurement model) placed where the objective's
profile over the delay, linearised at the current fit, is lowest, and refitted there.
Proposed on every single-channel record whose model has no delay or stream lag yet, when
the profile's predicted reduction is significant (:data:`~estimate.diagnosis.scoring.MIN_SCORE`,
as a screened term): not gated by the residual's correlation with the force's rate of
change, which a 20 ms lag on a transport record left at 0.1 ms."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from ...fitting.linearise import Linearisation, linearise
from ...fitting.measurement import SensorDelay as SensorDelayModel
from ...fitting.measurement import StreamLag
from ...fitting.result import FitResult
from ..scoring import MIN_SCORE, case_rows
from .base import Context, Family, Proposal, Score

__all__ = ["SensorDelay", "DelayProfile", "delay_profile", "DELAY_RANGE", "DELAY_STEP",
           "DELAY_TOL", "DELAY_FITS"]

#: Delays searched (s).
DELAY_RANGE = (0.0, 0.1)
#: Grid step (s) of the linearised delay profile, and the change of the delay (s) below
#: which refitting ends: 0.25 ms moves a 5 Hz force by 0.8 % of its amplitude.
DELAY_STEP = 5e-4
DELAY_TOL = 2.5e-4
#: At most this many fits of a sensor delay, each at the minimum of the profile linearised
#: at the previous one (or at the current fit).
DELAY_FITS = 3


@dataclass(frozen=True)
class DelayProfile:
    """The objective over a sensor delay, linearised at a fit (:func:`delay_profile`):
    trial ``delays`` (s), the objective at each (residuals in noise units) and its
    minimum, refined between grid points by a parabola."""

    delays: np.ndarray
    objective: np.ndarray
    best: float
    reduction: float


def delay_profile(res: FitResult, lin: Linearisation, measured: Sequence[np.ndarray],
                  delays: np.ndarray) -> DelayProfile:
    """Linearised profile of the objective over a sensor delay, without fitting.

    For every trial delay the recorded force ``measured`` (per case, before any delay) is
    advanced as :class:`estimate.fitting.measurement.SensorDelay` does, and the objective
    after one Gauss-Newton step from the fit ``res`` is computed with ``lin``, its
    linearisation (:meth:`estimate.fitting.linearise.Linearisation.objectives`: the
    parameters, the states and the estimated carriage motion all move; one solve for all
    delays). The data shift is exact and only the model's response is linearised, so near
    ``res`` the profile is close to the fitted one (a 20 ms skew came out at 20.0 ms from a
    fit without delay, fitted 20.2 ms). The samples within ``max(delays)`` of the end keep
    their residuals for every delay."""
    delays = np.asarray(delays, float)
    E = np.repeat(lin.residuals[:, None], delays.size, axis=1)
    for i, (m, w) in enumerate(zip(measured, res.weights)):
        t = np.asarray(res.problem.experiments[i].case.time, float)
        keep = (t + delays.max() <= t[-1]) & (w > 0)
        shifted = CubicSpline(t, np.asarray(m, float))(
            np.clip(t[keep][:, None] + delays[None, :], t[0], t[-1]))
        scale = res.problem.channel_scales(i)["force_x"]
        rows = case_rows(res, i).start + np.flatnonzero(keep)
        E[rows] += (np.asarray(res.measured[i])[keep][:, None] - shifted) * (w[keep] / scale)[:, None]
    cost = lin.objectives(E, tuple(n for n in res.names if n in lin.names))
    k = int(np.argmin(cost))
    best = float(delays[k])
    if 0 < k < delays.size - 1:  # parabola through the minimum and its neighbours
        c0, c1, c2 = cost[k - 1:k + 2]
        h = delays[k + 1] - delays[k]
        curv = c0 - 2 * c1 + c2
        if curv > 0:
            best += float(np.clip(0.5 * h * (c0 - c2) / curv, -h, h))
    return DelayProfile(delays, cost, best, float(lin.objective - cost[k]))


def _grid() -> np.ndarray:
    lo, hi = DELAY_RANGE
    return np.arange(lo, hi + 0.5 * DELAY_STEP, DELAY_STEP)


def _profile_at(fitter, at: FitResult, measured) -> DelayProfile:
    problem = fitter.problem(at.problem.model, at.problem.measurement,
                             dict(zip(at.names, at.values)))
    return delay_profile(at, linearise(problem, warm_start=at), measured, _grid())


def _delay_of(r: FitResult) -> float:
    return next(mm.delay for mm in r.problem.measurement if isinstance(mm, SensorDelayModel))


def _inside_range(r: FitResult) -> str | None:
    """Why the fitted delay is not physical (at the edge of :data:`DELAY_RANGE`), or None."""
    tau = _delay_of(r)
    if DELAY_RANGE[0] + 1e-3 <= tau <= DELAY_RANGE[1] - 5e-3:
        return None
    return f"the delay {1e3 * tau:.1f} ms is at the edge of the searched range"


class SensorDelay(Family):
    """A late force recording (a timing skew between the channels): a sensor delay on the
    measured force, placed by a linearised profile and refitted."""

    cause = "sensor_delay"

    def _timed(self, ctx: Context) -> bool:
        """The model already has a sensor delay or a stream lag."""
        return any(isinstance(m, (SensorDelayModel, StreamLag)) for m in ctx.measurement)

    def _profile(self, ctx: Context) -> DelayProfile | None:
        """The linearised profile at the current fit (made once a round), or ``None``."""
        if ctx.linearisation is None or self._timed(ctx):
            return None
        current = ctx.current
        return ctx.once("delay profile", lambda: delay_profile(
            current, ctx.linearisation, current.measured, _grid()))

    def _score(self, ctx: Context, profile: DelayProfile) -> float:
        return profile.reduction / max(ctx.current.residual_variance, 1e-300)

    def why_not(self, ctx: Context) -> str | None:
        if self._timed(ctx):
            return None
        profile = self._profile(ctx)
        if profile is None:
            return None
        score = self._score(ctx, profile)
        if score >= MIN_SCORE:
            return None
        if score <= 0.05:
            return (f"the objective's profile over the delay predicts no reduction (a score "
                    f"of {MIN_SCORE:.0f} is needed): no delay fits the record better")
        return (f"the objective's profile over the delay predicts a reduction of "
                f"{score:.1f} (needs {MIN_SCORE:.0f}); best delay {1e3 * profile.best:.1f} ms")

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        profile = self._profile(ctx)
        if profile is None or self._score(ctx, profile) < MIN_SCORE:
            return []
        current, ev = ctx.current, ctx.evidence
        measured = current.measured

        def fit(fitter, start: dict[str, float], warm: FitResult) -> FitResult:
            """Fit at the profile's minimum; profile again at that fit and refit while the
            delay moves more than :data:`DELAY_TOL`. Returns the best fit."""
            prof, at, best, tried = profile, warm, None, []
            for _ in range(DELAY_FITS):
                tau = round(prof.best, 5)
                if any(abs(tau - t) < DELAY_TOL for t in tried):
                    break
                tried.append(tau)
                res = fitter(ctx.model, ctx.measurement + (SensorDelayModel(tau),), start,
                             warm=at, purpose=f"sensor_delay at {1e3 * tau:.1f} ms")
                if best is None or (res.converged, -res.objective) > (best.converged, -best.objective):
                    best = res
                if not res.converged or fitter.time_left() <= 0:
                    break
                at = res
                prof = _profile_at(fitter, at, measured)
            return best

        def describe(r: FitResult) -> str:
            return (f"the objective's profile over a delay of the recorded force is lowest "
                    f"away from zero (residual correlation with dF/dt "
                    f"{ev.skew_correlation:+.2f}) -> a timing skew; a sensor delay of "
                    f"{1e3 * _delay_of(r):.1f} ms on the measured force")

        return [Proposal(self.cause, ("sensor_delay",), ctx.model, ctx.measurement, {},
                         score=self._score(ctx, profile),
                         fit=fit, extra_parameters=1, plausible=_inside_range, describe=describe)]
