"""Estimation as one NLP with exact derivatives: IPOPT through CasADi.

Decision variables are the scaled parameters plus the states at the nodes of the chosen
transcription; the cost is the sum of squared force residuals (or the seed's
``sum((|E| - |S|)^2)``). After the solve, the residual sensitivity reduced to the parameters
(:mod:`estimate.fitting.covariance`) gives the Gauss-Newton covariance and the
identifiability check.

The stages of :func:`fit`: the NLP assembled (:mod:`estimate.fitting.assembly`), solved
once (:func:`_solve`), its named outputs made a result (:mod:`estimate.fitting.solution`),
then refitted where the result asks for it (:mod:`estimate.fitting.refits`).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from analogs.errors import InputError

from ..data.case import KNOWN_INITIAL_STATES
from ..interrupts import surfacing
from ._progress import Recorder, progress_printer
from ._sparse import evaluate
from .assembly import assemble_nlp
from .covariance import reduced_jacobian
from .problem import FitProblem
from .refits import refined
from .result import FitResult
from .segment_start import first_part
from .solution import LOW_R_SQUARED, Solve, fit_result
from .stability import rotor_bounds
from .starts import second_start
from .strategies import Cost, cost_of
from .transcription import MultipleShooting, Transcription
from .vanished import STALLED, stall_stop

__all__ = ["IPOPT_DEFAULTS", "LOW_R_SQUARED", "fit", "Hessian"]

#: IPOPT options of every fit (``solver_options`` override them).
IPOPT_DEFAULTS = {
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
    # bound multipliers start at 1e-5, not IPOPT's 1: most bounds of a fit are inactive
    # (masses > 0, a hinge spring >= 0 the record may not need), and a multiplier z of a
    # bound at distance s adds z/s to that parameter's curvature. Started at 1, it halves
    # every step towards a bound: a 60 s record's hinge spring, whose optimum sits just
    # below 0, took 14 iterations (9 with the bound lifted). A multiplier the optimum
    # needs grows by Newton steps. Iterations 9/11/14 -> 5/6/6 on 6/20/60 s records and
    # 11/9/14 -> 6/5/9 on bench_fit's, the same estimates to 1e-6 of their values.
    "ipopt.bound_mult_init_val": 1e-5,
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
        hessian: Hessian = Hessian(), cost: Cost | str | None = None,
        initial_state: str | None = None,
        solver_options: Mapping[str, object] | None = None,
        progress: bool | None = None, robust_start: bool = True,
        compile_: bool | None = None, warm_start: FitResult | None = None,
        balance: bool = True, unbounded_retry: bool = True, hold_undetermined: bool = True,
        segment_start: bool = True, _free_retry: bool = True) -> FitResult:
    """Estimate the parameters of ``problem``.

    Parameters
    ----------
    problem : FitProblem
        Cases, model and the parameters to estimate (:meth:`FitProblem.build`).
    transcription : MultipleShooting or Collocation
        How the dynamics enter the NLP (default: multiple shooting, one RK4 step per sample,
        a node every 20 ms of samples; a one-mode model is solved with a node every 80 ms
        first, :data:`COARSE_INTERVAL_SECONDS`).
    hessian : Hessian
        ``Hessian("gauss-newton")`` (default) or ``Hessian("exact")``.
    cost : Cost, {"squared", "abs"} or None
        ``SquaredCost()`` or ``"squared"``: sum of squared force residuals (N^2).
        ``AbsCost()`` or ``"abs"``: the seed's ``sum((|E| - |S|)^2)``, with a smooth
        absolute value (filtered input only). None:
        :data:`~estimate.fitting.strategies.DEFAULT_COST` (squared).
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
    unbounded_retry : bool, default True
        When the fit ends on the liquid mass bound, fit again without it and keep that fit
        if it converges inside the bound with a smaller residual (a bound met on the way
        can hold the solver in another valley). ``False`` where the start is known to be
        in the right valley (a warm start from a fit that had its own retry).
    hold_undetermined : bool, default True
        When the fit does not converge because a mode's mass vanished (the record does not
        show it: the fit stops when its cost stalls then, status ``"Stalled"``), refit
        with that mode's other parameters held at their starts and its damper at 0
        (:mod:`estimate.fitting.vanished`); the note says so.
    segment_start : bool, default True
        When the fit of a long record (at least 2,000 samples, no estimated carriage
        motion) does not converge, fit its first third and then the whole record from
        those estimates (:mod:`estimate.fitting.segment_start`), kept when both converge.

    Returns
    -------
    FitResult
        Estimates with standard errors, correlations, identifiability, derived quantities,
        cost, residuals, solver status and the parameter trajectories over iterations.
    """
    chosen = cost_of(cost)
    chosen.check(problem)
    cost = chosen.name  # the terms and the result know the cost by name
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
    result = _solve(problem, transcription, hessian, cost, kinds, solver_options, progress,
                    compile_, warm_start, t_start)
    if result.status == "Invalid_Number_Detected" and warm_start is None:
        problem, result = _within_rk4(problem, result, lambda p: _solve(
            p, transcription, hessian, cost, kinds, solver_options, progress, compile_, None,
            t_start))
    other = (second_start(problem, dict(zip(result.names, result.values)))
             if _free_retry and warm_start is None else None)
    if other is not None:
        problem, result = _better_start(problem, result, *other, lambda p: _solve(
            p, transcription, hessian, cost, kinds, solver_options, progress, compile_, None,
            t_start))
    part = (first_part(problem) if segment_start and _free_retry and warm_start is None
            and not result.converged else None)
    if part is not None:
        problem, result = _from_first_part(problem, result, *part, lambda p: _solve(
            p, transcription, hessian, cost, kinds, solver_options, progress, compile_, None,
            t_start))
    return refined(problem, result, transcription=transcription, hessian=hessian, cost=cost,
                   initial_state=initial_state, solver_options=solver_options,
                   progress=progress, compile_=compile_, warm_start=warm_start,
                   balance=balance, free_retry=_free_retry,
                   unbounded_retry=unbounded_retry, hold_undetermined=hold_undetermined,
                   t_start=t_start)


def _within_rk4(problem: FitProblem, result: FitResult, solve
                ) -> tuple[FitProblem, FitResult]:
    """``problem`` and ``result`` (a solve whose simulation overflowed), or the solve of
    ``problem`` from the same start with its rotors' spin-up bounded to what the RK4 steps
    integrate stably (:mod:`estimate.fitting.stability`) when that converges, with a note.
    The bound is added only then: present from the start it changed IPOPT's path on
    spinning-rig records that converge without it (one then ran 300 iterations)."""
    bounds = rotor_bounds([e.case for e in problem.experiments], problem.model,
                          problem.names)
    if not bounds or any(b.stability for b in problem.linear_bounds):
        return problem, result
    bounded = replace(problem, linear_bounds=problem.linear_bounds + bounds)
    second = solve(bounded)
    iterations = result.iterations + second.iterations
    if not second.converged:
        return problem, replace(result, iterations=iterations)
    note = (f"the fit's simulation overflowed ({result.status} after {result.iterations} "
            f"iterations): solved again from the same start with "
            + "; ".join(b.text for b in bounds))
    bounded = replace(bounded, notes=bounded.notes + (note,))
    return bounded, replace(second, problem=bounded, iterations=iterations)


def _from_first_part(problem: FitProblem, result: FitResult, short: FitProblem, what: str,
                     solve) -> tuple[FitProblem, FitResult]:
    """``problem`` and ``result`` (a solve that did not converge), or the solve of
    ``problem`` from the estimates of ``short`` (its cases' first part, ``what``) when
    both converge, with a note (:mod:`estimate.fitting.segment_start`)."""
    first = solve(short)
    if not first.converged:
        return problem, replace(result, iterations=result.iterations + first.iterations)
    again = problem.with_initial(dict(zip(first.names, first.values)))
    second = solve(again)
    iterations = result.iterations + first.iterations + second.iterations
    if not second.converged:
        return problem, replace(result, iterations=iterations)
    note = (f"the fit from the first stage did not converge ({result.status} after "
            f"{result.iterations} iterations): fitted {what} first ({first.iterations} "
            f"iterations), then the whole record from those estimates")
    again = replace(again, notes=again.notes + (note,))
    return again, replace(second, problem=again, iterations=iterations)


def _better_start(problem: FitProblem, result: FitResult, other: FitProblem, why: str,
                  solve) -> tuple[FitProblem, FitResult]:
    """The problem and solve, of ``problem`` (solved: ``result``) and ``other`` (the same
    from the prediction, solved by ``solve``), that converged to the lower objective, with
    a note saying both were tried."""
    second = solve(other)
    keep = second.converged and (not result.converged or second.objective < result.objective)
    kept, dropped = (second, result) if keep else (result, second)
    note = (f"the fit from the first stage ended with masses far from the prediction ({why}):"
            f" solved from the prediction too; kept the {'prediction' if keep else 'first stage'}'s "
            f"(objective {kept.objective:.6g}; the other {dropped.objective:.6g}"
            f"{'' if dropped.converged else ', not converged'})")
    p, r = (other, second) if keep else (problem, result)
    p = replace(p, notes=p.notes + (note,))
    return p, replace(r, problem=p, iterations=result.iterations + second.iterations)


#: A carriage spline whose knots are more than this many samples apart somewhere (0.25 s at
#: rest on a 500 Hz record: 125) couples each of its coefficients to that many samples'
#: states: MUMPS then factors faster in METIS's nested-dissection order (5) than in QAMD
#: (6). CPU medians of 3, 13.6 s, 500 Hz transport records: 2.39/4.48/2.60/3.94 s ->
#: 1.28/1.85/1.41/2.11 s. QAMD stays where it was chosen (3001-sample records, 48 -> 14 ms
#: of analysis; there METIS was within the noise) and on the spinning rig, whose
#: six-channel rotor fit from the prediction took another path with METIS and did not
#: converge.
WIDE_KNOT_SAMPLES = 25


def _finite(out) -> bool:
    """Whether the residuals and their Jacobian at a solution are numbers."""
    return bool(np.all(np.isfinite(out.e)) and np.all(np.isfinite(out.jacobian.data)))


def _constraint_jacobian(solver: ca.Function, w: np.ndarray):
    """The constraint Jacobian IPOPT used, at ``w``, as a SciPy CSC matrix."""
    return evaluate(solver.get_function("nlp_jac_g"), w, np.zeros(0), sparse=(1,))[1]


def pivot_order(problem: FitProblem) -> int:
    """MUMPS's ordering for ``problem``'s KKT systems (``ipopt.mumps_pivot_order``): METIS
    (5) when a case's carriage spline has knots more than :data:`WIDE_KNOT_SAMPLES`
    samples apart, else QAMD (6)."""
    for ci, e in zip(problem.carriage or (), problem.experiments):
        if ci is not None and float(np.diff(ci.spline.knots).max()) > (
                WIDE_KNOT_SAMPLES * e.case.sample_interval):
            return 5
    return 6


#: A one-mode model (two states per case: a pendulum's angle and rate) is solved first
#: with a node every this many seconds of samples, four times the default grid's: its KKT
#: systems have a quarter of the states, and the same RK4 steps on the same samples give
#: the same discrete model, optimum and covariance (bench_fit's records: the same
#: iterations and estimates to 5 digits, 22 % less time). Where the swing is confounded
#: with the other parameters the longer intervals can leave IPOPT wandering (a 0.4 f1 sine:
#: 300 iterations, against 26 on the default grid), so the coarse solve gets
#: :data:`COARSE_MAX_ITER` iterations and the default grid solves from the start again
#: when it does not converge. Models with more modes keep the default grid (a mode the
#: record lacks wandered off on the coarse one).
COARSE_INTERVAL_SECONDS = 0.08
COARSE_MAX_ITER = 20


def _coarse(problem: FitProblem, transcription: Transcription, hessian: Hessian
            ) -> MultipleShooting | None:
    """The coarser grid :func:`_solve` tries first for ``problem``, or None."""
    if not (isinstance(transcription, MultipleShooting) and hessian.kind == "gauss-newton"
            and transcription.samples_per_interval is None
            and transcription.interval_seconds is None):
        return None
    if any(e.derived.nx != 2 for e in problem.experiments):
        return None
    coarse = replace(transcription, interval_seconds=COARSE_INTERVAL_SECONDS)
    times = [np.asarray(e.case.time, float) for e in problem.experiments]
    same = all(coarse.interval_samples(t) == transcription.interval_samples(t) for t in times)
    return None if same else coarse


def _solve(problem: FitProblem, transcription: Transcription, hessian: Hessian, cost: str,
           kinds: list[str], solver_options: Mapping[str, object] | None, progress: bool,
           compile_: bool | None, warm_start: FitResult | None, t_start: float) -> FitResult:
    """One IPOPT solve of ``problem`` (no refit) and its result: of a one-mode model on a
    coarser grid first (:data:`COARSE_INTERVAL_SECONDS`), on ``transcription`` when that
    does not converge."""
    coarse = _coarse(problem, transcription, hessian)
    if coarse is None:
        return _solve_once(problem, transcription, hessian, cost, kinds, solver_options,
                           progress, compile_, warm_start, t_start)
    options = dict(solver_options or {})
    cap = int(options.get("ipopt.max_iter", IPOPT_DEFAULTS["ipopt.max_iter"]))
    options["ipopt.max_iter"] = min(cap, COARSE_MAX_ITER)
    first = _solve_once(problem, coarse, hessian, cost, kinds, options, progress, compile_,
                        warm_start, t_start)
    if first.converged or cap <= COARSE_MAX_ITER:
        return first
    result = _solve_once(problem, transcription, hessian, cost, kinds, solver_options,
                         progress, compile_, warm_start, t_start)
    note = (f"solved first with a node every {COARSE_INTERVAL_SECONDS * 1e3:.0f} ms: "
            f"{first.status} after {first.iterations} iterations; solved again on the "
            f"default grid from the same start")
    again = replace(problem, notes=problem.notes + (note,))
    return replace(result, problem=again, iterations=result.iterations + first.iterations)


def _solve_once(problem: FitProblem, transcription: Transcription, hessian: Hessian,
                cost: str, kinds: list[str], solver_options: Mapping[str, object] | None,
                progress: bool, compile_: bool | None, warm_start: FitResult | None,
                t_start: float) -> FitResult:
    """One IPOPT solve of ``problem`` on ``transcription`` and its result."""
    est = problem.estimated
    scales = np.array([e.scale for e in est])
    # the exact Hessian differentiates g twice: keep g an AD-able expression then
    blocks_ok = hessian.kind == "gauss-newton"
    nlp, terms = assemble_nlp(problem, transcription, cost, kinds, blocks_ok, compile_,
                              warm_start)
    opts = dict(IPOPT_DEFAULTS)
    opts["ipopt.mumps_pivot_order"] = pivot_order(problem)
    derivatives, f, g_once = nlp.derivative_options(hessian, blocks_ok)
    opts.update(derivatives)
    recorder = Recorder(nlp.w.numel(), nlp.g.numel(), len(est), scales, 2 * nlp.norm,
                         progress_printer(problem.names) if progress else None,
                         stall_stop(problem, int(nlp.r.numel())))
    opts["iteration_callback"] = recorder
    g = nlp.g
    if "jac_g" in opts:
        # IPOPT gets g and its Jacobian from the per-interval functions (compiled when a
        # compiler exists), and CasADi builds no AD of g: nothing asks for it once the
        # multipliers of the (absent) NLP parameters are not computed
        g = nlp.g_fast if g_once is None else g_once
        opts.update({"no_nlp_grad": True, "calc_lam_p": False})
    opts.update(dict(solver_options or {}))
    solver = ca.nlpsol("fit", "ipopt", {"x": nlp.w, "f": f, "g": g}, opts)
    lbx, ubx = nlp.bounds(est)
    lbg, ubg = nlp.constraint_bounds()
    with surfacing():  # an interrupt inside IPOPT is an interruption, not a non-convergence
        sol = solver(x0=nlp.w0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    if progress:
        print(file=sys.stderr)
    w_opt = np.asarray(sol["x"]).ravel()
    # IPOPT may leave a bounded variable a hair outside its bound (its bound_relax_factor)
    theta = np.clip(w_opt[: len(est)] * scales, [e.lower for e in est], [e.upper for e in est])
    Jg = _constraint_jacobian(solver, w_opt)
    nlp.release_buffers()  # the iterates' Jacobians are no longer asked for
    out = nlp.outputs_at(w_opt, cost)
    if not _finite(out) and recorder.last_finite is not None:
        # a fit that diverged (Invalid_Number_Detected: a 60 s spinning-rig record whose
        # simulation overflowed) is reported where it last was finite, not converged
        w_opt = np.asarray(recorder.last_finite).ravel()
        theta = np.clip(w_opt[: len(est)] * scales, [e.lower for e in est],
                        [e.upper for e in est])
        out = nlp.outputs_at(w_opt, cost)
        Jg = _constraint_jacobian(solver, w_opt)
        nlp.release_buffers()
    Je = out.jacobian
    Jg = Jg[: Jg.shape[0] - nlp.n_linear]  # the dynamics; the linear bounds are the masses'
    J = reduced_jacobian(Je, Jg, len(est), scales, list(nlp.free_states))
    initial_states = tuple(
        dict(zip(e.derived.states, np.asarray(x, float).ravel().tolist()))
        for e, x in zip(problem.experiments, nlp.initial_states(w_opt)))
    stats = solver.stats()
    if recorder.stopped:  # the cost stalled (not an interrupt: `surfacing` raises those)
        stats = {**stats, "return_status": STALLED, "success": False}
    return fit_result(problem, Solve(theta, stats, recorder, tuple(terms), out, J, Je,
                                     Jg, t_start, transcription, cost, tuple(kinds),
                                     initial_states))
