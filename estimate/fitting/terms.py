"""One test case as terms of the estimation NLP: its transcribed dynamics, the residuals of
its measured channels (and of the carriage displacement when the input is estimated), and
the data as fitted."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np

from analogs.errors import InputError
from derive import OUTPUT_NAMES, RK4, simulate

from ..data.signals import lowpass
from .problem import FitProblem
from .residual_jacobian import force_residual_jacobian
from .steady import steady_start
from .transcription import Block, InputCoefficients, Transcription

__all__ = ["CaseTerms", "WarmStart", "case_terms"]


def _measured_output(dm, channels: tuple[str, ...], compiled: bool = False) -> ca.Function:
    """``(x, u, p, t) -> y``: the measured ``channels`` (built once per model), compiled
    to C when asked (then without CasADi derivatives)."""
    if compiled:
        from derive import compiled as compile_fn

        return dm.memo(("measured_output_compiled", channels),
                       lambda: compile_fn(_measured_output(dm, channels)))
    return dm.memo(("measured_output", channels),
                   lambda: _measured_output_function(dm, channels))


def _measured_output_function(dm, channels: tuple[str, ...]) -> ca.Function:
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
    labels = [e.name for e in problem.estimated]
    ties = {t.parameter: t for t in problem.ties}
    for name in dm.parameter_names:
        hit = None
        for j, e in enumerate(problem.estimated):
            if e.parameter == name and (e.case is None or e.case == case):
                hit = theta[j] * e.scale
        if name in ties:  # follows the estimates (the fixed liquid of an unweighed tank)
            t = ties[name]
            hit = ca.MX(t.constant) + sum(k * theta[labels.index(n)] * problem.estimated[
                labels.index(n)].scale for n, k in t.terms)
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
    noise = problem.noise[i] if problem.noise else None
    for name in names:
        F = np.asarray(have[name] if noise is None else noise.force, float)
        if problem.force_cutoff_hz is not None:
            F = lowpass(case.time, F, cutoff_hz=problem.force_cutoff_hz)
        for mm in problem.measurement:
            F, wm = mm.measured(case.time, F)
            w = w * wm
        cols.append(F)
    return (cols[0] if len(cols) == 1 else np.column_stack(cols)), w


@dataclass(frozen=True)
class CaseTerms:
    """One case in the NLP.

    ``block`` is its transcription; ``coef`` and ``coef0`` the coefficients of an estimated
    carriage motion (empty otherwise) with their start values. ``r`` is
    the cost residual and ``e`` the residual whose squares the covariance uses (``= r`` for
    the squared cost): force residuals divided by their scale, then displacement residuals
    divided by the displacement noise. ``raw`` is ``Y - F`` (N, N m; channel-major) and
    ``report`` the force residual in the units of the fit report (weighted, scaled).
    ``jacobian``, when assembled, is ``(d r / d theta, d r / d (block.w, coef))``
    (:mod:`estimate.fitting.residual_jacobian`); ``None``: CasADi differentiates ``r``."""

    block: Block
    coef: ca.MX
    coef0: np.ndarray
    r: ca.MX
    e: ca.MX
    raw: ca.MX
    report: ca.MX
    measured: np.ndarray
    weights: np.ndarray
    scaled_measured: np.ndarray
    free_initial_state: bool
    carriage: ca.MX | None
    displacement_residual: ca.MX | None
    jacobian: tuple[ca.MX, ca.MX] | None = None


def case_terms(problem: FitProblem, i: int, theta_s: ca.MX, transcription: Transcription,
               cost: str, initial_state: str, blocks_ok: bool, compile_: bool,
               warm: "WarmStart | None" = None) -> CaseTerms:
    exp = problem.experiments[i]
    dm, case = exp.derived, exp.case
    t = np.asarray(case.time, float)
    n = t.size
    p_i = _parameter_column(dm, problem.fixed[i], theta_s, problem, i)
    carriage = problem.carriage[i] if problem.carriage else None
    coefficients = None
    if carriage is not None:
        if dm.inputs != _CARRIAGE_INPUTS:
            raise InputError(f"an estimated carriage motion drives the inputs "
                             f"{', '.join(_CARRIAGE_INPUTS)}; the model takes {', '.join(dm.inputs)}")
        c = ca.MX.sym(f"carriage{i}", carriage.n_coefficients)
        fr = transcription.fractions()
        S_stage, S_grid = carriage.scipy_matrices(t, fr)
        # the stage inputs U are the transcription's to make from the coefficients
        U, Ug = None, None
        coefficients = InputCoefficients(c, S_stage, dm.nu * fr.size, S_grid,
                                         lambda: carriage.casadi_matrix(t, fr, "stage"),
                                         carriage.grid_cache(t, fr))
        coef0 = carriage.coefficients
        lag0 = _lag_value(problem, i)
        if warm is not None and warm.carriage is not None and warm.carriage.size == coef0.size:
            coef0 = warm.carriage
        elif lag0:
            from .measurement import StreamLag

            order = next(m.order for m in problem.measurement if isinstance(m, StreamLag))
            coef0 = lag_start(carriage, t, lag0, order)
        excitation = carriage.excitation(coef0)
        coef = c
    else:
        excitation = exp.excitation
        U = ca.DM(transcription.inputs(excitation, t, dm.nu))
        Ug = ca.DM(excitation.values(t) if dm.nu else np.zeros((0, n)))
        coef, coef0 = ca.MX(0, 1), np.zeros(0)
    if warm is not None and warm.coordinates == dm.coordinates and warm.states is not None:
        guess = warm.states
    elif dm.nx:
        values0 = problem.case_values(i, problem.initial)
        start = exp.initial_state(values0) if initial_state == "steady" else None
        guess = simulate(dm, values0, t, excitation, integrator=RK4(), x0=start).states.T
    else:
        guess = np.zeros((0, n))
    x0 = np.zeros(dm.nx) if initial_state == "rest" else None
    block = transcription.block(dm, p_i, t, U, guess, x0, theta=theta_s if blocks_ok else None,
                                compiled=compile_, coefficients=coefficients)
    if carriage is not None:
        Ug = block.grid_inputs
        if Ug is None:
            Ug = ca.reshape(ca.mtimes(carriage.casadi_matrix(t, fr, "grid"), c), dm.nu, n)
    if initial_state == "steady" and dm.nx:
        u0 = excitation.values(t[:1]) if dm.nu else np.zeros((0, 1))
        block = steady_start(block, dm, p_i, theta_s, np.asarray(u0).ravel(), float(t[0]),
                             coef.numel())
    chans = problem.channels(i)
    assembled = cost == "squared" and blocks_ok and block.jac_w is not None and dm.nx
    # with the residual Jacobian assembled nothing differentiates Y: its states may come
    # from compiled steps
    fast = bool(assembled and compile_)
    Xy = block.X_fast if fast and block.X_fast is not None else block.X
    Y = dm.mapped(("measured_output", chans, fast), _measured_output(dm, chans, fast), n)(
        Xy, Ug, p_i, ca.DM(t).T).T
    mvals = {e.parameter: theta_s[j] * e.scale for j, e in enumerate(problem.estimated)
             if e.case in (None, i)}
    # the measurement terms of the inputs on the samples as a symbol (their Jacobians
    # below are taken w.r.t. it), then at the inputs
    Us = ca.MX.sym("u", dm.nu * n)
    termed = [x for mm in problem.measurement
              if (x := mm.term(ca.reshape(Us, dm.nu, n), dm.inputs, mvals, t)) is not None]
    extras = [ca.substitute(x, Us, ca.vec(Ug)) for x in termed]
    for extra in extras:
        Y = Y + extra
    F, wts = _measured_force(problem, i)
    scale = problem.channel_scales(i)
    s = np.array([scale[ch] for ch in chans])
    F2 = F.reshape(n, len(chans), order="F")
    # channel-major: each channel divided by its scale, so N and N m are comparable
    Yv = ca.vec(Y / ca.repmat(ca.DM(s).T, n, 1))
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
        e = e * ca.DM(wv)
        r = e if cost == "squared" else r * ca.DM(wv)
    # the fit report keeps its units: N for a lateral force, channel RMS for several channels
    report_scale = np.array([problem.report_scale(i, ch) for ch in chans])
    report = raw / ca.DM(np.repeat(report_scale, n)) * ca.DM(wv)
    scaled_measured = (F2 / report_scale[None, :]).ravel(order="F")
    x_resid = None
    lag = _stream_lag(problem, i, theta_s)
    if carriage is not None:
        if lag is None:
            shifted = carriage.casadi_matrix(t, transcription.fractions(), "displacement")
        else:  # the recorded displacement is the spline `lag` later: its Taylor series
            pattern, V = carriage.shift_design(t, lag[2].order)
            powers = ca.vertcat(1, *[lag[0] ** d for d in range(1, V.size2())])
            shifted = ca.MX(pattern, ca.mtimes(V, powers))
        x_resid = ca.mtimes(shifted, coef) - ca.DM(carriage.displacement)
        ex = x_resid / carriage.displacement_noise
        e = ca.vertcat(e, ex)
        r = e if cost == "squared" else ca.vertcat(r, ex)
    jac = None
    if assembled:
        factor = wv / np.repeat(s, n)
        if block.state_jacobian is not None:  # states simulated from coarser nodes
            from .condensed import residual_jacobian

            jt, jx, jc = residual_jacobian(dm, chans, block.state_jacobian, Ug,
                                           theta_s.numel(), t, factor, compile_)
        else:
            jt, jx, jc = force_residual_jacobian(
                dm, chans, block.X, Ug, p_i, theta_s, t, factor, initial_state == "rest",
                compile_, None if carriage is None
                else carriage.casadi_matrix(t, transcription.fractions(), "grid"))
        if extras:
            # the terms differentiated w.r.t. the inputs on the samples as a symbol, then
            # chained with the inputs' (constant) Jacobian: CasADi's AD through the
            # estimated inputs' expression took 1.2 s on a 30,001-sample record
            ye = sum(termed[1:], termed[0])
            if ye.shape != Y.shape:  # a term of one column added to every channel
                ye = ca.repmat(ye, 1, len(chans)) if ye.size2() == 1 else ca.repmat(ye, n, 1)
            ye = ca.vec(ye) * ca.DM(factor)
            jt = jt + ca.substitute(ca.jacobian(ye, theta_s), Us, ca.vec(Ug))
            ju = ca.jacobian(ye, Us)
            if carriage is not None and ju.nnz():
                jc = jc + ca.mtimes(ca.substitute(ju, Us, ca.vec(Ug)), carriage.casadi_matrix(
                    t, transcription.fractions(), "grid"))
        jlocal = ca.horzcat(jx, jc if jc is not None else ca.MX(jx.size1(), 0))
        if carriage is not None:
            nd = carriage.displacement.size
            sx = carriage.displacement_noise
            jt_x = ca.MX(nd, jt.size2())
            if lag is not None:  # d x_rec / d lag: the shifted spline's velocity
                tau, j, mm = lag
                pattern, V = carriage.shift_design(t, mm.order)
                rates = ca.vertcat(0, 1, *[d * tau ** (d - 1) for d in range(2, V.size2())])
                velocity = ca.MX(pattern, ca.mtimes(V, rates))
                scale_j = problem.estimated[j].scale
                jt_x = ca.horzcat(ca.MX(nd, j), ca.mtimes(velocity, coef) * (scale_j / sx),
                                  ca.MX(nd, jt.size2() - j - 1))
            jt = ca.vertcat(jt, jt_x)
            jlocal = ca.vertcat(jlocal, ca.horzcat(ca.MX(nd, jx.size2()), shifted / sx))
        jac = (jt, jlocal)
    return CaseTerms(block, coef, coef0, r, e, raw, report, F, wts,
                     scaled_measured, initial_state == "free" and dm.nx > 0,
                     None if carriage is None else ca.reshape(Ug, dm.nu, n), x_resid, jac)


def _lag_value(problem: FitProblem, i: int) -> float:
    """The start value of case ``i``'s stream lag [s] (0 when not estimated)."""
    return next((e.initial for e in problem.estimated
                 if e.parameter == "rig.lag" and e.case in (None, i)), 0.0)


