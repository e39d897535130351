"""Estimation as one NLP with exact derivatives: IPOPT through CasADi.

Decision variables are the scaled parameters plus the states at the nodes of the chosen
transcription; the cost is the sum of squared force residuals (or the seed's
``sum((|E| - |S|)^2)``). After the solve, residual sensitivities through a single-shooting
RK4 rollout (forward AD) give the Gauss-Newton covariance and the identifiability check.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np

from derive import OUTPUT_NAMES, RK4, simulate

from .identifiability import analyse
from .problem import FitProblem
from .result import FitResult, derived_quantities
from .signals import lowpass
from .transcription import MultipleShooting, Transcription

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
            raise ValueError(f"Hessian kind must be 'gauss-newton' or 'exact', got {self.kind!r}")


class _Recorder(ca.Callback):
    """IPOPT iteration callback: records parameter trajectories and prints progress."""

    def __init__(self, nw: int, ng: int, ntheta: int, scales: np.ndarray, cost_scale: float,
                 printer: Callable[[int, float, np.ndarray], None] | None) -> None:
        ca.Callback.__init__(self)
        self.nw, self.ng, self.ntheta = nw, ng, ntheta
        self.scales, self.cost_scale = scales, cost_scale
        self.thetas: list[np.ndarray] = []
        self.costs: list[float] = []
        self.printer = printer
        self.construct("fit_iterations", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        n = ca.nlpsol_out(i)
        if n == "f":
            return ca.Sparsity.scalar()
        if n in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nw)
        if n in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        theta = np.asarray(arg[0]).ravel()[: self.ntheta] * self.scales
        cost = float(arg[1]) * self.cost_scale
        self.thetas.append(theta)
        self.costs.append(cost)
        if self.printer is not None:
            self.printer(len(self.costs) - 1, cost, theta)
        return [0]


def _progress_printer(names):
    def show(k, cost, theta):
        vals = "  ".join(f"{n}={v:.5g}" for n, v in zip(names, theta))
        print(f"\riter {k:3d}  cost {cost:.6g}  {vals}"[:200], end="", file=sys.stderr, flush=True)
    return show


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
        ``sum((|E| - |S|)^2)``, with a smooth absolute value.
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
        from a grid over their bounds (:func:`estimate.initial.crank_start`).

    Returns
    -------
    FitResult
        Estimates with standard errors, correlations, identifiability, derived quantities,
        cost, residuals, solver status and the parameter trajectories over iterations.
    """
    if cost not in ("squared", "abs"):
        raise ValueError(f"cost must be 'squared' or 'abs', got {cost!r}")
    if initial_state not in ("rest", "free"):
        raise ValueError(f"initial_state must be 'rest' or 'free', got {initial_state!r}")
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
    blocks = []
    ws, w0s, gs, rs = [theta_s], [problem.initial / scales], [], []
    measured, weights, measured_scaled, norm_parts = [], [], [], []
    extra_cols: list[int] = []
    raws: list[ca.MX] = []
    for i, exp in enumerate(problem.experiments):
        dm, case = exp.derived, exp.case
        t = np.asarray(case.time, float)
        values0 = problem.case_values(i, problem.initial)
        p_i = _parameter_column(dm, problem.fixed[i], theta_s, problem, i)
        if dm.nx:
            guess = simulate(dm, values0, t, exp.excitation, integrator=RK4()).states.T
        else:
            guess = np.zeros((0, t.size))
        x0 = np.zeros(dm.nx) if initial_state == "rest" else None
        block = transcription.block(dm, p_i, t, exp.excitation, guess, x0,
                                    theta=theta_s if blocks_ok else None, compiled=compile_)
        blocks.append(block)
        Ug = exp.excitation.values(t) if dm.nu else np.zeros((0, t.size))
        chans = problem.channels(i)
        out = _measured_output(dm, chans).map(t.size)
        Y = out(block.X, ca.DM(Ug), p_i, ca.DM(t).T).T
        F, wts = _measured_force(problem, i)
        scale = problem.channel_scales(i)
        mvals = {e.parameter: theta_s[j] * e.scale for j, e in enumerate(est)
                 if e.case in (None, i)}
        for mm in problem.measurement:
            extra = mm.term(ca.DM(Ug), dm.inputs, mvals)
            if extra is not None:
                Y = Y + extra
        measured.append(F)
        weights.append(wts)
        if len(chans) > 1:
            # channel-major: each channel divided by its scale, so N and N m are comparable
            s = np.array([scale[c] for c in chans])
            Yv = ca.vec(Y / ca.repmat(ca.DM(s).T, t.size, 1))
            Fv = (F / s[None, :]).ravel(order="F")
            wv = np.tile(wts, len(chans))
            raws.append(ca.vec(Y) - ca.DM(F.ravel(order="F")))
            if cost == "squared":
                r = Yv - ca.DM(Fv)
            else:
                eps = 1e-3 * float(np.std(Fv))
                r = ca.sqrt(Yv**2 + eps**2) - ca.DM(np.abs(Fv))
            if np.any(wv != 1.0):
                r = r * ca.DM(wv)
            measured_scaled.append(Fv[wv > 0])
            norm_parts.append(Fv)
        else:
            s0 = scale[chans[0]]
            Fs = F if s0 == 1.0 else F / s0
            Ys = Y if s0 == 1.0 else Y / s0
            if cost == "squared":
                r = Ys - ca.DM(Fs)
            else:
                eps = 1e-3 * float(np.std(Fs))
                r = ca.sqrt(Ys**2 + eps**2) - ca.DM(np.abs(Fs))
            raws.append(r if s0 == 1.0 else Y - ca.DM(F))
            if np.any(wts != 1.0):
                r = r * ca.DM(wts)
            measured_scaled.append(Fs[wts > 0])
            norm_parts.append(Fs)
        if x0 is None:  # the free initial state acts as nx extra parameters
            offset = sum(int(v.numel()) for v in ws)
            extra_cols.extend(range(offset, offset + dm.nx))
        ws.append(block.w)
        w0s.append(block.w0)
        gs.append(block.g)
        rs.append(r)
    w = ca.vertcat(*ws)
    g = ca.vertcat(*gs)
    r_all = ca.vertcat(*rs)
    norm = float(np.mean(np.concatenate(norm_parts) ** 2)) or 1.0
    problem_weights = weights
    f = 0.5 * ca.sumsqr(r_all) / norm
    lbx = np.full(w.numel(), -np.inf)
    ubx = np.full(w.numel(), np.inf)
    lbx[: len(est)] = [e.lower / e.scale for e in est]
    ubx[: len(est)] = [e.upper / e.scale for e in est]
    opts = dict(_IPOPT_DEFAULTS)
    if blocks_ok and all(b.jac_w is not None or b.g.numel() == 0 for b in blocks):
        jt = [b.jac_theta for b in blocks if b.g.numel()]
        jw = [b.jac_w for b in blocks if b.g.numel()]
        if jt:
            J = ca.horzcat(ca.vertcat(*jt), ca.diagcat(*jw))
            g_fast = ca.vertcat(*[b.g_fast for b in blocks if b.g.numel()])
            opts["jac_g"] = ca.Function("nlp_jac_g", [w, ca.MX(0, 1)], [g_fast, J],
                                        ["x", "p"], ["g", "jac_g_x"])
    Jr = ca.jacobian(r_all, w)
    residual_fn = ca.Function("residuals", [w], [r_all, Jr, ca.vertcat(*raws)])
    if hessian.kind == "gauss-newton":
        sigma = ca.MX.sym("sigma")
        lam = ca.MX.sym("lam", g.numel())
        H = sigma * ca.mtimes(Jr.T, Jr) / norm
        opts["hess_lag"] = ca.Function("nlp_hess_l", [w, ca.MX(0, 1), sigma, lam],
                                       [ca.triu(H)], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    recorder = _Recorder(w.numel(), g.numel(), len(est), scales, 2 * norm,
                         _progress_printer(problem.names) if progress else None)
    opts["iteration_callback"] = recorder
    opts.update(dict(solver_options or {}))
    solver = ca.nlpsol("fit", "ipopt", {"x": w, "f": f, "g": g}, opts)
    sol = solver(x0=np.concatenate(w0s), lbx=lbx, ubx=ubx, lbg=0, ubg=0)
    if progress:
        print(file=sys.stderr)
    stats = solver.stats()
    w_opt = np.asarray(sol["x"]).ravel()
    # IPOPT may leave a bounded variable a hair outside its bound (its bound_relax_factor)
    theta = np.clip(w_opt[: len(est)] * scales, [e.lower for e in est], [e.upper for e in est])
    resid, J, raw = _reduced_jacobian(solver, residual_fn, w_opt, len(est), scales, extra_cols)
    return _result(problem, theta, stats, recorder, measured, resid, J, t_start, transcription, cost,
                   problem_weights, raw, measured_scaled)


def _reduced_jacobian(solver, residual_fn, w_opt: np.ndarray, ntheta: int, scales: np.ndarray,
                      extra: list[int] = ()):
    """Residuals and their total derivative w.r.t. the (unscaled) estimates at ``w_opt``.

    The states ``z`` depend on the parameters through the constraints ``g(theta, z) = 0``:
    ``dz/dtheta = -g_z^-1 g_theta`` and ``dr/dtheta = r_theta + r_z dz/dtheta`` (sparse solve).
    Free initial states (columns ``extra``) count as parameters; their columns follow the
    estimates' in the returned Jacobian.
    """
    import scipy.sparse.linalg as spla

    r, Jr, raw = residual_fn(w_opt)
    r = np.asarray(r).ravel()
    raw = np.asarray(raw).ravel()
    Jr = Jr.sparse().tocsc()
    _, Jg = solver.get_function("nlp_jac_g")(w_opt, [])
    Jg = Jg.sparse().tocsc()
    pcols = list(range(ntheta)) + list(extra)
    zcols = np.setdiff1d(np.arange(Jr.shape[1]), pcols)
    R_p = Jr[:, pcols].toarray()
    if Jg.shape[0]:
        dz = -spla.splu(Jg[:, zcols].tocsc()).solve(Jg[:, pcols].toarray())
        J = R_p + Jr[:, zcols] @ dz
    else:
        J = R_p
    col_scale = np.concatenate([scales, np.ones(len(extra))])
    return r, np.asarray(J) / col_scale[None, :], raw


def _result(problem, theta, stats, recorder, measured, resid, J, t_start, transcription, cost_kind,
            weights, raw, measured_scaled):
    nch = [1 if np.ndim(m) == 1 else m.shape[1] for m in measured]
    wall = np.concatenate([np.tile(w, c) for w, c in zip(weights, nch)])
    n, k = int(np.count_nonzero(wall)), J.shape[1]
    ssr = float(resid @ resid)
    dof = max(n - k, 1)
    sigma2 = ssr / dof
    JtJ = J.T @ J
    warnings = []
    try:
        cov = sigma2 * np.linalg.inv(JtJ)
        if not np.all(np.isfinite(cov)):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        cov = sigma2 * np.linalg.pinv(JtJ)
        warnings.append("the residual sensitivity is singular: covariance from a pseudo-inverse")
    cov = cov[: theta.size, : theta.size]  # marginal over free initial states
    J = J[:, : theta.size]
    stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
    scales = np.array([e.scale for e in problem.estimated])
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.nan_to_num(cov / np.outer(d, d))
    ident = analyse(J, scales, problem.names, sigma2, corr)
    status = stats.get("return_status", "unknown")
    converged = bool(stats.get("success", False))
    if not converged:
        hint = _IPOPT_HINTS.get(status, "see IPOPT's status; try other initial values")
        warnings.append(f"IPOPT did not converge ({status}): {hint}")
    for e, v in zip(problem.estimated, theta):
        span = e.upper - e.lower
        tol = 1e-4 * span if math.isfinite(span) else 1e-5 * e.scale
        if min(v - e.lower, e.upper - v) < tol:
            warnings.append(f"`{e.name}` = {v:.6g} {e.unit} is at its bound [{e.lower:.6g}, {e.upper:.6g}]")
    F_all = np.concatenate(measured_scaled)
    derived = derived_quantities(problem, theta, cov)
    sizes = [int(np.size(m)) for m in measured]
    pieces = np.split(raw, np.cumsum(sizes)[:-1])
    residuals = tuple(p if np.ndim(m) == 1 else p.reshape(m.shape, order="F")
                      for p, m in zip(pieces, measured))
    return FitResult(
        problem=problem,
        values=theta, stderr=stderr, covariance=cov,
        cost=ssr, rms_residual=math.sqrt(ssr / n),
        r_squared=1 - ssr / float(np.sum((F_all - F_all.mean()) ** 2)),
        n_samples=n, iterations=int(stats.get("iter_count", len(recorder.costs))),
        seconds=time.perf_counter() - t_start, converged=converged, status=status,
        warnings=tuple(warnings), identifiability=ident, derived=derived,
        history=np.array(recorder.thetas), cost_history=np.array(recorder.costs),
        residuals=residuals,
        channels=tuple(problem.channels(i) for i in range(len(measured))),
        channel_scales=tuple(problem.channel_scales(i) for i in range(len(measured))),
        sensitivity=J,
        weights=tuple(weights),
        measured=tuple(measured), cost_kind=cost_kind, transcription=repr(transcription),
    )
