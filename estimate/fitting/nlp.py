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
from dataclasses import dataclass

import casadi as ca
import numpy as np

from analogs.errors import InputError
from derive import OUTPUT_NAMES, RK4, simulate

from ..data.signals import lowpass
from ._progress import Recorder, progress_printer
from .covariance import gauss_newton, reduced_jacobian
from .problem import FitProblem
from .result import FitResult, derived_quantities
from .transcription import Block, MultipleShooting, Transcription

__all__ = ["fit", "Hessian"]

_IPOPT_DEFAULTS = {
    "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-8,
    "ipopt.max_iter": 300, "ipopt.mu_strategy": "adaptive", "ipopt.linear_solver": "mumps",
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


def _measured_output(dm, channels: tuple[str, ...]) -> ca.Function:
    x = ca.SX.sym("x", dm.nx)
    u = ca.SX.sym("u", dm.nu)
    p = ca.SX.sym("p", len(dm.parameter_names))
    t = ca.SX.sym("t")
    out = dm.outputs(x, u, p, t)
    y = ca.vertcat(*[out[OUTPUT_NAMES.index(c)] for c in channels])
    return ca.Function("measured", [x, u, p, t], [y])


def _parameter_column(dm, values: Mapping[str, float], theta: ca.MX, problem: FitProblem,
                      case: int) -> ca.MX:
    """The model's parameter vector for one case as an MX of the scaled decision vector."""
    entries = []
    for name in dm.parameter_names:
        hit = None
        for j, e in enumerate(problem.estimated):
            if e.parameter == name and (e.case is None or e.case == case):
                hit = theta[j] * e.scale
        if hit is None:
            v = values.get(name)
            hit = ca.MX(0.0 if v is None or not math.isfinite(v) else float(v))
        entries.append(hit)
    return ca.vertcat(*entries)


def _measured_force(problem: FitProblem, i: int) -> tuple[np.ndarray, np.ndarray]:
    """The recorded channels as fitted (filtered, measurement models applied) and weights.

    One channel (the lateral force): a 1-D array; several: ``samples x channels`` in the
    order of :meth:`FitProblem.channels`."""
    exp = problem.experiments[i]
    case = exp.case
    names = problem.channels(i)
    have = case.channels
    cols = []
    w = (np.ones(case.time.size) if problem.weights[i] is None
         else np.asarray(problem.weights[i], float))
    for name in names:
        F = np.asarray(have[name], float)
        if problem.force_cutoff_hz is not None:
            F = lowpass(case.time, F, cutoff_hz=problem.force_cutoff_hz)
        for mm in problem.measurement:
            F, wm = mm.measured(case.time, F)
            w = w * wm
        cols.append(F)
    return (cols[0] if len(cols) == 1 else np.column_stack(cols)), w


def fit(problem: FitProblem, *, transcription: Transcription = MultipleShooting(),
        hessian: Hessian = Hessian(), cost: str = "squared", initial_state: str = "rest",
        solver_options: Mapping[str, object] | None = None,
        progress: bool | None = None, robust_start: bool = True,
        compile_: bool | None = None) -> FitResult:
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
        ``sum((|E| - |S|)^2)``, with a smooth absolute value. Residuals, RMS, R^2 and the
        covariance of the result are those of ``simulated - measured`` for either cost.
    initial_state : {"rest", "free"}
        Start every case at rest (the tests start from rest) or estimate the initial state.
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

    Returns
    -------
    FitResult
        Estimates with standard errors, correlations, identifiability, derived quantities,
        cost, residuals, solver status and the parameter trajectories over iterations.
    """
    if cost not in ("squared", "abs"):
        raise InputError(f"cost must be 'squared' or 'abs', got {cost!r}")
    if initial_state not in ("rest", "free"):
        raise InputError(f"initial_state must be 'rest' or 'free', got {initial_state!r}")
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
    theta_s = ca.MX.sym("theta", len(est))
    # the exact Hessian differentiates g twice: keep g an AD-able expression then
    blocks_ok = hessian.kind == "gauss-newton"
    if compile_ is None:
        from derive._compile import c_compiler

        compile_ = blocks_ok and c_compiler() is not None
    terms = [_case_terms(problem, i, theta_s, transcription, cost, initial_state,
                         blocks_ok, compile_) for i in range(len(problem.experiments))]
    nlp = _Nlp.assemble(theta_s, problem.initial / scales, terms)
    opts = dict(_IPOPT_DEFAULTS)
    opts.update(nlp.derivative_options(hessian, blocks_ok))
    recorder = Recorder(nlp.w.numel(), nlp.g.numel(), len(est), scales, 2 * nlp.norm,
                         progress_printer(problem.names) if progress else None)
    opts["iteration_callback"] = recorder
    opts.update(dict(solver_options or {}))
    solver = ca.nlpsol("fit", "ipopt", {"x": nlp.w, "f": nlp.f, "g": nlp.g}, opts)
    lbx, ubx = nlp.bounds(est)
    sol = solver(x0=nlp.w0, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
    if progress:
        print(file=sys.stderr)
    w_opt = np.asarray(sol["x"]).ravel()
    # IPOPT may leave a bounded variable a hair outside its bound (its bound_relax_factor)
    theta = np.clip(w_opt[: len(est)] * scales, [e.lower for e in est], [e.upper for e in est])
    e, Je, raw = nlp.error_function(cost)(w_opt)
    _, Jg = solver.get_function("nlp_jac_g")(w_opt, [])
    J = reduced_jacobian(Je, Jg, len(est), scales, nlp.free_states)
    return _result(problem, theta, solver.stats(), recorder, terms, np.asarray(e).ravel(), J,
                   np.asarray(raw).ravel(), t_start, transcription, cost)


@dataclass(frozen=True)
class _CaseTerms:
    """One case in the NLP: its transcription ``block``, the cost residual ``r``, the
    residual ``e = w (Y - F) / s`` whose squares the covariance and the reports use
    (``= r`` for the squared cost), the raw residual ``Y - F`` (N, N m; channel-major) and
    the measured data as fitted."""

    block: Block
    r: ca.MX
    e: ca.MX
    raw: ca.MX
    measured: np.ndarray
    weights: np.ndarray
    scaled_measured: np.ndarray
    free_initial_state: bool


def _case_terms(problem: FitProblem, i: int, theta_s: ca.MX, transcription: Transcription,
                cost: str, initial_state: str, blocks_ok: bool, compile_: bool) -> _CaseTerms:
    exp = problem.experiments[i]
    dm, case = exp.derived, exp.case
    t = np.asarray(case.time, float)
    p_i = _parameter_column(dm, problem.fixed[i], theta_s, problem, i)
    if dm.nx:
        values0 = problem.case_values(i, problem.initial)
        guess = simulate(dm, values0, t, exp.excitation, integrator=RK4()).states.T
    else:
        guess = np.zeros((0, t.size))
    x0 = np.zeros(dm.nx) if initial_state == "rest" else None
    block = transcription.block(dm, p_i, t, exp.excitation, guess, x0,
                                theta=theta_s if blocks_ok else None, compiled=compile_)
    Ug = exp.excitation.values(t) if dm.nu else np.zeros((0, t.size))
    chans = problem.channels(i)
    Y = _measured_output(dm, chans).map(t.size)(block.X, ca.DM(Ug), p_i, ca.DM(t).T).T
    mvals = {e.parameter: theta_s[j] * e.scale for j, e in enumerate(problem.estimated)
             if e.case in (None, i)}
    for mm in problem.measurement:
        extra = mm.term(ca.DM(Ug), dm.inputs, mvals)
        if extra is not None:
            Y = Y + extra
    F, wts = _measured_force(problem, i)
    scale = problem.channel_scales(i)
    s = np.array([scale[c] for c in chans])
    F2 = F.reshape(t.size, len(chans), order="F")
    # channel-major: each channel divided by its scale, so N and N m are comparable
    Yv = ca.vec(Y / ca.repmat(ca.DM(s).T, t.size, 1))
    Fv = (F2 / s[None, :]).ravel(order="F")
    wv = np.tile(wts, len(chans))
    raw = ca.vec(Y) - ca.DM(F2.ravel(order="F"))
    e = Yv - ca.DM(Fv)
    if cost == "squared":
        r = e
    else:
        eps = 1e-3 * float(np.std(Fv))
        r = ca.sqrt(Yv**2 + eps**2) - ca.DM(np.abs(Fv))
    if np.any(wv != 1.0):
        e, r = e * ca.DM(wv), r * ca.DM(wv)
    return _CaseTerms(block, r, e, raw, F, wts, Fv, x0 is None)


@dataclass(frozen=True)
class _Nlp:
    """The assembled NLP: decision vector ``w`` (scaled parameters first), its start
    ``w0``, constraints ``g`` (= 0), cost residuals ``r`` with ``f = |r|^2 / (2 norm)``."""

    w: ca.MX
    w0: np.ndarray
    g: ca.MX
    r: ca.MX
    norm: float
    terms: tuple[_CaseTerms, ...]
    free_states: tuple[int, ...]

    @classmethod
    def assemble(cls, theta_s: ca.MX, theta0: np.ndarray, terms: list[_CaseTerms]) -> "_Nlp":
        ws, w0s, free = [theta_s], [theta0], []
        offset = theta_s.numel()
        for term in terms:
            if term.free_initial_state:  # the free initial state acts as nx extra parameters
                nx = term.block.X.size1()
                free.extend(range(offset, offset + nx))
            ws.append(term.block.w)
            w0s.append(term.block.w0)
            offset += term.block.w.numel()
        norm = float(np.mean(np.concatenate([t.scaled_measured for t in terms]) ** 2)) or 1.0
        return cls(ca.vertcat(*ws), np.concatenate(w0s), ca.vertcat(*[t.block.g for t in terms]),
                   ca.vertcat(*[t.r for t in terms]), norm, tuple(terms), tuple(free))

    @property
    def f(self) -> ca.MX:
        return 0.5 * ca.sumsqr(self.r) / self.norm

    def bounds(self, est) -> tuple[np.ndarray, np.ndarray]:
        lbx = np.full(self.w.numel(), -np.inf)
        ubx = np.full(self.w.numel(), np.inf)
        lbx[: len(est)] = [e.lower / e.scale for e in est]
        ubx[: len(est)] = [e.upper / e.scale for e in est]
        return lbx, ubx

    def derivative_options(self, hessian: Hessian, blocks_ok: bool) -> dict:
        """``jac_g`` assembled from per-interval blocks and the Gauss-Newton ``hess_lag``."""
        opts: dict = {}
        blocks = [t.block for t in self.terms]
        if blocks_ok and all(b.jac_w is not None or b.g.numel() == 0 for b in blocks):
            with_g = [b for b in blocks if b.g.numel()]
            if with_g:
                J = ca.horzcat(ca.vertcat(*[b.jac_theta for b in with_g]),
                               ca.diagcat(*[b.jac_w for b in with_g]))
                g_fast = ca.vertcat(*[b.g_fast for b in with_g])
                opts["jac_g"] = ca.Function("nlp_jac_g", [self.w, ca.MX(0, 1)], [g_fast, J],
                                            ["x", "p"], ["g", "jac_g_x"])
        if hessian.kind == "gauss-newton":
            Jr = ca.jacobian(self.r, self.w)
            sigma = ca.MX.sym("sigma")
            lam = ca.MX.sym("lam", self.g.numel())
            H = sigma * ca.mtimes(Jr.T, Jr) / self.norm
            opts["hess_lag"] = ca.Function("nlp_hess_l", [self.w, ca.MX(0, 1), sigma, lam],
                                           [ca.triu(H)], ["x", "p", "lam_f", "lam_g"],
                                           ["triu_hess_gamma_x_x"])
        return opts

    def error_function(self, cost: str) -> ca.Function:
        """``w -> (e, de/dw, raw)``: the residuals the covariance and reports use."""
        e = ca.vertcat(*[t.e for t in self.terms])
        raw = ca.vertcat(*[t.raw for t in self.terms])
        return ca.Function("residuals", [self.w], [e, ca.jacobian(e, self.w), raw])


def _result(problem: FitProblem, theta: np.ndarray, stats: dict, recorder: Recorder,
            terms: list[_CaseTerms], e: np.ndarray, J: np.ndarray, raw: np.ndarray,
            t_start: float, transcription: Transcription, cost_kind: str) -> FitResult:
    measured = [t.measured for t in terms]
    weights = [t.weights for t in terms]
    nch = [1 if np.ndim(m) == 1 else m.shape[1] for m in measured]
    n = int(sum(np.count_nonzero(w) * c for w, c in zip(weights, nch)))
    unc = gauss_newton(J, e, n, theta.size, np.array([x.scale for x in problem.estimated]),
                       problem.names)
    warnings = list(unc.warnings)
    status = stats.get("return_status", "unknown")
    converged = bool(stats.get("success", False))
    if not converged:
        hint = _IPOPT_HINTS.get(status, "see IPOPT's status; try other initial values")
        warnings.append(f"IPOPT did not converge ({status}): {hint}")
    for x, v in zip(problem.estimated, theta):
        span = x.upper - x.lower
        tol = 1e-4 * span if math.isfinite(span) else 1e-5 * x.scale
        if min(v - x.lower, x.upper - v) < tol:
            warnings.append(f"`{x.name}` = {v:.6g} {x.unit} is at its bound "
                            f"[{x.lower:.6g}, {x.upper:.6g}]")
    F_all = np.concatenate([t.scaled_measured[np.tile(t.weights, c) > 0]
                            for t, c in zip(terms, nch)])
    ssr = float(e @ e)
    derived, derived_units = derived_quantities(problem, theta, unc.covariance)
    pieces = np.split(raw, np.cumsum([int(np.size(m)) for m in measured])[:-1])
    residuals = tuple(p if np.ndim(m) == 1 else p.reshape(m.shape, order="F")
                      for p, m in zip(pieces, measured))
    return FitResult(
        problem=problem,
        values=theta, stderr=unc.stderr, covariance=unc.covariance,
        cost=ssr, rms_residual=math.sqrt(ssr / n),
        r_squared=1 - ssr / float(np.sum((F_all - F_all.mean()) ** 2)),
        n_samples=n, iterations=int(stats.get("iter_count", len(recorder.costs))),
        seconds=time.perf_counter() - t_start, converged=converged, status=status,
        warnings=tuple(warnings), identifiability=unc.identifiability,
        derived=derived, derived_units=derived_units,
        history=np.array(recorder.thetas), cost_history=np.array(recorder.costs),
        residuals=residuals,
        channels=tuple(problem.channels(i) for i in range(len(measured))),
        channel_scales=tuple(problem.channel_scales(i) for i in range(len(measured))),
        sensitivity=unc.sensitivity,
        weights=tuple(weights),
        measured=tuple(measured), cost_kind=cost_kind, transcription=repr(transcription),
    )
