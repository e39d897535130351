"""Screening of candidate extensions without fitting them: the score test.

All hinge-torque families (quadratic damping, dry friction, cubic stiffness), the
measurement families (transducer offset and drift, rig friction) and a small library of
hinge torque terms are added at once, at their null values, to the current fitted model.
One linearisation of that super-model at the current fit
(:func:`estimate.fitting.nlp.linearise`: states through the dynamics, the carriage motion
re-optimised) gives, for every candidate, the objective reduction one Gauss-Newton step
would bring (the score or Lagrange multiplier statistic, chi-square with as many degrees of
freedom as new parameters when the candidate explains nothing) and the parameter values it
points to. Only candidates with a significant score and physically signed parameters are
fitted.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from analogs import Component, CubicHingeSpring, HingeFriction, HingeTorqueTerms, Model, QuadraticDamper
from analogs.hinge_nonlinear import TORQUE_TERMS

from ..fitting.linearise import Linearisation, linearise
from ..fitting.measurement import MeasurementModel, RigFriction, SensorOffset
from ..fitting.problem import FitProblem
from ..fitting.result import FitResult

__all__ = ["Family", "Score", "DelayProfile", "families", "screen", "delay_profile",
           "LIBRARY_TERMS"]

#: Library terms screened when no family explains the residual: those no family covers
#: (quadratic damping, dry friction and the cubic spring are families of their own).
LIBRARY_TERMS = ("angle_squared", "rate_cubed", "angle2_rate", "abs_angle_rate", "angle_rate2")


@dataclass(frozen=True)
class Family:
    """A candidate that adds hinge elements or measurement models with linear-in-effect
    parameters: its cause, label, the components and measurement models it adds, its new
    parameters, and which of them must be positive to be physical (``+1``)."""

    cause: str
    label: str
    components: tuple[Component, ...]
    measurement: tuple[MeasurementModel, ...]
    parameters: tuple[str, ...]
    signs: dict[str, int] = field(default_factory=dict)


@dataclass(frozen=True)
class Score:
    """A screened candidate: the objective reduction one Gauss-Newton step predicts over the
    residual variance (``statistic``), its degrees of freedom, the parameter values the
    step points to, and why it is not physical (``None`` when it is)."""

    family: Family
    statistic: float
    dof: int
    values: dict[str, float]
    unphysical: str | None


def families(model: Model, measurement: tuple[MeasurementModel, ...], host: str, *,
             measured_excitation: bool) -> list[Family]:
    """The hinge and measurement families not yet in ``model``/``measurement``, and one
    family per library term (cause ``hinge_torque``)."""
    have = {(type(c), c.name) for c in model.components}
    out = []
    if (QuadraticDamper, host) not in have:
        out.append(Family("nonlinear_damping", f"{host}:quadratic", (QuadraticDamper(host),), (),
                          (f"{host}.quadratic_damping",), {f"{host}.quadratic_damping": 1}))
    if (HingeFriction, host) not in have:
        out.append(Family("dry_friction", f"{host}:friction", (HingeFriction(host),), (),
                          (f"{host}.coulomb_friction",), {f"{host}.coulomb_friction": 1}))
    if (CubicHingeSpring, host) not in have:
        out.append(Family("nonlinear_stiffness", f"{host}:cubic", (CubicHingeSpring(host),), (),
                          (f"{host}.cubic_stiffness",)))
    kinds = {type(m) for m in measurement}
    if SensorOffset not in kinds:
        out.append(Family("sensor_offset", "sensor_offset", (), (SensorOffset(),),
                          ("rig.force_offset", "rig.force_drift")))
    if measured_excitation and RigFriction not in kinds:
        out.append(Family("rig_friction", "rig_friction", (), (RigFriction(),),
                          ("rig.friction_viscous", "rig.friction_coulomb"),
                          {"rig.friction_viscous": 1, "rig.friction_coulomb": 1}))
    present = {t for c in model.components if isinstance(c, HingeTorqueTerms) for t in c.terms}
    for term in LIBRARY_TERMS:
        if term not in present:
            out.append(Family("hinge_torque", f"{host}:torque_{term}",
                              (HingeTorqueTerms(host, terms=(term,)),), (),
                              (f"{host}.torque_{term}",)))
    return out


def _super_model(model: Model, fams: list[Family], host: str) -> Model:
    """``model`` with every family's components; the library terms merged into one
    :class:`analogs.HingeTorqueTerms` (one attachment per host)."""
    terms = [c.terms[0] for f in fams for c in f.components if isinstance(c, HingeTorqueTerms)]
    out = model
    for f in fams:
        for c in f.components:
            if not isinstance(c, HingeTorqueTerms):
                out = out + c
    if terms:
        out = out + HingeTorqueTerms(host, terms=tuple(terms))
    return out


def screen(current: FitResult, fams: list[Family], *, host: str,
           build: Callable[..., FitProblem]) -> list[Score]:
    """Score every family at the current fit (one linearisation of the super-model).

    ``build(model, measurement, initial)`` makes the fit problem of the diagnosed cases
    (the same weights as ``current``)."""
    if not fams:
        return []
    model = _super_model(current.problem.model, fams, host)
    measurement = tuple(current.problem.measurement) + tuple(
        m for f in fams for m in f.measurement)
    start = {n: v for n, v in zip(current.names, current.values)}
    problem = build(model, measurement, start)
    lin = linearise(problem, warm_start=current)
    base = tuple(n for n in current.names if n in lin.names)
    s2 = max(current.residual_variance, 1e-300)
    out = []
    for f in fams:
        reduction, values = lin.score(base + f.parameters)
        new = {n: values[n] for n in f.parameters}
        wrong = [n for n, sign in f.signs.items() if sign * new[n] <= 0]
        why = (f"the step points to {', '.join(f'`{n}` = {new[n]:.3g}' for n in wrong)}, "
               "which is not physical") if wrong else None
        out.append(Score(f, reduction / s2, len(f.parameters), values, why))
    return sorted(out, key=lambda sc: -sc.statistic)


def library_description(term: str) -> str:
    """What a library term describes (see :data:`analogs.hinge_nonlinear.TORQUE_TERMS`)."""
    return TORQUE_TERMS[term][2]


@dataclass(frozen=True)
class DelayProfile:
    """The objective over a sensor delay, linearised at a fit (:func:`delay_profile`):
    trial ``delays`` (s), the objective at each (residuals in noise units) and its
    minimum, refined between grid points by a parabola."""

    delays: np.ndarray
    objective: np.ndarray
    best: float
    reduction: float


def _force_rows(res: FitResult, case: int) -> int:
    """First row of case ``case``'s force residuals in ``res.sensitivity`` (each case: its
    force samples, then its displacement residuals when the carriage motion is estimated)."""
    rows = 0
    for k in range(case):
        rows += int(np.size(res.residuals[k]))
        if res.displacement_residuals and res.displacement_residuals[k] is not None:
            rows += int(np.size(res.displacement_residuals[k]))
    return rows


def delay_profile(res: FitResult, lin: Linearisation, measured: Sequence[np.ndarray],
                  delays: np.ndarray) -> DelayProfile:
    """Linearised profile of the objective over a sensor delay, without fitting.

    For every trial delay the recorded force ``measured`` (per case, before any delay) is
    advanced as :class:`estimate.fitting.measurement.SensorDelay` does, and the objective
    after one Gauss-Newton step from the fit ``res`` is computed with ``lin``, its
    linearisation (:meth:`estimate.fitting.linearise.Linearisation.objectives`: the
    parameters, the states and the estimated carriage motion all move; one solve for all
    delays). The data shift is exact and only the model's response is linearised, so near
    ``res`` the profile is close to the fitted one (a 20 ms skew came out at 20.0 ms from a
    fit without delay, fitted 20.2 ms). The samples within ``max(delays)`` of the end keep
    their residuals for every delay."""
    delays = np.asarray(delays, float)
    E = np.repeat(lin.residuals[:, None], delays.size, axis=1)
    for i, (m, w) in enumerate(zip(measured, res.weights)):
        t = np.asarray(res.problem.experiments[i].case.time, float)
        keep = (t + delays.max() <= t[-1]) & (w > 0)
        shifted = CubicSpline(t, np.asarray(m, float))(
            np.clip(t[keep][:, None] + delays[None, :], t[0], t[-1]))
        scale = res.problem.channel_scales(i)["force_x"]
        rows = _force_rows(res, i) + np.flatnonzero(keep)
        E[rows] += (np.asarray(res.measured[i])[keep][:, None] - shifted) * (w[keep] / scale)[:, None]
    cost = lin.objectives(E, tuple(res.names))
    k = int(np.argmin(cost))
    best = float(delays[k])
    if 0 < k < delays.size - 1:  # parabola through the minimum and its neighbours
        c0, c1, c2 = cost[k - 1:k + 2]
        h = delays[k + 1] - delays[k]
        curv = c0 - 2 * c1 + c2
        if curv > 0:
            best += float(np.clip(0.5 * h * (c0 - c2) / curv, -h, h))
    return DelayProfile(delays, cost, best, float(lin.objective - cost[k]))
