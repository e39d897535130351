"""Screened candidates as proposals to fit: the extended model, start values from the score
step, and what the fitted parameters mean physically (with the amplitude evidence that
points the same way)."""

from __future__ import annotations

import math

from analogs.hinge_nonlinear import FRICTION_RATE

from ..fitting.result import FitResult
from .candidates import Proposal
from .evidence import Evidence
from .screening import Score, library_description

__all__ = ["family_proposal", "evidence_start"]

#: Smallest start value of a positive parameter, relative to the score step's value.
_START_FLOOR = 0.2


def _significant(res: FitResult, name: str, factor: float = 3.0) -> bool:
    i = res.names.index(name) if name in res.names else None
    return i is not None and abs(res.values[i]) > factor * res.stderr[i]


def _trend_text(evidence: Evidence, quantity: str) -> str:
    trend = evidence.damping_trend if quantity == "damping" else evidence.frequency_trend
    return f"{trend.text()}; " if trend is not None and abs(trend.t) >= 2 else ""


def evidence_start(cause: str, host: str, evidence: Evidence, inertia: float
                   ) -> dict[str, float] | None:
    """Start values of a hinge family's parameter read off the amplitude trends of the
    segment fits, by harmonic balance on the pendulum of hinge inertia ``inertia`` = m L^2
    [kg m^2] (``None`` when the trend is weak or points the other way).

    * cubic stiffness: ``w(a)^2 = w0^2 (1 - a^2/8) + 3/4 k3 a^2 / I``, so
      ``k3 = I (d(w^2)/d(a^2) + w^2/8) / 0.75`` between the smallest and largest swing;
    * dry friction: a torque ``Tc sign(thd)`` dissipates like a damping ratio
      ``2 Tc / (pi I w^2 a)``, so ``Tc = pi I w^2 (z(a0) - z(a1)) / (2 (1/a0 - 1/a1))``.
    """
    if cause == "nonlinear_stiffness":
        tr = evidence.frequency_trend
        if tr is None or tr.t < 2:
            return None
        (a0, a1), (f0, f1) = tr.amplitudes, tr.values
        w0, w1 = 2 * math.pi * f0, 2 * math.pi * f1
        k3 = inertia * ((w1**2 - w0**2) / (a1**2 - a0**2) + 0.5 * (w0**2 + w1**2) / 8) / 0.75
        return {f"{host}.cubic_stiffness": k3} if k3 > 0 else None
    if cause == "dry_friction":
        tr, ftr = evidence.damping_trend, evidence.frequency_trend
        if tr is None or ftr is None or tr.t > -2:
            return None
        (a0, a1), (z0, z1) = tr.amplitudes, tr.values
        w = 2 * math.pi * 0.5 * sum(ftr.values)
        tc = math.pi * inertia * w**2 * (z0 - z1) / (2 * (1 / a0 - 1 / a1))
        return {f"{host}.coulomb_friction": tc} if tc > 0 else None
    return None


def family_proposal(score: Score, current: FitResult, evidence: Evidence,
                    statistic_text: str, *, inertia: float | None = None) -> Proposal:
    """The fit of a screened family, started at the current estimates and at the values the
    score step points to; its plausibility requires every new parameter to be distinct from
    zero (3 standard errors) and of the physical sign."""
    fam = score.family
    model = current.problem.model
    for c in fam.components:
        model = model + c
    measurement = tuple(current.problem.measurement) + fam.measurement
    initial = {}
    for n in fam.parameters:
        v = score.values[n]
        if fam.signs.get(n, 0) > 0:
            v = max(v, _START_FLOOR * abs(v), 1e-12)
        initial[n] = v

    def plausible(r: FitResult) -> str | None:
        for n in fam.parameters:
            if not _significant(r, n):
                return f"`{n}` = {r.value(n):.3g} is not distinguishable from zero"
            if fam.signs.get(n, 0) * r.value(n) < 0:
                return f"`{n}` = {r.value(n):.3g} has the unphysical sign"
        return None

    host = fam.parameters[0].split(".")[0]
    cold = evidence_start(fam.cause, host, evidence, inertia) if inertia else None
    return Proposal(fam.cause, (fam.label,), model, measurement, initial,
                    cold_start=cold, plausible=plausible,
                    describe=lambda r: _describe(fam.cause, fam.parameters, r, evidence,
                                                 statistic_text))


def _describe(cause: str, names: tuple[str, ...], r: FitResult, evidence: Evidence,
              statistic: str) -> str:
    v = {n: r.value(n) for n in names}
    host = names[0].split(".")[0]
    if cause == "dry_friction":
        tc = v[f"{host}.coulomb_friction"]
        return (f"{_trend_text(evidence, 'damping')}{statistic} -> dry (Coulomb) friction at the "
                f"hinge, whose equivalent damping falls with the swing; adding a friction torque "
                f"Tc = {tc:.3g} N m on {host} (tanh of the rate over {FRICTION_RATE:g} rad/s)")
    if cause == "nonlinear_damping":
        c2 = v[f"{host}.quadratic_damping"]
        return (f"{_trend_text(evidence, 'damping')}{statistic} -> damping that grows with the "
                f"swing (turbulent, separated flow); adding a quadratic hinge damper on {host} "
                f"(c2 = {c2:.3g} N m s^2/rad^2)")
    if cause == "nonlinear_stiffness":
        k3 = v[f"{host}.cubic_stiffness"]
        kind = "hardening" if k3 > 0 else "softening"
        return (f"{_trend_text(evidence, 'frequency')}{statistic} -> a {kind} restoring stiffness "
                f"(an elastomeric diaphragm); adding a cubic hinge spring on {host} "
                f"(k3 = {k3:.3g} N m/rad^3)")
    if cause == "sensor_offset":
        return (f"{statistic} -> the force transducer is not zeroed and drifts: offset "
                f"{v['rig.force_offset']:.3g} N, drift {v['rig.force_drift']:.3g} N/s")
    if cause == "rig_friction":
        return (f"{statistic} -> a force in phase with the carriage velocity: rig friction seen "
                f"by the transducer (viscous {v['rig.friction_viscous']:.3g} N s/m, Coulomb "
                f"{v['rig.friction_coulomb']:.3g} N)")
    (name,) = names
    term = name.split(".torque_", 1)[1]
    shape = {"angle_squared": "theta^2", "rate_cubed": "thetadot^3",
             "angle2_rate": "theta^2 thetadot", "abs_angle_rate": "|theta| thetadot",
             "angle_rate2": "theta thetadot^2"}.get(term, term)
    unit = r.problem.estimated[r.names.index(name)].unit
    return (f"{statistic}; no named element explains the residual, but a hinge torque "
            f"~ {shape} ({library_description(term)}) does: coefficient {v[name]:.3g} {unit} "
            f"on {host}")
