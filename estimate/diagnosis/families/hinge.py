"""Hinge nonlinearities of the first mode, screened by their score: damping that grows with
the swing (quadratic damper), dry (Coulomb) friction and a hardening or softening cubic
spring. Friction and the cubic spring also start from the amplitude trends of segment
refits (harmonic balance) when the current fit is far from the data."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from analogs import CubicHingeSpring, HingeFriction, Model, QuadraticDamper
from analogs.hinge_nonlinear import FRICTION_RATE

from ...fitting.result import FitResult
from ..evidence import Evidence
from .base import Context, Family, Proposal, Score, Term, screened_proposal, trend_text

__all__ = ["NonlinearDamping", "DryFriction", "NonlinearStiffness", "HOST"]

#: The pendulum whose hinge the families extend (the first mode).
HOST = "p1"
#: Rate scales [rad/s] the final fit tries for dry friction's sign, sharpest first: against
#: sharp friction (noise-free), Tc came out +3.2 % at 0.02 rad/s (the candidates'), +1.4 % at
#: 0.005 and +0.8 % at 0.002. Warm-started from the 0.02 fit, 0.002 took 25 iterations.
SHARPER_FRICTION = (0.002, 0.005)
#: A sharper rate is used only while ``h Tc / (rate m L^2)`` (the friction's stiffness over
#: the hinge inertia, times the RK4 step) stays below this; RK4 is unstable above ~2.8.
FRICTION_STIFFNESS = 1.0


class _HingeFamily(Family):
    """A hinge element on :data:`HOST` with one parameter, screened at zero."""

    component: type
    parameter: str
    label: str
    sign: int = 0

    def terms(self, ctx: Context) -> tuple[Term, ...]:
        if any(isinstance(c, self.component) and c.name == HOST for c in ctx.model.components):
            return ()
        name = f"{HOST}.{self.parameter}"
        return (Term(self.cause, f"{HOST}:{self.label}", (self.component(HOST),), (), (name,),
                     {name: self.sign} if self.sign else {}),)

    def start(self, evidence: Evidence, inertia: float) -> dict[str, float] | None:
        """Start values read off the amplitude trends (``None``: none)."""
        return None

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        out = []
        for sc in scores:
            # the evidence (and the cold start) read the amplitude trends of segment refits
            cold = self.start(ctx.with_trends(), ctx.inertia) if ctx.inertia else None
            out.append(screened_proposal(self, sc, ctx, cold))
        return out


class NonlinearDamping(_HingeFamily):
    """Damping that grows with the swing (turbulent, separated flow): a quadratic hinge
    damper on the first mode."""

    cause, component, parameter, label, sign = ("nonlinear_damping", QuadraticDamper,
                                                "quadratic_damping", "quadratic", 1)

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        return (f"{trend_text(evidence, 'damping')}{statistic} -> damping that grows with the "
                f"swing (turbulent, separated flow); adding a quadratic hinge damper on {HOST} "
                f"(c2 = {r.value(names[0]):.3g} N m s^2/rad^2)")


class DryFriction(_HingeFamily):
    """Dry (Coulomb) friction at the hinge, whose equivalent damping falls with the swing: a
    friction torque on the first mode, started from the damping's amplitude trend."""

    cause, component, parameter, label, sign = ("dry_friction", HingeFriction,
                                                "coulomb_friction", "friction", 1)

    def start(self, evidence: Evidence, inertia: float) -> dict[str, float] | None:
        """A torque ``Tc sign(thd)`` dissipates like a damping ratio ``2 Tc / (pi I w^2 a)``
        (hinge inertia I = m L^2), so ``Tc = pi I w^2 (z(a0) - z(a1)) / (2 (1/a0 - 1/a1))``
        between the smallest and largest swing."""
        tr, ftr = evidence.damping_trend, evidence.frequency_trend
        if tr is None or ftr is None or tr.t > -2:
            return None
        (a0, a1), (z0, z1) = tr.amplitudes, tr.values
        w = 2 * math.pi * 0.5 * sum(ftr.values)
        tc = math.pi * inertia * w**2 * (z0 - z1) / (2 * (1 / a0 - 1 / a1))
        return {f"{HOST}.coulomb_friction": tc} if tc > 0 else None

    def finish(self, fitter, final: FitResult) -> tuple[FitResult, str | None]:
        """Refit with the friction's sign sharpened to the first rate of
        :data:`SHARPER_FRICTION` that keeps RK4 stable and converges (warm-started)."""
        model = final.problem.model
        hosts = [c for c in model.components if isinstance(c, HingeFriction)]
        if not hosts:
            return final, None
        h = max(float(np.median(np.diff(e.case.time))) for e in final.problem.experiments)
        for rate in SHARPER_FRICTION:
            stiff = max(h * abs(final.value(f"{c.host}.coulomb_friction"))
                        / (rate * final.value(f"{c.host}.mass") * final.value(f"{c.host}.length") ** 2)
                        for c in hosts)
            if stiff > FRICTION_STIFFNESS:
                continue
            sharper = Model(tuple(HingeFriction(c.host, rate=rate)
                                  if isinstance(c, HingeFriction) else c for c in model.components))
            bounds = {e.name: (e.lower, e.upper) for e in final.problem.estimated if e.case is None}
            res = fitter(sharper, final.problem.measurement, dict(zip(final.names, final.values)),
                         bounds, weights=None, warm=final, purpose=f"final, friction at {rate:g} rad/s")
            if res.converged:
                return res, (f"the final fit sharpens the dry friction's sign to tanh(rate / "
                             f"{rate:g} rad/s) (the candidates' {FRICTION_RATE:g} rad/s biases the "
                             f"friction torque high by a few per cent against sharp friction)")
        return final, None

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        return (f"{trend_text(evidence, 'damping')}{statistic} -> dry (Coulomb) friction at the "
                f"hinge, whose equivalent damping falls with the swing; adding a friction torque "
                f"Tc = {r.value(names[0]):.3g} N m on {HOST} (tanh of the rate over "
                f"{FRICTION_RATE:g} rad/s)")


class NonlinearStiffness(_HingeFamily):
    """A restoring stiffness that changes with the swing (an elastomeric diaphragm): a cubic
    hinge spring on the first mode, started from the frequency's amplitude trend."""

    cause, component, parameter, label = ("nonlinear_stiffness", CubicHingeSpring,
                                          "cubic_stiffness", "cubic")

    def start(self, evidence: Evidence, inertia: float) -> dict[str, float] | None:
        """Harmonic balance: ``w(a)^2 = w0^2 (1 - a^2/8) + 3/4 k3 a^2 / I``, so ``k3 = I
        (d(w^2)/d(a^2) + w^2/8) / 0.75`` between the smallest and largest swing."""
        tr = evidence.frequency_trend
        if tr is None or tr.t < 2:
            return None
        (a0, a1), (f0, f1) = tr.amplitudes, tr.values
        w0, w1 = 2 * math.pi * f0, 2 * math.pi * f1
        k3 = inertia * ((w1**2 - w0**2) / (a1**2 - a0**2) + 0.5 * (w0**2 + w1**2) / 8) / 0.75
        return {f"{HOST}.cubic_stiffness": k3} if k3 > 0 else None

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        k3 = r.value(names[0])
        kind = "hardening" if k3 > 0 else "softening"
        return (f"{trend_text(evidence, 'frequency')}{statistic} -> a {kind} restoring stiffness "
                f"(an elastomeric diaphragm); adding a cubic hinge spring on {HOST} "
                f"(k3 = {k3:.3g} N m/rad^3)")
