"""The NLP of a fit assembled from its cases' terms: the decision vector (scaled
parameters, then per case its transcription's variables and carriage coefficients), the
constraints, the cost residuals, the derivative functions given to IPOPT, and the named
quantities read back at the solution (:class:`NlpOutputs`)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from ._sparse import evaluate
from .problem import FitProblem
from .terms import CaseTerms, case_terms
from .transcription import Transcription

if TYPE_CHECKING:
    import scipy.sparse as sps

    from .nlp import Hessian
    from .result import FitResult

__all__ = ["AssembledNlp", "NlpOutputs", "assemble_nlp"]


@dataclass(frozen=True)
class NlpOutputs:
    """What the NLP's error function gives at a solution, by name (per-case tuples follow
    the problem's cases; ``None`` where a case has no such quantity).

    Attributes
    ----------
    e : ndarray
        The residuals the covariance uses (the cost's, or ``simulated - measured`` for the
        ``"abs"`` cost), scaled.
    jacobian : scipy.sparse.csc_matrix
        ``de/dw`` (structural zeros kept).
    raw, report : ndarray
        ``simulated - measured`` per channel sample (N, N m) and as reports scale it.
    carriage : tuple
        The estimated carriage motion per case (stage inputs), or ``None``.
    displacement_residuals : tuple
        The estimated carriage's displacement residuals per case [m], or ``None``.
    states : tuple of ndarray
        The transcription's states per case (one column per node).
    coefficients : tuple
        The carriage spline's coefficients per case, or ``None``.
    """

    e: np.ndarray
    jacobian: "sps.csc_matrix"
    raw: np.ndarray
    report: np.ndarray
    carriage: tuple
    displacement_residuals: tuple
    states: tuple
    coefficients: tuple


def assemble_nlp(problem: FitProblem, transcription: Transcription, cost: str, kinds: list[str],
                 blocks_ok: bool, compile_: bool | None, warm_start: FitResult | None
                 ) -> tuple[AssembledNlp, list[CaseTerms]]:
    """The assembled NLP of ``problem`` and its per-case terms.

    Parameters
    ----------
    problem : FitProblem
        Cases, model and estimates.
    transcription : Transcription
        How the dynamics enter (multiple shooting, collocation).
    cost : {"squared", "abs"}
        The cost's name (:class:`~estimate.fitting.strategies.Cost`).
    kinds : list of str
        Each case's initial state: ``"rest"``, ``"steady"`` or ``"free"``.
    blocks_ok : bool
        Whether the constraint Jacobian may be assembled from per-interval blocks (not with
        the exact Hessian, which differentiates ``g`` twice).
    compile_ : bool or None
        Compile the per-interval functions to C; ``None``: when ``blocks_ok`` and a
        compiler exists.
    warm_start : FitResult or None
        A previous fit of the same cases whose states start the transcription.
    """
    if compile_ is None:
        from derive import c_compiler

        compile_ = blocks_ok and c_compiler() is not None
    scales = np.array([e.scale for e in problem.estimated])
    theta_s = ca.MX.sym("theta", len(problem.estimated))
    warm = _warm_starts(problem, warm_start)
    terms = [case_terms(problem, i, theta_s, transcription, cost, kinds[i],
                        blocks_ok, compile_, warm[i]) for i in range(len(problem.experiments))]
    rows = np.array([b.row(problem.names) * scales for b in problem.linear_bounds])
    upper = np.array([b.upper for b in problem.linear_bounds])
    return AssembledNlp.assemble(theta_s, problem.initial / scales, terms, rows, upper), terms



@dataclass(frozen=True)
class AssembledNlp:
    """The assembled NLP: decision vector ``w`` (scaled parameters first, then per case its
    transcription's variables and carriage coefficients), its start ``w0``, constraints
    ``g`` (= 0), cost residuals ``r`` with ``f = |r|^2 / (2 norm)``."""

    w: ca.MX
    w0: np.ndarray
    g: ca.MX
    r: ca.MX
    norm: float
    terms: tuple[CaseTerms, ...]
    free_states: tuple[int, ...]
    #: Linear bounds ``rows @ theta_scaled <= upper`` (the liquid mass budget), the last
    #: rows of ``g``.
    rows: np.ndarray
    upper: np.ndarray
    theta_s: ca.MX

    @property
    def n_linear(self) -> int:
        return int(self.upper.size)

    def constraint_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``lbg, ubg``: the dynamics' equalities, then the linear bounds."""
        n_eq = self.g.numel() - self.n_linear
        return (np.r_[np.zeros(n_eq), np.full(self.n_linear, -np.inf)],
                np.r_[np.zeros(n_eq), self.upper])

    @property
    def linear_g(self) -> ca.MX:
        return ca.mtimes(ca.DM(self.rows), self.theta_s) if self.n_linear else ca.MX(0, 1)

    @classmethod
    def assemble(cls, theta_s: ca.MX, theta0: np.ndarray, terms: list[CaseTerms],
                 rows: np.ndarray | None = None, upper: np.ndarray | None = None) -> "AssembledNlp":
        ws, w0s, free = [theta_s], [theta0], []
        offset = theta_s.numel()
        for term in terms:
            nb = term.block.w.numel()
            if term.free_initial_state:  # the free initial state acts as nx extra parameters
                nx = term.block.X.size1()
                free.extend(range(offset, offset + nx))
            # carriage coefficients are nuisance parameters: marginalised in the covariance
            free.extend(range(offset + nb, offset + nb + term.coef.numel()))
            ws += [term.block.w, term.coef]
            w0s += [term.block.w0, term.coef0]
            offset += nb + term.coef.numel()
        norm = float(np.mean(np.concatenate([t.scaled_measured for t in terms]) ** 2)) or 1.0
        n_r = sum(int(t.r.numel()) for t in terms)
        n_f = sum(t.scaled_measured.size for t in terms)
        norm *= n_r / max(n_f, 1)  # keep f = O(1) per sample when displacement terms join
        upper = np.zeros(0) if upper is None else np.asarray(upper, float)
        rows = np.zeros((0, theta_s.numel())) if rows is None or not upper.size else rows
        g = ca.vertcat(*[t.block.g for t in terms])
        if upper.size:
            g = ca.vertcat(g, ca.mtimes(ca.DM(rows), theta_s))
        return cls(ca.vertcat(*ws), np.concatenate(w0s), g, ca.vertcat(*[t.r for t in terms]),
                   norm, tuple(terms), tuple(free), rows, upper, theta_s)

    @property
    def f(self) -> ca.MX:
        return 0.5 * ca.sumsqr(self.r) / self.norm

    @cached_property
    def g_fast(self) -> ca.MX:
        """``g`` as IPOPT evaluates it: each block's ``g_fast`` (the compiled RK4 step when
        there is one, so CasADi cannot differentiate it)."""
        return ca.vertcat(*[t.block.g_fast for t in self.terms if t.block.g.numel()],
                          self.linear_g)

    @property
    def assembled_jac_r(self) -> bool:
        """Whether :attr:`jac_r` is assembled from the cases' blocks (not CasADi AD)."""
        return all(t.jacobian is not None for t in self.terms)

    @cached_property
    def jac_r(self) -> ca.MX:
        """``d r / d w``: assembled from the cases' blocks when each has them."""
        if not self.assembled_jac_r:
            return ca.jacobian(self.r, self.w)
        return ca.horzcat(ca.vertcat(*[t.jacobian[0] for t in self.terms]),
                          ca.diagcat(*[t.jacobian[1] for t in self.terms]))

    @cached_property
    def e(self) -> ca.MX:
        return ca.vertcat(*[t.e for t in self.terms])

    def bounds(self, est) -> tuple[np.ndarray, np.ndarray]:
        lbx = np.full(self.w.numel(), -np.inf)
        ubx = np.full(self.w.numel(), np.inf)
        lbx[: len(est)] = [e.lower / e.scale for e in est]
        ubx[: len(est)] = [e.upper / e.scale for e in est]
        return lbx, ubx

    def derivative_options(self, hessian: Hessian, blocks_ok: bool
                           ) -> tuple[dict, ca.MX, ca.MX | None]:
        """``(options, f, g)``: the options give ``jac_g`` assembled from per-interval
        blocks, the objective's gradient ``J_r^T r / norm`` from the assembled ``J_r`` and
        the Gauss-Newton ``hess_lag``. The Jacobians they share are evaluated once per
        iterate (:class:`OncePerPoint`), and then ``f`` and ``g`` are read from them too
        (IPOPT asks for f and g at the point where it then asks for their derivatives: one
        simulation per point, not three); else ``f`` is :attr:`f` and ``g`` ``None``."""
        opts: dict = {}
        f, g = self.f, None
        blocks = self.constraint_blocks(blocks_ok)
        jac_r = self.jac_r if (self.assembled_jac_r or hessian.kind == "gauss-newton") else None
        shared = [*(blocks or ()), *(() if jac_r is None else (jac_r,))]
        r = self.r
        if self.assembled_jac_r and blocks:
            from ._once import OncePerPoint

            # r too: the gradient's, not simulated a second time (40 ms of a 30,001-sample
            # fit's iterate)
            once = OncePerPoint("nlp_jacobians", ca.Function("jacobians", [self.w],
                                                             [*shared, r]))
            self._keep.append(once)  # alive as long as the solver that calls it
            *shared, r = once(self.w)
            if blocks:
                f, g = 0.5 * ca.sumsqr(r) / self.norm, shared[0]
        if blocks:
            opts["jac_g"] = ca.Function("nlp_jac_g", [self.w, ca.MX(0, 1)], shared[:2],
                                        ["x", "p"], ["g", "jac_g_x"])
        Jr = shared[-1] if jac_r is not None else None
        if self.assembled_jac_r:
            # f = |r|^2 / (2 norm): its gradient J_r^T r / norm from the assembled J_r,
            # not CasADi's reverse sweep through the mapped outputs and the carriage
            # spline (a 30,001-sample fit: 137 -> 51 ms per gradient)
            grad = ca.mtimes(r.T, Jr).T / self.norm  # no transpose of J_r
            f = 0.5 * ca.sumsqr(r) / self.norm
            opts["grad_f"] = ca.Function("nlp_grad_f", [self.w, ca.MX(0, 1)], [f, grad],
                                         ["x", "p"], ["f", "grad_f_x"])
        if hessian.kind == "gauss-newton":
            sigma = ca.MX.sym("sigma")
            lam = ca.MX.sym("lam", self.g.numel())
            H = sigma * ca.mtimes(Jr.T, Jr) / self.norm
            opts["hess_lag"] = ca.Function("nlp_hess_l", [self.w, ca.MX(0, 1), sigma, lam],
                                           [ca.triu(H)], ["x", "p", "lam_f", "lam_g"],
                                           ["triu_hess_gamma_x_x"])
        return opts, f, g

    @cached_property
    def _keep(self) -> list:
        return []

    def release_buffers(self) -> None:
        """Free the memory the solver's once-per-point Jacobians keep between calls."""
        for once in self._keep:
            once.release()

    def constraint_jacobian(self, blocks_ok: bool) -> ca.Function | None:
        """``w -> (g, dg/dw)`` assembled from per-interval blocks, or ``None`` (then CasADi
        differentiates ``g``)."""
        blocks = self.constraint_blocks(blocks_ok)
        if blocks is None:
            return None
        return ca.Function("nlp_jac_g", [self.w, ca.MX(0, 1)], list(blocks),
                           ["x", "p"], ["g", "jac_g_x"])

    def constraint_blocks(self, blocks_ok: bool) -> tuple[ca.MX, ca.MX] | None:
        """``(g, dg/dw)`` assembled from per-interval blocks, or ``None`` (then CasADi
        differentiates ``g``)."""
        blocks = [t.block for t in self.terms]
        if not (blocks_ok and all(b.jac_w is not None or b.g.numel() == 0 for b in blocks)):
            return None
        rows_t, locals_, g_jac = [], [], []
        for t in self.terms:
            b, nc = t.block, t.coef.numel()
            if b.g.numel():
                jc = b.jac_c if b.jac_c is not None else ca.MX(b.g.numel(), nc)
                rows_t.append(b.jac_theta)
                locals_.append(ca.horzcat(b.jac_w, jc))
                g_jac.append(b.g_jac)
            else:
                locals_.append(ca.MX(0, b.w.numel() + nc))
        if not rows_t:
            return None
        J = ca.horzcat(ca.vertcat(*rows_t), ca.diagcat(*locals_))
        gv = ca.vertcat(*g_jac)
        if self.n_linear:
            J = ca.vertcat(J, ca.horzcat(ca.DM(self.rows), ca.MX(self.n_linear,
                                                                 J.size2() - self.rows.shape[1])))
            gv = ca.vertcat(gv, self.linear_g)
        return gv, J

    def error_function(self, cost: str) -> ca.Function:
        """``w -> (e, de/dw, raw, report, carriage..., displacement residuals..., states...,
        coefficients...)``: what the covariance and the reports use
        (:meth:`outputs_at` names them)."""
        e = self.e
        same = all(t.e is t.r for t in self.terms)  # squared cost: reuse d r / d w
        raw = ca.vertcat(*[t.raw for t in self.terms])
        report = ca.vertcat(*[t.report for t in self.terms])
        extra = [t.carriage if t.carriage is not None else ca.MX(0, 1) for t in self.terms]
        xres = [t.displacement_residual if t.displacement_residual is not None else ca.MX(0, 1)
                for t in self.terms]
        jac = self.jac_r if same else ca.jacobian(e, self.w)
        # the compiled steps' states where there are (the same values: IPOPT's)
        states = [t.block.X if t.block.X_fast is None else t.block.X_fast for t in self.terms]
        coefs = [t.coef for t in self.terms]
        return ca.Function("residuals", [self.w],
                           [e, jac, raw, report, *extra, *xres, *states, *coefs])

    def outputs_at(self, w: np.ndarray, cost: str) -> NlpOutputs:
        """The residuals and per-case quantities at the decision vector ``w``, named
        (:meth:`error_function` gives them in order)."""
        out = evaluate(self.error_function(cost), w, sparse=(1,))
        terms, k = self.terms, len(self.terms)
        return NlpOutputs(
            e=out[0].ravel(), jacobian=out[1], raw=out[2].ravel(), report=out[3].ravel(),
            carriage=tuple(None if terms[i].carriage is None else out[4 + i]
                           for i in range(k)),
            displacement_residuals=tuple(
                None if terms[i].displacement_residual is None
                else out[4 + k + i].ravel() for i in range(k)),
            states=tuple(out[4 + 2 * k + i] for i in range(k)),
            coefficients=tuple(out[4 + 3 * k + i].ravel()
                               if terms[i].coef.numel() else None for i in range(k)))

    def initial_states(self, w: np.ndarray) -> tuple[np.ndarray, ...]:
        """Per case, the states at its first sample in the decision vector ``w``."""
        starts = ca.Function("starts", [self.w], [t.block.X[:, 0] for t in self.terms])(w)
        return (starts,) if len(self.terms) == 1 else tuple(starts)


def _warm_starts(problem: FitProblem, previous: FitResult | None) -> list:
    """Per case, where its variables start: a previous solution of the same case, or None."""
    from .terms import WarmStart

    out = []
    for i, exp in enumerate(problem.experiments):
        prev = None
        if previous is not None and i < len(previous.problem.experiments) and previous.states:
            old = previous.problem.experiments[i]
            if old.case.path == exp.case.path and old.case.n_samples == exp.case.n_samples:
                coefs = previous.carriage_coefficients[i] if previous.carriage_coefficients \
                    else None
                prev = WarmStart(old.derived.coordinates, previous.states[i], coefs)
        out.append(prev)
    return out
