"""The refits after a solve: without the liquid bound when the fit ended on it, inside
the tank's ranges when the analog left its tank, with the force reweighed by its noise
figure, with the displacement noise rebalanced (:func:`refined`)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

from .budget import BUDGET_RTOL
from .noise_figures import reweighed
from .problem import FitProblem
from .result import FitResult
from .transcription import Transcription
from .vanished import HELD_STATUSES, held_refit

if TYPE_CHECKING:
    from .nlp import Hessian

__all__ = ["FREE_RETRY_MIN_ITERATIONS", "refined"]

#: Iterations a fit that ended on a liquid bound gives its refit without the bound, at least
#: (twice the bounded fit's otherwise; see :func:`_without_linear_bounds`).
FREE_RETRY_MIN_ITERATIONS = 40


def refined(problem: FitProblem, result: FitResult, *, transcription: Transcription,
            hessian: Hessian, cost: str, initial_state: str | None,
            solver_options: Mapping[str, object] | None, progress: bool,
            compile_: bool | None, warm_start: FitResult | None, balance: bool,
            free_retry: bool, t_start: float, unbounded_retry: bool = True,
            hold_undetermined: bool = True) -> FitResult:
    """``result`` (a solve of ``problem``), or the refit that replaces it.

    Parameters
    ----------
    problem : FitProblem
        The problem solved (with its robust start).
    result : FitResult
        Its solve.
    transcription, hessian, cost, initial_state, solver_options, progress, compile_, \
warm_start, balance
        The options of :func:`~estimate.fitting.nlp.fit`, passed to the refits.
    free_retry : bool
        Whether the refits without the liquid bound and inside the tank may run (not
        inside a refit).
    unbounded_retry : bool
        Whether the refit without the liquid bound may run (``fit``'s option).
    hold_undetermined : bool
        Whether a fit that did not converge is refitted with the parameters of a mode the
        record does not determine held (:mod:`estimate.fitting.vanished`; ``fit``'s
        option).
    t_start : float
        ``time.perf_counter()`` when the fit started [s]: a refit's result counts the
        time since.
    """
    from .nlp import IPOPT_DEFAULTS, fit

    liquid_active = any(b.text in result.active_bounds for b in problem.linear_bounds
                        if not b.stability)
    if result.converged and liquid_active and free_retry and unbounded_retry:
        # the free fit gets a few times the bounded one's iterations: one that wants more
        # mass than the liquid walks far (a diagnosis baseline lacking two effects: 300
        # iterations, 24 s, to be discarded)
        budget = {**dict(solver_options or {}), "ipopt.max_iter": min(
            int(dict(solver_options or {}).get("ipopt.max_iter", IPOPT_DEFAULTS["ipopt.max_iter"])),
            max(2 * result.iterations, FREE_RETRY_MIN_ITERATIONS))}
        other = _without_linear_bounds(problem, result, transcription=transcription,
                                       hessian=hessian, cost=cost, initial_state=initial_state,
                                       solver_options=budget, progress=progress,
                                       compile_=compile_, warm_start=warm_start, balance=balance,
                                       _free_retry=False)
        if other is not None:
            return replace(other, iterations=result.iterations + other.iterations,
                           seconds=time.perf_counter() - t_start)
    if result.converged and result.outside_tank and free_retry:
        inside = _inside_the_tank(problem, result, transcription=transcription,
                                  hessian=hessian, cost=cost, initial_state=initial_state,
                                  solver_options=solver_options, progress=progress,
                                  compile_=compile_, balance=balance, _free_retry=False)
        if inside is not None:
            return replace(inside, iterations=result.iterations + inside.iterations,
                           seconds=time.perf_counter() - t_start)
    if result.status in HELD_STATUSES and free_retry and hold_undetermined:
        held = held_refit(problem, result.values, result.status, result.iterations)
        if held is not None:
            again, note = held
            again = replace(again, notes=again.notes + (note,))
            second = fit(again, transcription=transcription, hessian=hessian, cost=cost,
                         initial_state=initial_state, solver_options=solver_options,
                         progress=progress, robust_start=False, compile_=compile_,
                         warm_start=result, balance=balance, _free_retry=False)
            return replace(second, iterations=result.iterations + second.iterations,
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
    from .nlp import fit

    kept = tuple(b for b in problem.linear_bounds if b.stability)  # the RK4's stay
    free = fit(replace(problem, linear_bounds=kept), **options)
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
    from .nlp import fit

    res = fit(bounded, warm_start=outside, robust_start=False, **options)
    if not res.converged:
        return None
    note = ("the analog left its tank in a fit without the tank's ranges as bounds ("
            + "; ".join(outside.outside_tank) + "); refitted within them")
    return replace(res, problem=replace(res.problem, notes=res.problem.notes + (note,)))
