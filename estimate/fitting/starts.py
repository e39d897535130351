"""Where a fit's estimates start besides the prediction: the first stage of lateral
measured records (:mod:`estimate.fitting.first_stage`) and of the spinning rig
(:mod:`estimate.fitting.spin_stage`), the stream lag it finds, an unweighed container's
guess. Steps of :meth:`FitProblem.build <estimate.fitting.problem.FitProblem.build>`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from analogs import Model
from analogs.errors import InputError

from ..data.case import Case

__all__ = ["LAG_MIN", "LAG_MODES", "SECOND_START_SPREAD", "container_guess", "liquid_or_none",
           "record_first_stage", "second_start", "spin_start", "with_lag"]

#: ``lag="auto"`` estimates a stream lag only where the first stage finds one of at least
#: this much [s]: a record without one keeps the parameters it always had (a lag the NLP
#: is free to move otherwise bends around what the model lacks; a sample at 500 Hz).
LAG_MIN = 0.002

#: How a stream lag between motion and force is treated (see :meth:`FitProblem.build`).
LAG_MODES = ("auto", "estimate", "none")


#: A fit the first stage started whose masses end farther than this fraction of the liquid
#: mass from the prediction is solved from the prediction too, and the lower objective kept
#: (:func:`second_start`).
SECOND_START_SPREAD = 0.25


def second_start(problem, values) -> tuple[object, str] | None:
    """``problem`` started from the prediction where the first stage started its masses and
    the fit's ``values`` (by label) left them far from it (more than
    :data:`SECOND_START_SPREAD` of the liquid mass, or of the predicted masses' sum when the
    tank gives none), with the reason in words; ``None`` otherwise.

    A record that barely separates the rigid from the sloshing mass (a light sine near
    resonance: its steady state fixes only their sum weighted by the resonance) can lead
    the linear first stage to a split it does not support, and the NLP stays in that
    valley: 0.16 kg fixed and 1.60 kg sloshing against 1.46 and 1.30, at an objective 161
    above the one the prediction's start reaches, with intervals that missed the truth by
    30 standard errors."""
    pred = dict(problem.prediction_start)
    masses = [e for e in problem.estimated
              if e.name in pred and e.parameter.endswith(".mass")]
    if not masses:
        return None
    liquid = liquid_or_none(problem.experiments[0].case)
    total = liquid if liquid else sum(abs(pred[e.name]) for e in masses)
    far = [e for e in masses if abs(values[e.name] - pred[e.name]) > SECOND_START_SPREAD * total]
    if not far:
        return None
    other = problem.with_initial(pred)
    start = {e.name: e.initial for e in other.estimated}
    if any(b.slack(other.names, np.array(list(start.values()))) < 0
           for b in other.linear_bounds) or any(t.value(start) < 0 for t in other.ties):
        return None  # the prediction puts more mass in the analog than the liquid holds
    why = ", ".join(f"`{e.name}` {values[e.name]:.4g} against {pred[e.name]:.4g} {e.unit}"
                    for e in far)
    return other, why


def liquid_or_none(case: Case) -> float | None:
    """The liquid mass of ``case`` [kg], or None when its tank does not give it."""
    try:
        return float(case.liquid_mass)
    except (ValueError, ArithmeticError):
        return None



def record_first_stage(cases, model: Model, exps, carriage, noise, weights):
    """The first stage (:func:`estimate.fitting.first_stage.record_stage`) of lateral
    measured cases fitted with a first-mode pendulum, else ``None``."""
    from .first_stage import record_stage
    from .initial import predicted_values

    if not any(p.name == "p1.length" for p in model.parameters):
        return None
    g = cases[0].rig.gravity
    try:
        pred = predicted_values(cases[0], model)
        L, m = pred["p1.length"], pred["p1.mass"]
        f = math.sqrt(g / L + pred.get("p1.stiffness", 0.0) / (m * L**2)) / (2 * math.pi)
    except (KeyError, InputError, ValueError, ArithmeticError):
        f = math.nan
    return record_stage((exps, carriage, noise, weights), frequency_hz=f, gravity=g)



def spin_start(exps, weights, est: list, start: Mapping[str, float], given,
                cutoff: float | None, inside: Mapping[str, tuple[float, float]]):
    """``est`` started from the spinning rig's first stage
    (:func:`estimate.fitting.spin_stage.spin_stage`, searching within the estimates'
    bounds and the tank, ``inside``) where it applies (the values the user gave kept), and
    the stage (``None``: not run)."""
    if exps[0].case.test.rig != "spinning" or any(e.case is not None for e in est):
        return est, None
    from .spin_stage import spin_stage

    box = {e.parameter: (max(e.lower, inside.get(e.parameter, (-math.inf,))[0]),
                         min(e.upper, inside.get(e.parameter, (0, math.inf))[1])) for e in est}
    stage = spin_stage(exps, weights, [e.parameter for e in est], start, box, cutoff_hz=cutoff)
    if stage is None:
        return est, None
    out = [replace(e, initial=min(max(stage.values[e.parameter], e.lower), e.upper))
           if e.parameter in stage.values and e.parameter not in given else e for e in est]
    return out, stage



def with_lag(measurement: tuple, mode: str, stage, carriage, exps) -> tuple[tuple, str | None]:
    """``measurement`` with a :class:`StreamLag` where ``mode`` asks for one, and a note."""
    from .measurement import SensorDelay, StreamLag

    if mode == "none" or any(isinstance(m, (StreamLag, SensorDelay)) for m in measurement):
        return measurement, None
    estimable = bool(carriage) and all(c is not None for c in carriage)
    if not estimable:
        if mode == "estimate":
            raise InputError("a stream lag is estimated with the estimated carriage motion: "
                             "build with input='estimated' and measured displacements")
        return measurement, None
    if mode == "auto" and (stage is None or not stage.lag_identified):
        why = ("no first stage" if stage is None else "the first stage determines it to "
               + ", ".join(f"{1e3 * s:.3g} ms" for s in stage.lag_stderr))
        return measurement, f"stream lag not estimated: not identifiable from the record ({why})"
    if mode == "auto" and all(abs(t) < LAG_MIN for t in stage.lags):
        return measurement, ("stream lag not estimated: the first stage puts it at "
                             + ", ".join(f"{1e3 * t:.2f} +/- {1e3 * s:.2g} ms" for t, s in
                                         zip(stage.lags, stage.lag_stderr))
                             + f", below {1e3 * LAG_MIN:g} ms")
    return measurement + (StreamLag(),), ("stream lag between the displacement and the force "
                                          "estimated (`rig.lag`, per case)")



def container_guess(case: Case) -> float:
    """Start value of an unweighed container's mass [kg]: the liquid's, when the tank
    geometry gives it, else 1 kg."""
    try:
        return float(case.liquid_mass)
    except (ValueError, ArithmeticError):
        return 1.0
