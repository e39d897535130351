"""Estimation as one NLP with exact derivatives: IPOPT through CasADi.

Decision variables are the scaled parameters plus the states at the nodes of the chosen
transcription; the cost is the sum of squared force residuals (or the seed's
``sum((|E| - |S|)^2)``). After the solve, the residual sensitivity reduced to the parameters
(:mod:`estimate.fitting.covariance`) gives the Gauss-Newton covariance and the
identifiability check.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cached_property

import casadi as ca
import numpy as np
import scipy.sparse as sps

from analogs.errors import InputError

from ..data.case import KNOWN_INITIAL_STATES
from ..interrupts import surfacing
from ._progress import Recorder, progress_printer
from ._sparse import scipy_csc
from .budget import BUDGET_RTOL
from .covariance import reduced_jacobian, uncertainty
from .noise_figures import case_figures, model_error_factor, reweighed
from .problem import FitProblem
from .result import FitResult, derived_quantities
from .terms import CaseTerms, case_terms
from .transcription import MultipleShooting, Transcription

__all__ = ["LOW_R_SQUARED", "fit", "Hessian"]

#: A fit whose R^2 (fraction of the measurement's variance the model explains) is below this
#: says so in a warning: a force column of pure noise fits "converged" with R^2 near 0.
LOW_R_SQUARED = 0.1

#: Iterations a fit that ended on a liquid bound gives its refit without the bound, at least
#: (twice the bounded fit's otherwise; see :func:`_without_linear_bounds`).
FREE_RETRY_MIN_ITERATIONS = 40
_IPOPT_DEFAULTS = {
    # tol 1e-6 (IPOPT's 1e-8 by default): the estimates move by < 1e-5 standard errors
    # between the two on six records from rest (1e-4 moved one by 0.04), 5 % fewer iterations
    "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-6,
    "ipopt.max_iter": 300, "ipopt.mu_strategy": "adaptive", "ipopt.linear_solver": "mumps",
    # QAMD orders the parameters' dense rows of the KKT matrix last: MUMPS's analysis
    # 48 -> 14 ms and every factorisation cheaper (a 3001-sample fit 0.55 -> 0.48 s)
    "ipopt.mumps_pivot_order": 6,
    # MUMPS solves these KKT systems accurately: no residual check and refinement of every
    # step (8 % of a fit; the same iterates to 1e-12 of a standard error on six records)
    "ipopt.fast_step_computation": "yes",
    # a long record's objective sums 1e4 squares: its last digits are round-off, and a
    # stream lag's bilinear residual leaves the dual infeasibility a hair above 1e-6 while
    # the line search finds nothing to gain (a 6,900-sample transport record: stuck at
    # 1.4e-6 from iteration 10, "Error_In_Step_Computation" at 13). Four iterations within
    # 1e-5 end the fit as "Solved_To_Acceptable_Level" instead.
    "ipopt.acceptable_tol": 1e-5, "ipopt.acceptable_iter": 4,
}
_IPOPT_HINTS = {
    "Maximum_Iterations_Exceeded": "raise `ipopt.max_iter` in solver_options, or start closer "
                                    "(check [prediction] and the drive frequency)",
    "Restoration_Failed": "the initial guess is far from feasible: check the excitation and the "
                          "initial values",
    "Infeasible_Problem_Detected": "bounds exclude every solution: widen `bounds`",
    "Invalid_Number_Detected": "a parameter reached a value where the model is undefined: "
                               "tighten bounds",
}


@dataclass(frozen=True)
class Hessian:
    """Hessian of the Lagrangian given to IPOPT: ``"gauss-newton"`` (J_r^T J_r of the
    residuals, cheaper and positive semidefinite) or ``"exact"`` (CasADi AD)."""

    kind: str = "gauss-newton"

    def __post_init__(self) -> None:
        if self.kind not in ("gauss-newton", "exact"):
            raise InputError(f"Hessian kind must be 'gauss-newton' or 'exact', got {self.kind!r}")


def fit(problem: FitProblem, *, transcription: Transcription = MultipleShooting(),
        hessian: Hessian = Hessian(), cost: str = "squared", initial_state: str | None = None,
        solver_options: Mapping[str, object] | None = None,
        progress: bool | None = None, robust_start: bool = True,
        compile_: bool | None = None, warm_start: FitResult | None = None,
        balance: bool = True, _free_retry: bool = True) -> FitResult:
    """Estimate the parameters of ``problem``.

    Parameters
    ----------
    problem : FitProblem
        Cases, model and the parameters to estimate (:meth:`FitProblem.build`).
    transcription : MultipleShooting or Collocation
        How the dynamics enter the NLP (default: multiple shooting, one RK4 step per sample).
    hessian : Hessian
        ``Hessian("gauss-newton")`` (default) or ``Hessian("exact")``.
    cost : {"squared", "abs"}
        ``"squared"``: sum of squared force residuals (N^2). ``"abs"``: the seed's
        ``sum((|E| - |S|)^2)``, with a smooth absolute value (filtered input only).
        Residuals, RMS, R^2 and the covariance of the result are those of
        ``simulated - measured`` for either cost.
    initial_state : {"rest", "steady", "free"}, optional
        Where the analog starts in every case: at rest; ``"steady"``, at the relative
        equilibrium under the rig motion at the first sample (a pendulum on its cone on a
        spinning table, a rotor turning with the tank), tied to the parameters by equality
        constraints (:mod:`estimate.fitting.steady`); ``"free"``, estimated with the
        parameters (and marginalised in the covariance). Default: each case's ``[test]
        initial_state`` (``"rest"`` when absent).
    solver_options : mapping, optional
        Options passed to ``casadi.nlpsol`` (e.g. ``{"ipopt.max_iter": 500}``).
    progress : bool, optional
        Print iteration and cost live; default: only when stderr is a terminal.
    compile_ : bool, optional
        Compile the per-interval RK4 value-and-Jacobian function to C (cached on disk by
        its hash, reused for any case and record length). Default: when a C compiler is
        available and the Hessian is Gauss-Newton (multiple shooting only).
    robust_start : bool, default True
        Initialise crank speed corrections from the force spectrum and flywheel angles
        from a grid over their bounds (:func:`estimate.fitting.initial.crank_start`).
    warm_start : FitResult, optional
        A previous fit of the same cases (e.g. of a smaller model): its states start the
        transcription where the coordinates agree and its estimated carriage motion starts
        this one's. The parameters start at ``problem``'s initial values.
    balance : bool, default True
        When an estimated carriage motion's displacement residuals come out many times
        their assumed noise while the force's do not (a planned path given as the
        displacement), refit once with the displacement noise rescaled
        (:mod:`estimate.fitting.balance`), from this fit's solution.

    Returns
    -------
    FitResult
        Estimates with standard errors, correlations, identifiability, derived quantities,
        cost, residuals, solver status and the parameter trajectories over iterations.
    """
    if cost not in ("squared", "abs"):
        raise InputError(f"cost must be 'squared' or 'abs', got {cost!r}")
    if cost == "abs" and any(c is not None for c in problem.carriage):
        raise InputError("cost='abs' compares force magnitudes only, so it cannot tell the "
                         "carriage motion's sign: build the problem with input='filtered' "
                         "(`slosh fit --cost abs --input filtered`)")
    if initial_state not in (None, *KNOWN_INITIAL_STATES):
        raise InputError(f"initial_state must be one of {', '.join(map(repr, KNOWN_INITIAL_STATES))} "
                         f"(or None: each case's `[test] initial_state`), got {initial_state!r}")
    kinds = [initial_state or e.initial_state_kind for e in problem.experiments]
    if progress is None:
        progress = sys.stderr.isatty()
    t_start = time.perf_counter()
    problem.check()
    if robust_start:
        from .initial import crank_start

        start = crank_start(problem)
        if start:
            problem = problem.with_initial(start)
    est = problem.estimated
    scales = np.array([e.scale for e in est])
    # the exact Hessian differentiates g twice: keep g an AD-able expression then
    blocks_ok = hessian.kind == "gauss-newton"
    nlp, terms = _setup(problem, transcription, cost, kinds, blocks_ok, compile_, warm_start)
    opts = dict(_IPOPT_DEFAULTS)
    opts.update(nlp.derivative_options(hessian, blocks_ok))
    recorder = Recorder(nlp.w.numel(), nlp.g.numel(), len(est), scales, 2 * nlp.norm,
                         progress_printer(problem.names) if progress else None)
    opts["iteration_callback"] = recorder
    g = nlp.g
    if "jac_g" in opts:
        # IPOPT gets g and its Jacobian from the per-interval functions (compiled when a
        # compiler exists), and CasADi builds no AD of g: nothing asks for it once the
        # multipliers of the (absent) NLP parameters are not computed
        g = nlp.g_fast
        opts.update({"no_nlp_grad": True, "calc_lam_p": False})
    opts.update(dict(solver_options or {}))
    solver = ca.nlpsol("fit", "ipopt", {"x": nlp.w, "f": nlp.f, "g": g}, opts)
    lbx, ubx = nlp.bounds(est)
    lbg, ubg = nlp.constraint_bounds()
    with surfacing():  # an interrupt inside IPOPT is an interruption, not a non-convergence
        sol = solver(x0=nlp.w0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    if progress:
        print(file=sys.stderr)
    w_opt = np.asarray(sol["x"]).ravel()
    # IPOPT may leave a bounded variable a hair outside its bound (its bound_relax_factor)
    theta = np.clip(w_opt[: len(est)] * scales, [e.lower for e in est], [e.upper for e in est])
    out = nlp.error_function(cost)(w_opt)
    k = len(terms)
    _, Jg = solver.get_function("nlp_jac_g")(w_opt, [])
    Je, Jg = scipy_csc(out[1]), scipy_csc(Jg)
    Jg = Jg[: Jg.shape[0] - nlp.n_linear]  # the dynamics; the linear bounds are the masses'
    J = reduced_jacobian(Je, Jg, len(est), scales, list(nlp.free_states))
    carriage = tuple(None if terms[i].carriage is None else np.asarray(out[4 + i])
                     for i in range(k))
    xres = tuple(None if terms[i].displacement_residual is None
                 else np.asarray(out[4 + k + i]).ravel() for i in range(k))
    states = tuple(np.asarray(out[4 + 2 * k + i]) for i in range(k))
    coefs = tuple(np.asarray(out[4 + 3 * k + i]).ravel() if terms[i].coef.numel() else None
                  for i in range(k))
    starts = ca.Function("starts", [nlp.w], [t.block.X[:, 0] for t in terms])(w_opt)
    starts = (starts,) if k == 1 else tuple(starts)
    initial_states = tuple(
        dict(zip(e.derived.states, np.asarray(x, float).ravel().tolist()))
        for e, x in zip(problem.experiments, starts))
    result = _result(problem, theta, solver.stats(), recorder, terms,
                     *(np.asarray(out[j]).ravel() for j in (0, 2, 3)), J, Je, Jg, t_start,
                     transcription, cost, carriage, xres, states, coefs, tuple(kinds),
                     initial_states)
    if result.converged and result.active_bounds and problem.linear_bounds and _free_retry:
        # the free fit gets a few times the bounded one's iterations: one that wants more
        # mass than the liquid walks far (a diagnosis baseline lacking two effects: 300
        # iterations, 24 s, to be discarded)
        budget = {**dict(solver_options or {}), "ipopt.max_iter": min(
            int(dict(solver_options or {}).get("ipopt.max_iter", _IPOPT_DEFAULTS["ipopt.max_iter"])),
            max(2 * result.iterations, FREE_RETRY_MIN_ITERATIONS))}
        other = _without_linear_bounds(problem, result, transcription=transcription,
                                       hessian=hessian, cost=cost, initial_state=initial_state,
                                       solver_options=budget, progress=progress,
                                       compile_=compile_, warm_start=warm_start, balance=balance,
                                       _free_retry=False)
        if other is not None:
            return replace(other, iterations=result.iterations + other.iterations,
                           seconds=time.perf_counter() - t_start)
    if result.converged and result.outside_tank and _free_retry:
        inside = _inside_the_tank(problem, result, transcription=transcription,
                                  hessian=hessian, cost=cost, initial_state=initial_state,
                                  solver_options=solver_options, progress=progress,
                                  compile_=compile_, balance=balance, _free_retry=False)
        if inside is not None:
            return replace(inside, iterations=result.iterations + inside.iterations,
                           seconds=time.perf_counter() - t_start)
    if not result.converged:
        # a fit that did not converge (its iterations or time budget spent) is no place to
        # read a noise figure or a residual balance from, and a refit would spend the
        # budget again
        return result
    again = reweighed(problem, result.noise_figures)  # a provisional force weight was off
    if again is not None:
        second = fit(again.with_initial(dict(zip(result.names, result.values))),
                     transcription=transcription, hessian=hessian, cost=cost,
                     initial_state=initial_state, solver_options=solver_options,
                     progress=progress, robust_start=False, compile_=compile_,
                     warm_start=result, balance=balance, _free_retry=False)
        return replace(second, iterations=result.iterations + second.iterations,
                       seconds=time.perf_counter() - t_start)
    if balance and cost == "squared":
        from .balance import rebalanced

        again = rebalanced(result)
        if again is not None:
            balanced, text = again
            balanced = replace(balanced.with_initial(dict(zip(result.names, result.values))),
                               notes=balanced.notes + (text,))
            second = fit(balanced, transcription=transcription, hessian=hessian, cost=cost,
                         initial_state=initial_state, solver_options=solver_options,
                         progress=progress, robust_start=False, compile_=compile_,
                         warm_start=result, balance=False, _free_retry=False)
            result = replace(second, iterations=result.iterations + second.iterations,
                             seconds=time.perf_counter() - t_start)
    return result


def _without_linear_bounds(problem: FitProblem, bounded: FitResult, **options
                           ) -> FitResult | None:
    """The fit of ``problem`` without its linear bounds (the masses within the liquid),
    when it converges inside them with a smaller residual than ``bounded``, which ended on
    one; else ``None``.

    A bound that is active on the way can hold the solver in another valley: a spinning-rig
    baseline (fixed mass and a spherical pendulum, truth 2.75 of 2.84 kg of liquid) ended on
    the bound at 0.68 N RMS with the pendulum's mass traded into the fixed mass, from any
    start and barrier strategy tried; without the bound it converges to the truth at
    0.026 N. A minimum inside the bounds is a minimum of the bounded problem too."""
    free = fit(replace(problem, linear_bounds=()), **options)
    inside = all(b.slack(problem.names, free.values) >= -BUDGET_RTOL * abs(b.upper)
                 for b in problem.linear_bounds)
    if not (free.converged and inside and free.rms_residual < bounded.rms_residual):
        return None
    note = ("the masses were fitted without the liquid bound, which held the solver away "
            "from this minimum; it ends inside the bound")
    return replace(free, problem=replace(free.problem, linear_bounds=problem.linear_bounds,
                                         notes=free.problem.notes + (note,)))


def _inside_the_tank(problem: FitProblem, outside: FitResult, **options) -> FitResult | None:
    """The fit of ``problem`` with the tank's ranges (:attr:`FitProblem.tank_ranges`) as
    bounds, started from ``outside`` (a converged fit that put the analog outside its tank)
    moved inside them; ``None`` when it does not converge.

    The ranges are not bounds of every fit (any finite bound sent a six-channel rotor fit
    from the prediction astray), but a fit that left them trades a poorly determined
    quantity into an impossible one: a spinning-rig candidate with a rotary oscillator
    fitted the torques to 0.013 N m with the fixed mass's inertias at 1.1 and 2.5 kg m^2
    (the whole liquid's at the wall: 0.15 kg m^2)."""
    ranges = problem.tank_ranges
    est = tuple(replace(e, lower=max(e.lower, ranges[e.parameter][0]),
                        upper=min(e.upper, ranges[e.parameter][1]))
                if e.parameter in ranges else e for e in problem.estimated)
    bounded = replace(problem, estimated=est).with_initial(dict(zip(outside.names,
                                                                    outside.values)))
    res = fit(bounded, warm_start=outside, robust_start=False, **options)
    if not res.converged:
        return None
    note = ("the analog left its tank in a fit without the tank's ranges as bounds ("
            + "; ".join(outside.outside_tank) + "); refitted within them")
    return replace(res, problem=replace(res.problem, notes=res.problem.notes + (note,)))


def _setup(problem: FitProblem, transcription: Transcription, cost: str, kinds: list[str],
           blocks_ok: bool, compile_: bool | None, warm_start: FitResult | None):
    """The assembled NLP of ``problem`` and its per-case terms (``kinds``: each case's
    initial state, "rest", "steady" or "free")."""
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
    return _Nlp.assemble(theta_s, problem.initial / scales, terms, rows, upper), terms


@dataclass(frozen=True)
class _Nlp:
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
                 rows: np.ndarray | None = None, upper: np.ndarray | None = None) -> "_Nlp":
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

    @cached_property
    def jac_r(self) -> ca.MX:
        """``d r / d w``: assembled from the cases' blocks when each has them."""
        if not all(t.jacobian is not None for t in self.terms):
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

    def derivative_options(self, hessian: Hessian, blocks_ok: bool) -> dict:
        """``jac_g`` assembled from per-interval blocks and the Gauss-Newton ``hess_lag``."""
        opts: dict = {}
        jac_g = self.constraint_jacobian(blocks_ok)
        if jac_g is not None:
            opts["jac_g"] = jac_g
        if hessian.kind == "gauss-newton":
            Jr = self.jac_r
            sigma = ca.MX.sym("sigma")
            lam = ca.MX.sym("lam", self.g.numel())
            H = sigma * ca.mtimes(Jr.T, Jr) / self.norm
            opts["hess_lag"] = ca.Function("nlp_hess_l", [self.w, ca.MX(0, 1), sigma, lam],
                                           [ca.triu(H)], ["x", "p", "lam_f", "lam_g"],
                                           ["triu_hess_gamma_x_x"])
        return opts

    def constraint_jacobian(self, blocks_ok: bool) -> ca.Function | None:
        """``w -> (g, dg/dw)`` assembled from per-interval blocks, or ``None`` (then CasADi
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
        return ca.Function("nlp_jac_g", [self.w, ca.MX(0, 1)], [gv, J],
                           ["x", "p"], ["g", "jac_g_x"])

    def error_function(self, cost: str) -> ca.Function:
        """``w -> (e, de/dw, raw, report, carriage..., displacement residuals...)``: what the
        covariance and the reports use."""
        e = self.e
        same = all(t.e is t.r for t in self.terms)  # squared cost: reuse d r / d w
        raw = ca.vertcat(*[t.raw for t in self.terms])
        report = ca.vertcat(*[t.report for t in self.terms])
        extra = [t.carriage if t.carriage is not None else ca.MX(0, 1) for t in self.terms]
        xres = [t.displacement_residual if t.displacement_residual is not None else ca.MX(0, 1)
                for t in self.terms]
        jac = self.jac_r if same else ca.jacobian(e, self.w)
        states = [t.block.X for t in self.terms]
        coefs = [t.coef for t in self.terms]
        return ca.Function("residuals", [self.w],
                           [e, jac, raw, report, *extra, *xres, *states, *coefs])


def _result(problem: FitProblem, theta: np.ndarray, stats: dict, recorder: Recorder,
            terms: list[CaseTerms], e: np.ndarray, raw: np.ndarray, report: np.ndarray,
            J: np.ndarray, Je: sps.spmatrix, Jg: sps.spmatrix, t_start: float,
            transcription: Transcription, cost_kind: str, carriage: tuple,
            displacement_residuals: tuple, states: tuple, coefficients: tuple,
            initial_state_kinds: tuple[str, ...] = (),
            initial_states: tuple[dict[str, float], ...] = ()) -> FitResult:
    measured = [t.measured for t in terms]
    weights = [t.weights for t in terms]
    nch = [1 if np.ndim(m) == 1 else m.shape[1] for m in measured]
    n_force = int(sum(np.count_nonzero(w) * c for w, c in zip(weights, nch)))
    n_disp = sum(x.size for x in displacement_residuals if x is not None)
    at_bound = tuple(_at_bound(x, v) for x, v in zip(problem.estimated, theta))
    # the scores of the robust covariance are read from the measured channels' rows
    samples = [np.r_[np.tile(np.arange(np.shape(m)[0]), c),
                     np.full(0 if x is None else x.size, -1)]
               for m, c, x in zip(measured, nch, displacement_residuals)]
    unc = uncertainty(Je, Jg, e, n_force + n_disp, theta.size,
                      np.array([x.scale for x in problem.estimated]), problem.names,
                      held=tuple(i for i, side in enumerate(at_bound) if side), samples=samples)
    active = tuple(b for b in problem.linear_bounds if _on_linear_bound(b, problem, theta))
    if active:
        unc = _held_on(unc, np.array([b.row(problem.names) for b in active]))
    warnings = list(unc.warnings)
    for b in active:
        warnings.append(f"the estimates end on the bound {b.text}: the data ask for more mass "
                        "than the liquid holds (check the dry mass, the fill and the density, "
                        "or a mode the model lacks); held there in the covariance")
    status = stats.get("return_status", "unknown")
    converged = bool(stats.get("success", False))
    if not converged:
        hint = _IPOPT_HINTS.get(status, "see IPOPT's status; try other initial values")
        warnings.append(f"IPOPT did not converge ({status}): {hint}")
    for x, v, side in zip(problem.estimated, theta, at_bound):
        if side:
            warnings.append(f"`{x.name}` = {v:.6g} {x.unit} is at its bound "
                            f"[{x.lower:.6g}, {x.upper:.6g}]: no standard error, held there in "
                            "the covariance")
    F_all = np.concatenate([t.scaled_measured[np.tile(t.weights, c) > 0]
                            for t, c in zip(terms, nch)])
    ssr = float(report @ report)
    r_squared = 1 - ssr / float(np.sum((F_all - F_all.mean()) ** 2))
    if not r_squared >= LOW_R_SQUARED:
        warnings.append(f"the model explains almost nothing of the measurement (R^2 = "
                        f"{r_squared:.3g}): the record may hold noise only, a channel of "
                        "another quantity, or a drive that does not excite the model; check it "
                        "before using these estimates")
    # the intervals use the robust covariance: the Gauss-Newton one when the residuals are
    # white, wider when they are correlated (coloured noise, a filtered force, a model that
    # misses a small effect), where the Gauss-Newton one is optimistic
    kind = "robust" if unc.robust is not None else "gauss-newton"
    cov = unc.robust if unc.robust is not None else unc.covariance
    free = np.array([side is None for side in at_bound])
    stderr = np.where(free, np.sqrt(np.clip(np.diag(cov), 0, None)), np.nan)
    derived, derived_units = derived_quantities(problem, theta, cov, free)
    pieces = np.split(raw, np.cumsum([int(np.size(m)) for m in measured])[:-1])
    residuals = tuple(p if np.ndim(m) == 1 else p.reshape(m.shape, order="F")
                      for p, m in zip(pieces, measured))
    figures = tuple(case_figures(problem, i, r, w)
                    for i, (r, w) in enumerate(zip(residuals, weights)))
    robust, widen = unc.robust, 1.0
    if robust is not None:
        widen = model_error_factor(figures, residuals, tuple(weights))
        robust = robust * widen**2
        if kind == "robust":
            cov = robust
            stderr = np.where(free, np.sqrt(np.clip(np.diag(cov), 0, None)), np.nan)
            derived, derived_units = derived_quantities(problem, theta, cov, free)
    return FitResult(
        problem=problem,
        values=theta, stderr=stderr, covariance=cov,
        cost=ssr, rms_residual=math.sqrt(ssr / n_force),
        r_squared=r_squared,
        n_samples=n_force, iterations=int(stats.get("iter_count", len(recorder.costs))),
        seconds=time.perf_counter() - t_start, converged=converged, status=status,
        warnings=tuple(warnings), identifiability=unc.identifiability,
        derived=derived, derived_units=derived_units,
        history=np.array(recorder.thetas), cost_history=np.array(recorder.costs),
        residuals=residuals,
        channels=tuple(problem.channels(i) for i in range(len(measured))),
        channel_scales=tuple({c: problem.report_scale(i, c) for c in problem.channels(i)}
                             for i in range(len(measured))),
        sensitivity=J,
        weights=tuple(weights),
        measured=tuple(measured), cost_kind=cost_kind, transcription=repr(transcription),
        carriage=carriage, displacement_residuals=displacement_residuals,
        states=states, carriage_coefficients=coefficients,
        objective=float(e @ e), residual_variance=unc.sigma2,
        dof=max(n_force + n_disp - (Je.shape[1] - Jg.shape[0]), 1),
        initial_state_kinds=initial_state_kinds, initial_states=initial_states,
        at_bound=at_bound, bound_stderr=unc.bound_stderr,
        active_bounds=tuple(b.text for b in active), noise_figures=figures,
        gauss_newton_covariance=unc.covariance, robust_covariance=robust,
        covariance_kind=kind, bandwidths=unc.bandwidths, model_error=widen,
    )


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


def _on_linear_bound(bound, problem: FitProblem, theta: np.ndarray) -> bool:
    """Whether ``theta`` ends on the linear ``bound`` (slack within 1e-4 of its upper)."""
    return bound.slack(problem.names, theta) <= 1e-4 * max(abs(bound.upper), 1e-12)


def _held_on(unc, rows: np.ndarray):
    """``unc`` with its covariances (Gauss-Newton and robust) conditioned on the active
    linear bounds ``rows``
    (:func:`estimate.fitting.budget.conditioned`), standard errors and correlations anew."""
    from dataclasses import replace

    from .budget import conditioned

    free = np.isfinite(unc.stderr)

    def held(c):
        out = np.zeros_like(c)
        out[np.ix_(free, free)] = conditioned(c[np.ix_(free, free)], rows[:, free])
        return out

    cov = held(unc.covariance)
    robust = None if unc.robust is None else held(unc.robust)
    se = np.full(free.size, np.nan)
    se[free] = np.sqrt(np.clip(np.diag(cov)[free], 0, None))
    corr = np.full_like(cov, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        sub = cov[np.ix_(free, free)] / np.outer(se[free], se[free])
    corr[np.ix_(free, free)] = np.clip(np.nan_to_num(sub, nan=0.0, posinf=0.0, neginf=0.0),
                                       -1.0, 1.0)
    return replace(unc, covariance=cov, stderr=se, correlation=corr, robust=robust)


def _at_bound(x, value: float) -> str | None:
    """``"lower"`` or ``"upper"`` when the estimate sits on that bound (within 1e-4 of the
    span between finite bounds, else 1e-5 of its scale), else ``None``."""
    span = x.upper - x.lower
    tol = 1e-4 * span if math.isfinite(span) else 1e-5 * x.scale
    if value - x.lower < tol:
        return "lower"
    if x.upper - value < tol:
        return "upper"
    return None
