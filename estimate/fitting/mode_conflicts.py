"""Fitted slosh modes that no longer stand for the tank's mode of their number.

A pendulum ``pN`` the record does not show still takes whatever lowers the cost: on a sine
record through a transducer model (one mode in the tank, ``fixed,p1,p2`` fitted), ``p2``
ended as a 5.1 Hz pendulum of 0.42 kg, ten times the tank's mode 2, driven far below its
frequency, where it is a second fixed mass: the fixed mass took 0.93 kg for 1.456 and its
interval (+/- 0.17 kg, local to that optimum) missed the truth by 3.1 standard errors. The
covariance cannot say so (it is local); the prediction can: a determined pendulum mass more
than :data:`~estimate.fitting.initial.PREDICTION_FACTOR` times its mode's predicted mass is
reported, with the estimates it moves with.
"""

from __future__ import annotations

import math

import numpy as np

from analogs.errors import InputError

from .initial import PREDICTION_FACTOR, predicted_values

__all__ = ["mode_conflicts"]

#: Correlations at least this strong (in size) are named as moving with the mode.
STRONG = 0.7


def mode_conflicts(problem, theta: np.ndarray, stderr: np.ndarray, cov: np.ndarray,
                   derived: dict[str, float]) -> list[str]:
    """Warnings for the estimated pendulum masses of ``problem`` (values ``theta``, standard
    errors ``stderr``, covariance ``cov``) above ``PREDICTION_FACTOR`` times the tank's
    prediction of their mode by more than two standard errors; ``derived`` holds the fitted
    ``pN.frequency_hz``. Empty when the tank has no prediction."""
    if not problem.experiments:
        return []
    case = problem.experiments[0].case
    try:
        predicted = predicted_values(case, problem.model)
    except (InputError, ValueError, ArithmeticError):
        return []
    g = case.rig.gravity
    names = [e.name for e in problem.estimated]
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    out = []
    for i, e in enumerate(problem.estimated):
        comp, local = e.parameter.split(".", 1) if "." in e.parameter else ("", "")
        if local != "mass" or not (comp.startswith("p") and comp[1:].isdigit()):
            continue
        m_pred, L_pred = predicted.get(f"{comp}.mass"), predicted.get(f"{comp}.length")
        if not m_pred or not L_pred or m_pred <= 0:
            continue
        m, se = float(theta[i]), float(stderr[i])
        if not (math.isfinite(se) and m - 2 * se > PREDICTION_FACTOR * m_pred):
            continue
        f_pred = math.sqrt(g / L_pred) / (2 * math.pi)
        f_fit = derived.get(f"{comp}.frequency_hz", math.nan)
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov[i] / (d[i] * d)
        movers = [(names[j], corr[j]) for j in np.argsort(-np.abs(np.nan_to_num(corr)))
                  if j != i and np.isfinite(corr[j]) and abs(corr[j]) >= STRONG
                  and not names[j].startswith(comp + ".")][:3]
        moves = ("; it moves with " + ", ".join(f"`{n}` (correlation {c:+.2f})" for n, c in movers)
                 + ", whose intervals hold only if it is real") if movers else ""
        out.append(f"`{comp}` ended as a {f_fit:.3g} Hz pendulum of {m:.3g} +/- {se:.2g} kg, "
                   f"{m / m_pred:.3g} x the tank's mode {comp[1:]} ({m_pred:.3g} kg at "
                   f"{f_pred:.3g} Hz): it stands for something else in the record than that "
                   f"mode{moves}. Fit without it, or run `slosh diagnose` to test whether the "
                   "record shows it")
    return out
