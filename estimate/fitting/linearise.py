"""What fitting a problem would gain, predicted without solving: its least-squares
objective linearised at the start, every variable but the parameters eliminated (one
sparse factorisation of the Gauss-Newton KKT matrix). The diagnosis screens candidate
families with it (:mod:`estimate.diagnosis.screening`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from ._sparse import scipy_csc
from .assembly import assemble_nlp
from .covariance import ReducedKKT
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
    #: the reduced KKT system at the start and its residuals ``e`` and constraint values
    kkt: ReducedKKT | None = field(default=None, repr=False, compare=False)
    residuals: np.ndarray | None = field(default=None, repr=False, compare=False)
    constraints: np.ndarray | None = field(default=None, repr=False, compare=False)

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

    @cached_property
    def _nuisance_solve(self):
        """``B -> K0^-1 B`` for many right-hand sides: SuperLU of the KKT block of every
        variable but the parameters (pivoted, so the saddle point needs no regularisation)."""
        kkt = self.kkt
        p = kkt.ntheta
        if kkt.n_primal + kkt.ng == 0:
            return lambda B: B
        Hrr = (kkt.Je[:, p:].T @ kkt.Je[:, p:]).tocsc()
        Gr = kkt.Jg[:, p:]
        K0 = sps.bmat([[Hrr, Gr.T], [Gr, None]], format="csc") if kkt.ng else Hrr
        return spla.splu(K0).solve

    def objectives(self, residuals: np.ndarray, free: tuple[str, ...]) -> np.ndarray:
        """The objective after one Gauss-Newton step from each column of ``residuals``
        (residual vectors ``e`` of other data, e.g. the recorded force shifted in time, at
        the same point): the parameters ``free`` and every variable but the other
        parameters (states through the linearised constraints, the carriage motion and free
        initial states) move. One multi-right-hand-side solve with the factorisation of the
        start; for columns equal to :attr:`residuals` the reduction is :meth:`score`'s."""
        kkt = self.kkt
        if kkt is None:
            raise ValueError("this Linearisation keeps no KKT system: make it with `linearise`")
        E = np.asarray(residuals, float).reshape(len(self.residuals), -1)
        p, m = kkt.ntheta, E.shape[1]
        b = -(kkt.Je.T @ E)
        g = np.zeros(kkt.ng) if self.constraints is None else self.constraints
        b_r = np.vstack([b[p:], np.repeat(-g[:, None], m, axis=1)])
        y = self._nuisance_solve(b_r)
        nuisance = np.sum(b[p:] * y[:kkt.n_primal], axis=0)
        bt = b[:p] - kkt.B.T @ y
        idx = [self.names.index(n) for n in free]
        x = np.linalg.lstsq(self.information[np.ix_(idx, idx)], bt[idx], rcond=1e-12)[0]
        return np.sum(E**2, axis=0) - nuisance - np.sum(bt[idx] * x, axis=0)


def linearise(problem: FitProblem, *, warm_start: FitResult | None = None,
              transcription: Transcription = MultipleShooting(),
              initial_state: str | None = None) -> Linearisation:
    """The :class:`Linearisation` of ``problem`` at its initial values, its states and
    carriage motion starting from ``warm_start`` (the current fit): what fitting it would
    gain, predicted without solving (one sparse factorisation)."""
    est = problem.estimated
    kinds = [initial_state or e.initial_state_kind for e in problem.experiments]
    nlp, _ = assemble_nlp(problem, transcription, "squared", kinds, True, False, warm_start)
    w0 = nlp.w0
    e, Je = ca.Function("e", [nlp.w], [nlp.e, nlp.jac_r])(w0)
    e, Je = np.asarray(e).ravel(), scipy_csc(Je)
    jac_g = nlp.constraint_jacobian(True)
    g, Jg = (jac_g(w0, []) if jac_g is not None
             else ca.Function("g", [nlp.w], [nlp.g, ca.jacobian(nlp.g, nlp.w)])(w0))
    # the dynamics only: the liquid mass budget's linear bound is an inequality (the last
    # rows), not a manifold the states follow
    n_eq = nlp.g.numel() - nlp.n_linear
    g, Jg = np.asarray(g).ravel()[:n_eq], scipy_csc(Jg)[:n_eq]
    kkt = ReducedKKT(Je, Jg, len(est))
    scales = np.array([x.scale for x in est])
    return Linearisation(problem.names, scales, problem.initial, float(e @ e),
                         kkt.gradient(e, g), kkt.information, kkt, e, g)
