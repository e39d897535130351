"""What fitting a problem would gain, predicted without solving: its least-squares
objective linearised at the start, every variable but the parameters eliminated (one
sparse factorisation of the Gauss-Newton KKT matrix). The diagnosis screens candidate
families with it (:mod:`estimate.diagnosis.screening`)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .nlp import _setup
from .problem import FitProblem
from .result import FitResult
from .transcription import MultipleShooting, Transcription

__all__ = ["Linearisation", "linearise"]


@dataclass(frozen=True)
class Linearisation:
    """A problem's weighted least-squares objective around its start, every variable but the
    parameters eliminated (states through the dynamics, the carriage motion and free
    initial states re-optimised): ``objective`` there, the reduced gradient ``gradient``
    (``-dS/dtheta / 2``) and ``information`` ``S`` of the scaled parameters, in the order
    of ``names``, with their ``scales`` and start ``values``.

    :meth:`score` gives what freeing some parameters would gain."""

    names: tuple[str, ...]
    scales: np.ndarray
    values: np.ndarray
    objective: float
    gradient: np.ndarray
    information: np.ndarray

    def score(self, free: tuple[str, ...]) -> tuple[float, dict[str, float]]:
        """The objective reduction of one Gauss-Newton step in the parameters ``free`` (the
        others held at their start values), and the parameters after it (by name, unscaled).

        At the optimum of a model, with a candidate's new parameters at their null values,
        the reduction over the residual variance is the score (Lagrange multiplier)
        statistic of the candidate: chi-square with as many degrees of freedom as new
        parameters when the candidate explains nothing."""
        idx = [self.names.index(n) for n in free]
        S = self.information[np.ix_(idx, idx)]
        b = self.gradient[idx]
        x = np.linalg.lstsq(S, b, rcond=1e-12)[0]
        after = {n: float((self.values[i] / self.scales[i] + xi) * self.scales[i])
                 for n, i, xi in zip(free, idx, x)}
        return float(b @ x), after


def linearise(problem: FitProblem, *, warm_start: FitResult | None = None,
              transcription: Transcription = MultipleShooting(),
              initial_state: str | None = None) -> Linearisation:
    """The :class:`Linearisation` of ``problem`` at its initial values, its states and
    carriage motion starting from ``warm_start`` (the current fit): what fitting it would
    gain, predicted without solving (one sparse factorisation)."""
    from .covariance import ReducedKKT

    est = problem.estimated
    kinds = [initial_state or e.initial_state_kind for e in problem.experiments]
    nlp, _ = _setup(problem, transcription, "squared", kinds, True, False, warm_start)
    w0 = nlp.w0
    e, Je = ca.Function("e", [nlp.w], [nlp.e, nlp.jac_r])(w0)
    e, Je = np.asarray(e).ravel(), Je.sparse()
    jac_g = nlp.constraint_jacobian(True)
    g, Jg = (jac_g(w0, []) if jac_g is not None
             else ca.Function("g", [nlp.w], [nlp.g, ca.jacobian(nlp.g, nlp.w)])(w0))
    g = np.asarray(g).ravel()
    kkt = ReducedKKT(Je, Jg.sparse(), len(est))
    scales = np.array([x.scale for x in est])
    return Linearisation(problem.names, scales, problem.initial, float(e @ e),
                         kkt.gradient(e, g), kkt.information)
