"""A mode the record does not show: its mass goes to zero, and then nothing in the record
determines its other parameters (a massless pendulum's length, damper and spring change no
force). IPOPT then wanders along those directions without end: a ``fixed,p1,p2`` fit of a
record with one mode took all 300 iterations (17-39 s on 3,001 samples, 466 s on 30,001)
to finish "not converged" at a point no better than the one it had at iteration 16.

Here such a fit stops when its cost has stalled with a vanished mass (:func:`stall_stop`;
status :data:`STALLED`, not converged), and is refitted with the vanished component's
other parameters held (:func:`held_refit`): at their starts (the prediction), and its
damper at zero, since a damper on a vanishing mass is a mode ever more damped, whose force
is not linear in the mass (IPOPT then converged linearly: 45 iterations where 9 do). The
mass stays estimated, on its bound at zero, with the one-sided interval of the data for a
mode of those parameters.

A second mode the record does not determine can also keep its mass and wander along a
ridge of the cost (an overdamped element trading with the fixed mass). That is not
stopped: a correct one-mode model on a weak-spring record walks its length-spring ridge
the same way for dozens of iterations before it converges, and a rule that stopped the
one and held its parameters stopped and held the other too. But a fit that did not
converge (out of iterations, or diverged) with such a pendulum far heavier than its tank
mode (more than ``PREDICTION_FACTOR`` times: driven far below its frequency it is a second
fixed mass, and takes the fixed mass's share) is refitted from its start with that
pendulum's other parameters held as a vanished one's: on 6 s sweeps of a one-mode tank
(13 draws) five such fits had ended with the fixed mass at 0.0001-0.99 kg for 1.5, and
then converged within 0.5 % of it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .initial import PREDICTION_FACTOR
from .mode_conflicts import mode_masses
from .problem import FitProblem

__all__ = ["HELD_STATUSES", "STALLED", "STALL_ITERATIONS", "STALL_WINDOW", "VANISHED_SHARE",
           "held_refit", "held_value", "stall_stop"]

#: A component's mass has vanished when it is below this share of its start.
VANISHED_SHARE = 0.01
#: A fit has stalled when its least cost fell by less than one residual variance over the
#: last ``STALL_WINDOW`` iterations, counted from at least ``STALL_ITERATIONS``.
STALL_WINDOW, STALL_ITERATIONS = 10, 15
#: The status of a fit stopped so (not converged).
STALLED = "Stalled"
#: The statuses of the fits :func:`held_refit` looks at: stalled, out of iterations, or
#: diverged (IPOPT's ``Invalid_Number_Detected``: its estimates are where it was last finite).
HELD_STATUSES = (STALLED, "Maximum_Iterations_Exceeded", "Invalid_Number_Detected")


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


def stall_stop(problem: FitProblem, residuals: int
               ) -> Callable[[Sequence[float], np.ndarray], bool]:
    """The iteration callback's test to stop IPOPT, from the costs (``|r|^2``) of the
    iterations so far and the current estimates: a component's mass has vanished and the cost has
    stalled (its least fell by less than one residual variance, ``|r|^2 / residuals``,
    over :data:`STALL_WINDOW` iterations, the current cost within that of the least: a
    change of one in chi-square, below what any parameter the record determines would
    make)."""
    masses = _components(problem)

    def stop(costs: Sequence[float], theta: np.ndarray) -> bool:
        if not masses or len(costs) <= max(STALL_ITERATIONS, STALL_WINDOW):
            return False
        best = min(costs)
        tol = best / max(residuals, 1)
        return (min(costs[:-STALL_WINDOW]) - best < tol and costs[-1] - best < tol
                and bool(_vanished(problem, theta, masses)))

    return stop


def held_value(name: str, start: float) -> float:
    """The value a vanished component's parameter ``name`` is held at: its start, a
    damper's 0 (module docstring)."""
    return 0.0 if name.endswith(".damping") else float(start)


def _too_heavy(problem: FitProblem, theta: np.ndarray, masses) -> list[int]:
    """The pendulum masses above ``PREDICTION_FACTOR`` times their tank mode's prediction
    (:mod:`estimate.fitting.mode_conflicts`)."""
    modes = mode_masses(problem)
    return [j for j in masses if j in modes and theta[j] > PREDICTION_FACTOR * modes[j][1]]


def held_refit(problem: FitProblem, values: Sequence[float], status: str, iterations: int
               ) -> tuple[FitProblem, str] | None:
    """``(problem, note)`` for the refit of a fit that did not converge (its estimates
    ``values``, IPOPT ``status`` and ``iterations``): ``problem`` with the other
    parameters of every component whose mass vanished held (:func:`held_value`), the
    remaining estimates started at ``values``; or, when none vanished but a pendulum's mass
    ended far above its tank mode's (a mode the record does not excite, driven far below
    its frequency: a second fixed mass, free to wander in frequency), that pendulum's
    other parameters held likewise and every estimate started anew; ``None`` when
    neither."""
    theta = np.asarray(values, float)
    masses = _components(problem)
    gone = _vanished(problem, theta, masses)
    heavy = [] if gone else _too_heavy(problem, theta, masses)
    if not gone and not heavy:
        return None
    est = problem.estimated
    held, parts = problem, []
    for j in gone or heavy:
        others = [est[k] for k in masses[j]]
        values_held = [held_value(e.name, e.initial) for e in others]
        for e, v in zip(others, values_held):
            held = held.holding(e.name, v)
        kept = ", ".join(f"{e.name} (held at {v:.4g})" for e, v in zip(others, values_held))
        parts.append(f"{est[j].name} went to {theta[j]:.3g} (its start {est[j].initial:.4g}): "
                     f"the record shows no such mode and does not determine {kept}" if gone
                     else f"{est[j].name} went to {theta[j]:.3g} kg, over {PREDICTION_FACTOR:g} "
                     f"x its tank mode's: the record does not determine {kept}")
    note = "; ".join(parts) + f". The fit did not converge ({status} after {iterations} iterations)"
    if heavy:  # the estimates it reached are the far mass's: every one starts anew
        return held, note + " and was refitted from its start with those held; the masses stay estimated."
    start = {e.name: float(v) for e, v in zip(est, theta)}
    return held.with_initial(start), note + (" and was refitted with those held; the masses "
                                             "stay estimated.")
