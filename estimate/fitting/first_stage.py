"""The fit's first stage: a linear identification of the record that needs no good start
(:mod:`estimate.fitting.identification`), run on the records of a problem being built
(:func:`record_stage`, the last few kept) and turned into the NLP's starting values
(:func:`starting_values`): masses, length, hinge damping, the rigid mass of an unweighed
container, the stream lag, and whether the lag is identifiable."""

from __future__ import annotations

import math

import numpy as np

from .identification import (
    BUDGET_SHARE,
    LAG_IDENTIFIED,
    LAG_RANGE,
    FirstStage,
    StartOutcome,
    identify,
)

__all__ = ["FirstStage", "StartOutcome", "identify", "record_stage", "starting_values",
           "forget_stages", "LAG_RANGE", "LAG_IDENTIFIED"]


_RECENT: dict = {}


def forget_stages() -> None:
    """Drop the kept :func:`record_stage` results (benchmarks time a first fit of a record)."""
    _RECENT.clear()


def record_stage(problem_parts, *, frequency_hz: float, gravity: float) -> FirstStage | None:
    """The first stage of the measured lateral cases of a problem being built:
    ``problem_parts`` is ``(experiments, carriage inputs, record noises, weights)``; the
    acceleration is each estimated carriage motion's start (the least-squares spline
    through the displacement) or the filtered input's. ``None`` when a case is not a
    lateral measured one with one force channel, or one whose liquid is not at rest at the
    first sample (``[test] initial_state`` "free" or "steady": the identification filters
    the acceleration from rest, and a window of a running test or a free decay would put
    the unmodelled start in the lag and the damping). The last few results are kept (the
    diagnosis builds a problem per candidate of one record)."""
    import hashlib

    exps, carriage, noise, weights = problem_parts
    records, key, levels = [], [round(frequency_hz, 9), gravity], []
    for i, e in enumerate(exps):
        case = e.case
        if case.test.rig != "lateral" or case.test.excitation != "measured" \
                or case.force is None or e.channels != ("force_x",) \
                or (case.test.initial_state or "rest") != "rest":
            return None
        ci = carriage[i] if carriage else None
        F = noise[i].force if noise and noise[i] is not None else case.force
        levels.append(noise[i].force_noise if noise and noise[i] is not None else math.nan)
        w = weights[i] if weights else None
        acc = _acceleration(e, ci)
        if acc is None:
            return None
        records.append((case.time, acc, F, w))
        key.append(hashlib.sha256(np.ascontiguousarray(case.time).tobytes()
                                  + np.ascontiguousarray(F).tobytes()
                                  + np.ascontiguousarray(case.displacement).tobytes()
                                  + (b"" if w is None else np.asarray(w, float).tobytes())
                                  + (b"e" if ci is not None else b"f")).hexdigest())
    key = tuple(key)
    if key not in _RECENT:
        _RECENT[key] = identify(records, frequency_hz=frequency_hz, gravity=gravity,
                                noise=levels if np.all(np.isfinite(levels)) else None)
        while len(_RECENT) > 4:
            _RECENT.pop(next(iter(_RECENT)))
    return _RECENT[key]


def _acceleration(exp, carriage):
    """The carriage acceleration (m/s^2) of an experiment as a function of time: its
    estimated motion's start, or the filtered input; ``None`` without one."""
    if carriage is not None:
        def acc(tt):
            return carriage.values(carriage.coefficients, tt)[2]
        return acc
    exc, dm = exp.excitation, exp.derived
    if exc is None or "rig.x_ddot" not in dm.inputs:
        return None
    j = dm.inputs.index("rig.x_ddot")

    def acc_filtered(tt):
        return np.asarray(exc.values(np.asarray(tt, float)))[j]
    return acc_filtered


def starting_values(stage: FirstStage, *, gravity: float, estimated, values, liquid_mass,
                    length_bounds: tuple[float, float] | None = None,
                    host: str = "p1") -> dict[str, float]:
    """Start values (by parameter name) of the first slosh mode ``host``, the rigid mass
    and the lags from the first stage, for the parameters ``estimated`` given the others'
    ``values``: ``host.mass``; ``host.length`` from the frequency (or, with a hinge spring
    estimated, the predicted length kept and the spring taking the rest of the stiffness);
    the hinge damper from the damping ratio; ``rig.dry_mass`` (an unweighed container: the
    rigid mass less the fixed liquid and the other modes) or ``fixed.mass`` (the rigid
    mass less the dry mass and the other modes). A slosh mass that is not positive leaves
    the masses to the prediction (the frequency and damping still start the mode); one
    beyond :data:`BUDGET_SHARE` of the liquid starts there."""
    est = set(estimated)
    m = stage.slosh_mass
    keep_mass = m > 0
    if not keep_mass:  # the frequency still holds; the mass stays the prediction's
        m = float(values.get(f"{host}.mass", math.nan))
        if not m > 0:
            return {}
    if liquid_mass is not None and m >= BUDGET_SHARE * liquid_mass:
        m = BUDGET_SHARE * liquid_mass  # inside the liquid budget, where IPOPT starts
    omega = 2 * math.pi * stage.frequency_hz
    out: dict[str, float] = {}
    L = gravity / omega**2
    if f"{host}.stiffness" in est and f"{host}.length" in values:
        L0 = float(values[f"{host}.length"])
        if omega**2 > gravity / L0:
            L = L0
            out[f"{host}.stiffness"] = m * L**2 * (omega**2 - gravity / L)
        else:
            out[f"{host}.stiffness"] = 0.0
    if keep_mass:
        out[f"{host}.mass"] = m
    out[f"{host}.length"] = L
    out[f"{host}.damping"] = 2 * stage.damping_ratio * omega * m * L**2
    others = sum(float(v) for k, v in values.items()
                 if k.endswith(".mass") and k.split(".")[0] not in ("fixed", "rig", host)
                 and k not in est)
    others += sum(float(values.get(k, 0.0)) for k in est
                  if k.endswith(".mass") and k.split(".")[0] not in ("fixed", "rig", host))
    M = stage.rigid_mass - others
    if not keep_mass:
        return {k: v for k, v in out.items() if k in est}
    if "rig.dry_mass" in est:
        fixed = (liquid_mass - m - others) if "fixed.mass" not in est and liquid_mass else \
            float(values.get("fixed.mass", 0.0))
        out["rig.dry_mass"] = max(M - fixed, 0.0)
    elif "fixed.mass" in est:
        dry = float(values.get("rig.dry_mass", 0.0))
        upper = (liquid_mass - m - others) if liquid_mass else math.inf
        out["fixed.mass"] = min(max(M - dry, 1e-3 * m), upper)
    return {k: v for k, v in out.items() if k in est}
