"""A start from the record's first part, for a long record whose fit did not converge.

A fit's path from the first stage's start grows harder with the record: a 60 s, 100 Hz
spinning-rig record (pendulum and rotor, six channels) diverged at iteration 26, where the
same rig's 20 s record converged in 24. Fitted on its first 20 s (24 iterations), then on
the whole record from those estimates, it converged in 3 more, to the truth. Records
whose carriage motion is estimated are not cut (their spline covers the whole record).
"""

from __future__ import annotations

from dataclasses import replace

from ..data.experiment import experiment
from .problem import FitProblem

__all__ = ["SEGMENT_MIN_SAMPLES", "first_part"]

#: The first part holds a third of the longest record, and at least this many samples; a
#: record shorter than twice this is not cut.
SEGMENT_MIN_SAMPLES = 1000


def first_part(problem: FitProblem) -> tuple[FitProblem, str] | None:
    """``(problem on the first part of every case, what it is)``, or ``None`` when no case
    is long enough or a case's carriage motion is estimated."""
    longest = max(x.case.time.size for x in problem.experiments)
    if longest < 2 * SEGMENT_MIN_SAMPLES or any(c is not None for c in problem.carriage):
        return None
    n = max(longest // 3, SEGMENT_MIN_SAMPLES)

    def cut(case):
        columns = {k: v[:n] for k, v in case.columns.items()}
        return replace(case, time=case.time[:n], columns=columns,
                       displacement=None if case.displacement is None else case.displacement[:n],
                       force=None if case.force is None else case.force[:n])

    exps = tuple(experiment(cut(x.case), problem.model) for x in problem.experiments)
    weights = tuple(None if w is None else w[:n] for w in problem.weights)
    noise = tuple(None if r is None else replace(r, force=r.force[:n]) for r in problem.noise)
    seconds = max(float(x.case.time[-1] - x.case.time[0]) for x in exps)
    return (replace(problem, experiments=exps, weights=weights, noise=noise),
            f"the first {n} samples ({seconds:.3g} s)")
