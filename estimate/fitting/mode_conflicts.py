"""Fitted slosh modes that no longer stand for the tank's mode of their number.

A pendulum ``pN`` the record does not show still takes whatever lowers the cost: on a sine
record through a transducer model (one mode in the tank, ``fixed,p1,p2`` fitted), ``p2``
ended as a 5.1 Hz pendulum of 0.42 kg, ten times the tank's mode 2, driven far below its
frequency, where it is a second fixed mass: the fixed mass took 0.93 kg for 1.456 and its
interval (+/- 0.17 kg, local to that optimum) missed the truth by 3.1 standard errors. On
eighteen 6 s sine records from rest (one mode, 1.3 % force noise) ``p2`` took 0.2-0.6 kg
in half of them, its length at the edge of its band, hunting the noise near its frequency,
and the fixed mass's interval missed 1.5 kg in all of those. The covariance cannot say so
(it is local); the prediction can: a pendulum mass more than
:data:`~estimate.fitting.initial.PREDICTION_FACTOR` times its mode's predicted mass may
stand for something else, and the estimates that move with it would then be elsewhere.
Each such mass is a :class:`ModeConflict`: how every estimate moves when the mass is put at
the prediction (the regression in the covariance), which the intervals reach; reported as
a warning when the mass is that far above the prediction by more than two standard errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analogs.errors import InputError

from .initial import PREDICTION_FACTOR, predicted_values

__all__ = ["ModeConflict", "mode_conflicts", "mode_masses"]

#: Correlations at least this strong (in size) are named as moving with the mode.
STRONG = 0.7


@dataclass(frozen=True)
class ModeConflict:
    """A pendulum mass (estimate ``index``) above ``PREDICTION_FACTOR`` times its tank
    mode's ``predicted`` mass [kg]; ``message`` is the fit's warning when it is so by more
    than two standard errors (``None`` otherwise: the intervals still reach)."""

    index: int
    name: str
    predicted: float
    message: str | None

    def shift(self, theta: np.ndarray, cov: np.ndarray) -> np.ndarray:
        """How every estimate moves (SI units, estimates' order) when this mass is put at
        its mode's predicted mass and the others follow the regression in ``cov``
        (estimates held at a bound have zero rows there, and do not move): the linear
        answer of the fit with this mass fixed at the prediction."""
        i = self.index
        d = self.predicted - float(theta[i])
        out = np.zeros(theta.size)
        if cov[i, i] > 0:
            out = cov[:, i] / cov[i, i] * d
        out[i] = d
        return out


def mode_masses(problem) -> dict[int, tuple[str, float, float]]:
    """Per estimated pendulum mass of ``problem`` (its index among the estimates): the
    component ``pN``, and the tank's predicted mass [kg] and length [m] of mode N. Empty
    when the tank has no prediction."""
    if not problem.experiments:
        return {}
    try:
        predicted = predicted_values(problem.experiments[0].case, problem.model)
    except (InputError, ValueError, ArithmeticError):
        return {}
    out = {}
    for i, e in enumerate(problem.estimated):
        comp, local = e.parameter.split(".", 1) if "." in e.parameter else ("", "")
        if local != "mass" or not (comp.startswith("p") and comp[1:].isdigit()):
            continue
        m_pred, L_pred = predicted.get(f"{comp}.mass"), predicted.get(f"{comp}.length")
        if m_pred and L_pred and m_pred > 0:
            out[i] = (comp, float(m_pred), float(L_pred))
    return out


def mode_conflicts(problem, theta: np.ndarray, stderr: np.ndarray, cov: np.ndarray,
                   derived: dict[str, float]) -> list[ModeConflict]:
    """The estimated pendulum masses of ``problem`` (values ``theta``, standard errors
    ``stderr``, covariance ``cov``) above ``PREDICTION_FACTOR`` times the tank's
    prediction of their mode, with a warning for those above it by more than two standard
    errors; ``derived`` holds the fitted ``pN.frequency_hz``. Empty when the tank has no
    prediction. A mass at a bound (no standard error) is left out."""
    modes = mode_masses(problem)
    if not modes:
        return []
    g = problem.experiments[0].case.rig.gravity
    names = [e.name for e in problem.estimated]
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    out = []
    for i, (comp, m_pred, L_pred) in modes.items():
        m, se = float(theta[i]), float(stderr[i])
        if not (math.isfinite(se) and m > PREDICTION_FACTOR * m_pred):
            continue
        if not m - 2 * se > PREDICTION_FACTOR * m_pred:
            out.append(ModeConflict(i, names[i], float(m_pred), None))
            continue
        f_pred = math.sqrt(g / L_pred) / (2 * math.pi)
        f_fit = derived.get(f"{comp}.frequency_hz", math.nan)
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov[i] / (d[i] * d)
        movers = [(names[j], corr[j]) for j in np.argsort(-np.abs(np.nan_to_num(corr)))
                  if j != i and np.isfinite(corr[j]) and abs(corr[j]) >= STRONG
                  and not names[j].startswith(comp + ".")][:3]
        moves = ("; it moves with " + ", ".join(f"`{n}` (correlation {c:+.2f})" for n, c in movers)
                 + ", whose intervals reach as far as they move when it is put at the "
                 "prediction") if movers else ""
        out.append(ModeConflict(i, names[i], float(m_pred), (
            f"`{comp}` ended as a {f_fit:.3g} Hz pendulum of {m:.3g} +/- {se:.2g} kg, "
            f"{m / m_pred:.3g} x the tank's mode {comp[1:]} ({m_pred:.3g} kg at "
            f"{f_pred:.3g} Hz): it stands for something else in the record than that "
            f"mode{moves}. Fit without it, or run `slosh diagnose` to test whether the "
            "record shows it")))
    return out
