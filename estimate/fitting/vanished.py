"""A mode the record does not show, or does not show clearly: its mass goes to zero, and
then nothing in the record determines its other parameters (a massless pendulum's length,
damper and spring change no force), or its estimates trade with the others along a ridge
of the cost. IPOPT then wanders without end: a ``fixed,p1,p2`` fit of a record with one
mode took all 300 iterations (17-39 s on 3,001 samples, 466 s on 30,001) to finish "not
converged" at a point no better than the one it had at iteration 16.

Here such a fit stops when its cost has stalled (:func:`stall_stop`; status
:data:`STALLED`, not converged), and a fit that did not converge is refitted with the
undetermined component's other parameters held (:func:`held_refit`): at their starts (the
prediction), a vanished component's damper at zero, since a damper on a vanishing mass is
a mode ever more damped, whose force is not linear in the mass (IPOPT then converged
linearly: 45 iterations where 9 do). The masses stay estimated: a vanished one on its
bound at zero, with the one-sided interval of the data for a mode of those parameters.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .problem import FitProblem

__all__ = ["HELD_STATUSES", "RIDGE_ITERATIONS", "RIDGE_WINDOW", "STALLED", "STALL_ITERATIONS", "STALL_WINDOW",
           "VANISHED_SHARE", "WANDER_SHARE", "held_refit", "held_value", "stall_stop"]

#: A component's mass has vanished when it is below this share of its start.
VANISHED_SHARE = 0.01
#: A fit has stalled when its least cost fell by less than one residual variance over the
#: last ``window`` iterations, counted from at least ``iterations``. With a vanished mass
#: (10, 15) it stops; without, (20, 40), it stops when an estimate still moved by more than
#: :data:`WANDER_SHARE` of its scale over the window. Measured on ``fixed,p1,p2`` fits of
#: one-mode records, which ran 300 iterations: the second mode made an overdamped element
#: whose damper moved by 20-1000 times its start over every 20 iterations, or IPOPT
#: bounced between points 1-2 residual variances above the least, the second mode's
#: estimates moving by 0.14-0.6 of their scales; a fit that converged slowly (73
#: iterations) had its cost flat from the 20th but moved by less than 0.004 from the 40th.
STALL_WINDOW, STALL_ITERATIONS = 10, 15
RIDGE_WINDOW, RIDGE_ITERATIONS = 20, 40
WANDER_SHARE = 0.05
#: The status of a fit stopped so (not converged).
STALLED = "Stalled"
#: The statuses of the fits :func:`held_refit` looks at: stalled, or out of iterations (a
#: fit that diverged, IPOPT's ``Invalid_Number_Detected``, wandered too, but not along a
#: ridge of the cost: holding its modes made a 60 s spinning-rig fit worse).
HELD_STATUSES = (STALLED, "Maximum_Iterations_Exceeded")


def _components(problem: FitProblem) -> dict[int, list[int]]:
    """Per component with an estimated mass and other estimated parameters (all shared
    between the cases): the index of its mass among the estimates, and of the others."""
    groups: dict[str, list[int]] = {}
    for j, e in enumerate(problem.estimated):
        if e.case is None and "." in e.name:
            groups.setdefault(e.name.split(".", 1)[0], []).append(j)
    out = {}
    for prefix, idx in groups.items():
        mass = [j for j in idx if problem.estimated[j].name == f"{prefix}.mass"]
        if mass and len(idx) > 1:
            out[mass[0]] = [j for j in idx if j != mass[0]]
    return out


def _vanished(problem: FitProblem, theta: np.ndarray, masses) -> list[int]:
    est = problem.estimated
    return [j for j in masses
            if theta[j] - max(est[j].lower, 0.0) < VANISHED_SHARE * abs(est[j].initial)]


def _moved(problem: FitProblem, thetas) -> np.ndarray:
    """How far each estimate moved over the last :data:`RIDGE_WINDOW` iterates, in its
    scale."""
    scales = np.array([abs(e.scale) or 1.0 for e in problem.estimated])
    return np.ptp(np.asarray(thetas[-RIDGE_WINDOW:], float), axis=0) / scales


def stall_stop(problem: FitProblem, residuals: int
               ) -> Callable[[Sequence[float], Sequence[np.ndarray]], bool]:
    """The iteration callback's test to stop IPOPT, from the costs (``|r|^2``) and
    estimates of the iterations so far: its cost has stalled (:data:`STALL_WINDOW`; one
    residual variance, ``|r|^2 / residuals``, is a change of one in chi-square, below what
    any parameter the record determines would make) with a vanished mass, or with
    estimates still wandering (:data:`RIDGE_WINDOW`)."""
    masses = _components(problem)

    def stalled(costs: Sequence[float], window: int, iterations: int) -> bool:
        if len(costs) <= max(iterations, window):
            return False
        best = min(costs)
        return min(costs[:-window]) - best < best / max(residuals, 1)

    def stop(costs: Sequence[float], thetas: Sequence[np.ndarray]) -> bool:
        if masses and stalled(costs, STALL_WINDOW, STALL_ITERATIONS) \
                and costs[-1] - min(costs) < min(costs) / max(residuals, 1) \
                and _vanished(problem, thetas[-1], masses):
            return True
        return stalled(costs, RIDGE_WINDOW, RIDGE_ITERATIONS) \
            and bool(np.max(_moved(problem, thetas)) > WANDER_SHARE)

    return stop


def held_value(name: str, start: float, vanished: bool) -> float:
    """The value an undetermined component's parameter ``name`` is held at: its start; a
    damper's 0 when the component's mass vanished (module docstring)."""
    return 0.0 if vanished and name.endswith(".damping") else float(start)


def held_refit(problem: FitProblem, values: Sequence[float], history, status: str,
               iterations: int) -> tuple[FitProblem, str] | None:
    """``(problem, note)`` for the refit of a fit that did not converge (its estimates
    ``values``, iterates ``history``, IPOPT ``status`` and ``iterations``): ``problem``
    with the other parameters of every component whose mass vanished or whose estimates
    wandered over the last iterations held (:func:`held_value`), the remaining estimates
    started at ``values``; ``None`` when there is no such component."""
    theta = np.asarray(values, float)
    masses = _components(problem)
    gone = set(_vanished(problem, theta, masses))
    history = np.asarray(history, float)
    wandering = set()
    if history.ndim == 2 and len(history) >= RIDGE_WINDOW:
        moved = _moved(problem, history) > WANDER_SHARE
        wandering = {j for j, others in masses.items() if moved[[j, *others]].any()}
    if not gone | wandering:
        return None
    est = problem.estimated
    held, parts = problem, []
    for j in sorted(gone | wandering):
        others = [est[k] for k in masses[j]]
        values_held = [held_value(e.name, e.initial, j in gone) for e in others]
        for e, v in zip(others, values_held):
            held = held.holding(e.name, v)
        kept = ", ".join(f"{e.name} (held at {v:.4g})" for e, v in zip(others, values_held))
        why = (f"{est[j].name} went to {theta[j]:.3g} (its start {est[j].initial:.4g}): the "
               "record shows no such mode" if j in gone else
               f"the estimates of {est[j].name.split('.', 1)[0]} wandered without changing "
               "the cost: the record does not show that mode clearly")
        parts.append(f"{why} and does not determine {kept}")
    start = {e.name: float(v) for e, v in zip(est, theta)}
    note = ("; ".join(parts) + f". The fit did not converge ({status} after {iterations} "
            "iterations) and was refitted with those held; the masses stay estimated.")
    return held.with_initial(start), note