def _stream_lag(problem: FitProblem, i: int, theta_s: ca.MX):
    """``(lag, index, model)`` when case ``i``'s stream lag is estimated (its value as an
    expression of the scaled estimates, its index among them, the
    :class:`~estimate.fitting.measurement.StreamLag`), else ``None``."""
    from .measurement import StreamLag

    mm = next((m for m in problem.measurement if isinstance(m, StreamLag)), None)
    if mm is None:
        return None
    for j, e in enumerate(problem.estimated):
        if e.parameter == "rig.lag" and e.case in (None, i):
            return theta_s[j] * e.scale, j, mm
    return None


def lag_start(carriage, times: np.ndarray, lag: float, order: int) -> np.ndarray:
    """Start coefficients of the carriage spline when the displacement stream leads the
    force by ``lag`` seconds: the least-squares spline ``s`` with ``s(t + lag) = x_rec(t)``."""
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    designs = carriage.taylor_designs(times, order)
    B = sum((lag**d * designs[d] for d in range(1, order + 1)), designs[0])
    A = (B.T @ B).tocsc()
    A = A + 1e-10 * A.diagonal().mean() * sps.identity(A.shape[0], format="csc")
    return np.asarray(spla.spsolve(A, B.T @ carriage.displacement)).ravel()


@dataclass(frozen=True)
class WarmStart:
    """Where a case's NLP variables start: the states ``(nx, samples)`` of a previous
    solution (used when its coordinates are this model's) and its carriage coefficients."""

    coordinates: tuple[str, ...]
    states: np.ndarray | None
    carriage: np.ndarray | None


#: The inputs an estimated carriage motion supplies, in the order of its spline's rows.
_CARRIAGE_INPUTS = ("rig.x", "rig.x_dot", "rig.x_ddot")
