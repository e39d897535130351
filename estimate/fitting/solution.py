"""What a solve of the NLP gives, named (:class:`Solve`), and the :class:`FitResult` made
from it: covariances held on active bounds and widened by the model error, warnings, noise
figures, derived quantities."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sps

from ..data.decimation import noise_band
from ._progress import Recorder
from .assembly import NlpOutputs
from .covariance import uncertainty
from .mode_conflicts import mode_conflicts
from .noise_figures import case_figures, model_error_factor
from .problem import FitProblem
from .result import FitResult, derived_jacobian, derived_quantities, derived_shifts, reach_sides
from .terms import CaseTerms
from .transcription import Transcription

__all__ = ["LOW_R_SQUARED", "Solve", "fit_result"]

#: A fit whose R^2 (fraction of the measurement's variance the model explains) is below this
#: says so in a warning: a force column of pure noise fits "converged" with R^2 near 0.
LOW_R_SQUARED = 0.1

_IPOPT_HINTS = {
    "Maximum_Iterations_Exceeded": "raise `ipopt.max_iter` in solver_options, or start closer "
                                    "(check [prediction] and the drive frequency)",
    "Restoration_Failed": "the initial guess is far from feasible: check the excitation and the "
                          "initial values",
    "Infeasible_Problem_Detected": "bounds exclude every solution: widen `bounds`",
    "Stalled": "the cost changed by less than the noise over many iterations: the record does "
               "not determine some parameters (hold them, or drop what the record does not show)",
    "Invalid_Number_Detected": "a parameter reached a value where the model is undefined: "
                               "tighten bounds",
}


@dataclass(frozen=True)
class Solve:
    """One IPOPT solve of a problem, by name: what :func:`fit_result` reads.

    Attributes
    ----------
    theta : ndarray
        The estimates (SI units, clipped into their bounds).
    stats : dict
        IPOPT's statistics (``return_status``, ``success``, ``iter_count``).
    recorder : Recorder
        The iterations' parameters and costs.
    terms : tuple of CaseTerms
        Per case, its terms of the NLP.
    outputs : NlpOutputs
        Residuals, states and carriage motions at the solution.
    sensitivity : ndarray
        The residuals' Jacobian reduced to the parameters (:func:`reduced_jacobian`).
    jac_e, jac_g : scipy.sparse matrix
        ``de/dw`` and the dynamics' ``dg/dw`` (linear bounds left out).
    t_start : float
        ``time.perf_counter()`` when the fit started [s].
    transcription : Transcription
        How the dynamics entered.
    cost_kind : str
        The cost's name (``"squared"`` or ``"abs"``).
    initial_state_kinds : tuple of str
        Per case, ``"rest"``, ``"steady"`` or ``"free"``.
    initial_states : tuple of dict
        Per case, the states at the first sample by state name (SI units).
    """

    theta: np.ndarray
    stats: dict
    recorder: Recorder
    terms: tuple[CaseTerms, ...]
    outputs: NlpOutputs
    sensitivity: np.ndarray
    jac_e: sps.spmatrix
    jac_g: sps.spmatrix
    t_start: float
    transcription: Transcription
    cost_kind: str
    initial_state_kinds: tuple[str, ...] = ()
    initial_states: tuple[dict[str, float], ...] = ()


def fit_result(problem: FitProblem, solve: Solve) -> FitResult:
    """The :class:`FitResult` of one solve of ``problem``: estimates, covariances (held on
    active bounds, widened by the model error), warnings, noise figures and the named
    quantities of the solution."""
    terms, out = solve.terms, solve.outputs
    theta, stats, recorder = solve.theta, solve.stats, solve.recorder
    e, raw, report = out.e, out.raw, out.report
    J, Je, Jg = solve.sensitivity, solve.jac_e, solve.jac_g
    displacement_residuals = out.displacement_residuals
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
    # an estimate on a band's edge is not held (Estimated.band): the others' covariance
    # allows for it, and its spread away from the edge is its own standard error
    held = np.array([bool(side) and not x.band for side, x in zip(at_bound, problem.estimated)])
    unc = uncertainty(Je, Jg, e, n_force + n_disp, theta.size,
                      np.array([x.scale for x in problem.estimated]), problem.names,
                      held=tuple(np.flatnonzero(held)), samples=samples,
                      bands=[noise_band(x.case) for x in problem.experiments])
    edge = [i for i, side in enumerate(at_bound) if side and not held[i]]
    if edge:
        spread = np.full(theta.size, np.nan) if unc.bound_stderr is None else unc.bound_stderr.copy()
        c = unc.robust if unc.robust is not None else unc.covariance
        spread[edge] = np.sqrt(np.clip(np.diag(c)[edge], 0, None))
        unc = replace(unc, bound_stderr=spread)
    active = tuple(b for b in problem.linear_bounds if _on_linear_bound(b, problem, theta))
    if active:
        unc = _held_on(unc, np.array([b.row(problem.names) for b in active]))
    warnings = list(unc.warnings)
    for b in active:
        if b.stability:
            warnings.append(f"the estimates end on the bound {b.text}: the record does not "
                            "resolve a faster spin-up (the rotor acts as a damper there); "
                            "held there in the covariance")
        else:
            warnings.append(f"the estimates end on the bound {b.text}: the data ask for more "
                            "mass than the liquid holds (check the dry mass, the fill and the "
                            "density, or a mode the model lacks); held there in the covariance")
    status = stats.get("return_status", "unknown")
    converged = bool(stats.get("success", False))
    if not converged:
        hint = _IPOPT_HINTS.get(status, "see IPOPT's status; try other initial values")
        warnings.append(f"IPOPT did not converge ({status}): {hint}")
    for x, v, side in zip(problem.estimated, theta, at_bound):
        if side and x.band:
            warnings.append(f"`{x.name}` = {v:.6g} {x.unit} is at the edge of its band "
                            f"[{x.lower:.6g}, {x.upper:.6g}] around the prediction: the data "
                            "do not place it inside; the other intervals allow for its "
                            "freedom (not held there)")
        elif side:
            warnings.append(f"`{x.name}` = {v:.6g} {x.unit} is at its bound "
                            f"[{x.lower:.6g}, {x.upper:.6g}]: no standard error, held there in "
                            "the covariance; the intervals of the estimates that move with it "
                            "reach off the bound")
    F_all = np.concatenate([t.scaled_measured[np.tile(t.weights, c) > 0]
                            for t, c in zip(terms, nch)])
    ssr = float(report @ report)
    r_squared = 1 - ssr / float(np.sum((F_all - F_all.mean()) ** 2))
    if not r_squared >= LOW_R_SQUARED:
        warnings.append(f"the model explains almost nothing of the measurement (R^2 = "
                        f"{r_squared:.3g}): the record may hold noise only, a channel of "
                        "another quantity, or a drive that does not excite the model; check it "
                        "before using these estimates")
    pieces = np.split(raw, np.cumsum([int(np.size(m)) for m in measured])[:-1])
    residuals = tuple(p if np.ndim(m) == 1 else p.reshape(m.shape, order="F")
                      for p, m in zip(pieces, measured))
    figures = tuple(case_figures(problem, i, r, w)
                    for i, (r, w) in enumerate(zip(residuals, weights)))
    robust, widen = unc.robust, 1.0
    if robust is not None:
        widen = model_error_factor(figures, residuals, tuple(weights))
        robust = robust * widen**2
    # the intervals use the robust covariance: the Gauss-Newton one when the residuals are
    # white, wider when they are correlated (coloured noise, a filtered force, a model that
    # misses a small effect), where the Gauss-Newton one is optimistic
    kind = "robust" if robust is not None else "gauss-newton"
    cov = robust if robust is not None else unc.covariance
    # the sandwich's products leave it asymmetric by rounding (1e-8 relative seen)
    cov = 0.5 * (cov + cov.T)
    free = np.array([side is None for side in at_bound])
    stderr = np.where(free, np.sqrt(np.clip(np.diag(cov), 0, None)), np.nan)
    # the held estimates' regression columns, signed away from their bounds; the model error
    # widens the spread off the bounds as it widens the rest
    away = np.array([{"lower": 1.0, "upper": -1.0}.get(side, 0.0) if h else 0.0
                     for side, h in zip(at_bound, held)])
    reach = None if unc.bound_reach is None else widen * unc.bound_reach * np.r_[
        away, np.ones(unc.bound_reach.shape[1] - away.size)][None, :]
    bound_stderr = None if unc.bound_stderr is None else widen * unc.bound_stderr
    jacobian = derived_jacobian(problem, theta)
    derived, derived_units, derived_reach = derived_quantities(problem, theta, cov, held, reach,
                                                               jacobian)
    conflicts = mode_conflicts(problem, theta, stderr, cov, {k: v[0] for k, v in derived.items()})
    warnings += [c.message for c in conflicts if c.message]
    # a pendulum far heavier than its tank mode may stand for something else: the intervals
    # reach to where the estimates go when its mass is put at the mode's prediction
    mode_shifts = tuple((f"`{c.name}` at its tank mode's {c.predicted:.3g} kg",
                         np.where(free, c.shift(theta, cov), 0.0)) for c in conflicts)
    derived_mode_reach = derived_shifts(jacobian, np.column_stack(
        [m for _, m in mode_shifts])) if mode_shifts else {}
    return FitResult(
        problem=problem,
        values=theta, stderr=stderr, covariance=cov,
        cost=ssr, rms_residual=math.sqrt(ssr / n_force),
        r_squared=r_squared,
        n_samples=n_force, iterations=int(stats.get("iter_count", len(recorder.costs))),
        seconds=time.perf_counter() - solve.t_start, converged=converged, status=status,
        warnings=tuple(warnings), identifiability=unc.identifiability,
        derived=derived, derived_units=derived_units,
        history=np.array(recorder.thetas), cost_history=np.array(recorder.costs),
        residuals=residuals,
        channels=tuple(problem.channels(i) for i in range(len(measured))),
        channel_scales=tuple({c: problem.report_scale(i, c) for c in problem.channels(i)}
                             for i in range(len(measured))),
        sensitivity=J,
        weights=tuple(weights),
        measured=tuple(measured), cost_kind=solve.cost_kind,
        transcription=solve.transcription.describe([e.case.time for e in problem.experiments]),
        carriage=out.carriage, displacement_residuals=displacement_residuals,
        states=out.states, carriage_coefficients=out.coefficients,
        objective=float(e @ e), residual_variance=unc.sigma2,
        dof=max(n_force + n_disp - (Je.shape[1] - Jg.shape[0]), 1),
        initial_state_kinds=solve.initial_state_kinds, initial_states=solve.initial_states,
        at_bound=at_bound, bound_stderr=bound_stderr,
        bound_reach=None if reach is None else np.where(free[:, None], reach_sides(reach), 0.0),
        bound_directions=_directions(problem, reach, held, bound_stderr, active),
        derived_reach=derived_reach,
        mode_shifts=mode_shifts, derived_mode_reach=derived_mode_reach,
        active_bounds=tuple(b.text for b in active), noise_figures=figures,
        gauss_newton_covariance=unc.covariance, robust_covariance=robust,
        covariance_kind=kind, bandwidths=unc.bandwidths, model_error=widen,
    )


def _directions(problem: FitProblem, reach: np.ndarray | None, held: np.ndarray,
                bound_stderr: np.ndarray | None, active) -> tuple[tuple[str, np.ndarray], ...]:
    """:attr:`FitResult.bound_directions` from the reach columns (one per estimate, then one
    per active linear bound): those of held estimates the data determine, and the linear
    bounds'."""
    if reach is None:
        return ()
    n = len(problem.names)
    out = [(problem.names[h], reach[:, h].copy()) for h in range(n)
           if held[h] and bound_stderr is not None and np.isfinite(bound_stderr[h])
           and np.any(reach[:, h])]
    out += [(b.text, reach[:, n + k].copy()) for k, b in enumerate(active)]
    return tuple(out)


