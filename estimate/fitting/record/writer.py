"""A fit result as the JSON record that ``slosh fit`` writes (:data:`SCHEMA`): the estimates
with their standard errors and intervals, the covariances, the derived quantities, the
statistics with AIC and BIC, the noise figures, the solver's status and the provenance."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .provenance import provenance

if TYPE_CHECKING:  # pragma: no cover
    from ..result import FitResult

__all__ = ["SCHEMA", "fit_json", "fit_record", "information_criteria"]

#: The layout of the fit record: ``"slosh-analogs/fit"`` and its version. Version 1 is
#: every file written before the record carried ``"schema"`` (no provenance).
SCHEMA = "slosh-analogs/fit/2"


def _number(x: float) -> float | None:
    """NaN and infinities (no standard error, an open bound) are written as null."""
    return float(x) if math.isfinite(x) else None


def information_criteria(result: "FitResult") -> dict[str, Any]:
    """Akaike's and the Bayesian information criterion of ``result``, up to a constant that
    is the same for every fit of the same records: ``AIC = -2 log L + 2 k`` and
    ``BIC = -2 log L + k log n`` with ``n`` the fitted samples and ``k`` the estimates.
    ``-2 log L`` is the objective when the residuals are divided by their noise figures
    (the estimated input), else ``n log(cost / n)`` (lmfit's form). Lower is better; only
    differences between fits of the same records mean anything."""
    n = int(result.n_samples)
    k = len(result.names)
    weighted = any(x is not None for x in (result.problem.noise or ()))
    if weighted:
        m2ll, form = float(result.objective), "objective (residuals in units of their noise)"
    else:
        m2ll, form = n * math.log(result.cost / n), "n log(cost / n)"
    return {"aic": m2ll + 2 * k, "bic": m2ll + k * math.log(n), "samples": n, "estimates": k,
            "minus_two_log_likelihood": m2ll, "likelihood": form}


def _noise_dict(carriage: Any, noise: Any, rate_hz: float) -> dict[str, Any] | None:
    """Noise levels (per sample of the fitted record, sampled at ``rate_hz``), tones and the
    carriage estimate's settings of one case."""
    if noise is None:
        return None
    out: dict[str, Any] = {"force_noise_N": noise.force_noise, "sample_rate_hz": rate_hz,
                           "band_hz": noise.band_hz,
                           "force_tones": [{"hz": f, "amplitude_N": a} for f, a in noise.tones]}
    if carriage is not None:
        out |= {"displacement_noise_m": carriage.displacement_noise,
                "displacement_tones": [{"hz": f, "amplitude_m": a}
                                       for f, a in carriage.displacement_tones],
                "knot_spacing_s": carriage.spline.spacing, "starts_at_rest": carriage.at_rest}
    return out


def _derived_intervals(result: "FitResult") -> dict[str, list[float | None]]:
    """95 % interval of each derived quantity (:meth:`FitResult.derived_interval`); null
    where there is no standard error."""
    return {k: [_number(x) for x in result.derived_interval(k)] for k in result.derived}


def _parameters(result: "FitResult") -> dict[str, Any]:
    params: dict[str, Any] = {}
    free = result.free
    gn_se, rb_se = result.gauss_newton_stderr, result.robust_stderr
    for i, (name, v, se, e) in enumerate(zip(result.names, result.values, result.stderr,
                                             result.problem.estimated)):
        lo, hi = result.interval(name)
        params[name] = {"value": float(v), "stderr": float(se) if free[i] else None,
                        "stderr_gauss_newton": _number(gn_se[i]),
                        "stderr_robust": _number(rb_se[i]),
                        "interval_95": [_number(lo), _number(hi)],
                        "unit": e.unit, "lower": _number(e.lower),
                        "upper": _number(e.upper), "estimated": True}
        if not free[i]:
            params[name] |= {"at_bound": result.at_bound[i],
                             "one_sided_95": result.one_sided_limit(name)}
    units = {p.name: p.unit for p in result.problem.experiments[0].derived.parameters}
    for name, (v, se, text) in result.tied().items():
        params[name] = {"value": v, "stderr": se, "unit": units.get(name, ""),
                        "estimated": False, "tied": text}
    needed = set(result.problem.experiments[0].derived.needed_parameters())
    for name, v in result.problem.fixed[0].items():
        if name not in params and name in needed and v is not None and math.isfinite(v):
            params[name] = {"value": float(v), "stderr": None, "unit": units.get(name, ""),
                            "estimated": False}
    return params


def fit_record(result: "FitResult", *, model_spec: str | None = None,
               options: Mapping[str, Any] | None = None, command: str | None = None,
               warnings: Sequence[str] = ()) -> dict[str, Any]:
    """The JSON record of ``result`` (a dict of JSON values; NaN where there is none).

    Parameters
    ----------
    result : FitResult
        The fit.
    model_spec : str, optional
        The model specification as the user gave it (``--model``), kept in the provenance;
        the record's ``model_spec`` is the specification that rebuilds the fitted model
        (:meth:`analogs.Model.spec`: as given when the model was built from one), or this
        one when the model has no specification.
    options : mapping, optional
        The options of the command that made the fit, kept in the provenance.
    command : str, optional
        The command that made the fit (``"slosh fit"``).
    warnings : sequence of str, default ()
        Warnings about the inputs that the fit itself does not hold (the case files'
        ``[prediction]`` against the tank's), listed before the fit's own.

    Examples
    --------
    >>> record = fit_record(result, model_spec="fixed,p1:nospring")   # doctest: +SKIP
    >>> record["schema"], record["parameters"]["p1.mass"]["interval_95"]   # doctest: +SKIP
    ('slosh-analogs/fit/2', [1.2958, 1.3044])
    """
    problem = result.problem
    model = problem.model
    free = result.free
    experiments = problem.experiments
    n = len(experiments)
    return {
        "schema": SCHEMA,
        "model": model.names,
        "model_spec": model.spec() or model_spec or ",".join(model.names),
        "cases": [str(e.case.path) for e in experiments],
        "parameters": _parameters(result),
        # estimates at a bound have no covariance: both matrices hold the others only
        "covariance": {"parameters": [nm for nm, f in zip(result.names, free) if f],
                       "matrix": result.covariance[np.ix_(free, free)].tolist(),
                       # how the estimates move off each bound the covariance holds, per
                       # standard deviation (FitResult.bound_directions)
                       "off_bounds": [{"bound": label,
                                       "move": {nm: float(v) for nm, v in zip(result.names, col)
                                                if v != 0.0}}
                                      for label, col in result.bound_directions],
                       # how the estimates move when a pendulum far heavier than its tank
                       # mode is put at the prediction (FitResult.mode_shifts); the
                       # intervals reach that far
                       "to_predicted_modes": [{"mode": label,
                                               "move": {nm: float(v) for nm, v in
                                                        zip(result.names, col) if v != 0.0}}
                                              for label, col in result.mode_shifts]},
        "correlation": result.correlation[np.ix_(free, free)].tolist(),
        "initial_states": {e.case.test.id: dict(x) for e, x in
                           zip(experiments, result.initial_states)},
        "initial_state": {e.case.test.id: k for e, k in
                          zip(experiments, result.initial_state_kinds)},
        "derived": {k: v for k, (v, _) in result.derived.items()},
        "derived_stderr": {k: _number(se) for k, (_, se) in result.derived.items()},
        "derived_units": dict(result.derived_units),
        "derived_interval_95": _derived_intervals(result),
        "cost": result.cost,
        "rms_residual": result.rms_residual,
        "r_squared": result.r_squared,
        "information_criteria": information_criteria(result),
        "iterations": result.iterations,
        "seconds": result.seconds,
        "converged": result.converged,
        "status": result.status,
        "verdict": result.verdict,
        "at_bound": list(result.bounds_reached),
        "outside_tank": list(result.outside_tank),
        "first_stage": None if problem.first_stage is None else problem.first_stage.to_dict(),
        "confounded": result.confounded(),
        "warnings": [*warnings, *result.warnings],
        "input": problem.input,
        "transcription": result.transcription,
        "cost_kind": result.cost_kind,
        "covariance_note": result.covariance_note(),
        "notes": list(problem.notes),
        "covariance_kind": result.covariance_kind,
        "covariance_gauss_newton": None if result.gauss_newton_covariance is None else
        result.gauss_newton_covariance[np.ix_(free, free)].tolist(),
        "newey_west_lags": list(result.bandwidths),
        "model_error_factor": result.model_error,
        "residual_variance": result.residual_variance,
        "noise_figures": [{c: f.to_dict() for c, f in figs.items()}
                          for figs in result.noise_figures],
        "residual_over_noise": [_number(result.residual_over_noise(i))
                                for i in range(len(result.noise_figures))],
        "noise": [_noise_dict(ci, rn, float(e.case.sample_rate))
                  for ci, rn, e in zip(problem.carriage or [None] * n, problem.noise or [None] * n,
                                       experiments)],
        "provenance": provenance([e.case for e in experiments], options=options,
                                 model_spec=model_spec, command=command),
    }


def fit_json(record: Mapping[str, Any]) -> str:
    """The fit ``record`` (:func:`fit_record`) as the strict JSON text written to a file
    (:func:`estimate.outputs.json_text`: a value that is not finite is null and listed under
    ``"non_finite"``).

    Examples
    --------
    >>> text = fit_json(fit_record(result, model_spec="fixed,p1"))   # doctest: +SKIP
    """
    from ...outputs import json_text

    return json_text(dict(record))