def _on_linear_bound(bound, problem: FitProblem, theta: np.ndarray) -> bool:
    """Whether ``theta`` ends on the linear ``bound`` (slack within 1e-4 of its upper)."""
    return bound.slack(problem.names, theta) <= 1e-4 * max(abs(bound.upper), 1e-12)


def _held_on(unc, rows: np.ndarray):
    """``unc`` with its covariances (Gauss-Newton and robust) conditioned on the active
    linear bounds ``rows``
    (:func:`estimate.fitting.budget.conditioned`), standard errors and correlations anew,
    and the reach off them appended to ``bound_reach``: the estimates' joint regression on
    the rows' values, one standard deviation of each into the bound (the truth may be just
    inside: a liquid not quite all in the analog)."""

    from .budget import conditioned

    free = np.isfinite(unc.stderr)
    C = unc.covariance[np.ix_(free, free)]
    A = rows[:, free]
    M = A @ C @ A.T
    inside = np.zeros((free.size, rows.shape[0]))
    inside[free] = -(C @ A.T @ np.linalg.pinv(M)) * np.sqrt(np.clip(np.diag(M), 0, None))
    before = np.zeros((free.size, free.size)) if unc.bound_reach is None else unc.bound_reach

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
    return replace(unc, covariance=cov, stderr=se, correlation=corr, robust=robust,
                   bound_reach=np.hstack([before, inside]))


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
