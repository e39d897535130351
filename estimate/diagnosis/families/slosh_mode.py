"""Another slosh mode: a pendulum with a linear hinge damper above the highest modelled
mode, found by a matched scan of its frequency on the round's linearisation."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from analogs import HingeDamper, LateralRig, Pendulum

from ...fitting.result import FitResult
from ..scoring import case_rows, distinct
from .base import Context, Family, Proposal, Score, frequency

__all__ = ["SloshMode", "ModeScan", "scan_mode", "MODE_SCORE", "MIN_MODE_DAMPING"]

#: Score (objective reduction over the residual variance, as the screening's) a matched
#: scan must reach for another slosh mode to be fitted.
MODE_SCORE = 25.0
#: Smallest damping ratio of a slosh mode: viscous damping of liquid slosh is ~1e-3 in tanks
#: up to a metre (Mikishev's law) and higher for higher modes; a fitted "mode" that hardly
#: decays over a record (damping ratio ~0) is a constant tone in the force.
MIN_MODE_DAMPING = 2e-4
#: Damping ratio of the scan's probe: more than a slosh resonance has, so that a trial
#: frequency a grid step from a sharp resonance still correlates with its response; the
#: refinement between grid points uses half of it.
PROBE_DAMPING = 0.02


@dataclass(frozen=True)
class ModeScan:
    """The best trial of :func:`scan_mode`: frequency (Hz), mass (kg), the objective
    reduction one Gauss-Newton step with it predicts, and that reduction's fraction of the
    objective."""

    frequency: float
    mass: float
    reduction: float
    fraction: float


def _probe_columns(ctx: Context, freqs: np.ndarray, zeta: float) -> np.ndarray:
    """The weighted, scaled force of a unit-mass pendulum at each trial frequency, driven
    by each case's carriage motion (the estimated one when there is), placed in the rows of
    the round's linearisation (one column per trial)."""
    from derive import Sampled, simulate_outputs

    current = ctx.current
    probe = LateralRig() + Pendulum("q") + HingeDamper("q")
    Y = np.zeros((len(ctx.linearisation.residuals), freqs.size))
    for i, exp in enumerate(current.problem.experiments):
        t = np.asarray(exp.case.time, float)
        excitation = exp.excitation
        if current.carriage and current.carriage[i] is not None:
            excitation = Sampled(t, current.carriage[i])
        w = current.weights[i] if current.weights else np.ones(t.size)
        scale = current.problem.channel_scales(i)["force_x"]
        g = exp.case.rig.gravity
        trials = []
        for f in freqs:
            om = 2 * math.pi * f
            L = g / om**2
            trials.append({"rig.dry_mass": 0.0, "rig.gravity": g, "q.mass": 1.0,
                           "q.length": L, "q.damping": 2 * zeta * L**2 * om})
        force = simulate_outputs(probe, trials, t, excitation, outputs=("force_x",))[:, :, 0]
        Y[case_rows(current, i), :] = (force * (w / scale)).T
    return Y


def _best(ctx: Context, freqs: np.ndarray, zeta: float) -> ModeScan | None:
    """The trial of ``freqs`` whose unit probe, scaled by its best positive mass, lowers the
    linearised objective most (the parameters, states and carriage motion move too)."""
    lin = ctx.linearisation
    Y = _probe_columns(ctx, freqs, zeta)
    e = lin.residuals[:, None]
    q = lin.objectives(np.hstack([e, e + Y, e - Y]), ctx.base_names)
    q0, qp, qm = q[0], q[1:1 + freqs.size], q[1 + freqs.size:]
    curv, slope = 0.5 * (qp + qm) - q0, 0.5 * (qp - qm)  # objective q0 + slope a + curv a^2
    with np.errstate(divide="ignore", invalid="ignore"):
        mass = np.where(curv > 0, -slope / (2 * curv), 0.0)
        reduction = np.where((curv > 0) & (mass > 0), slope**2 / (4 * curv), 0.0)
    k = int(np.argmax(reduction))
    if not reduction[k] > 0:
        return None
    return ModeScan(float(freqs[k]), float(mass[k]), float(reduction[k]),
                    float(reduction[k] / max(lin.objective, 1e-300)))


def scan_mode(ctx: Context, f_lo: float, f_hi: float, *, n: int = 60) -> ModeScan | None:
    """Matched scan for an unmodelled slosh mode between ``f_lo`` and ``f_hi`` (Hz): for
    each trial frequency, a unit-mass pendulum driven by the carriage motion is added to
    the residual with the mass that lowers the round's linearised objective most (the
    current parameters, the states and the estimated carriage motion re-optimised: one
    multi-right-hand-side solve for all trials). The best trial is refined between its
    neighbouring grid points with a probe as lightly damped as a slosh mode (a fit of a
    lightly damped mode started a grid step off can ring out of phase). Its reduction over
    the residual variance is a score like the screening's. ``None``: nothing explained."""
    best = _best(ctx, np.geomspace(f_lo, f_hi, n), PROBE_DAMPING)
    if best is None:
        return None
    step = (f_hi / f_lo) ** (1 / max(n - 1, 1))
    fine = _best(ctx, np.geomspace(best.frequency / step, best.frequency * step, 9),
                 0.5 * PROBE_DAMPING)
    return fine if fine is not None and fine.reduction >= best.reduction else best


class SloshMode(Family):
    """An unmodelled higher slosh mode: another pendulum with a linear hinge damper, its
    frequency from a matched scan above the highest modelled mode."""

    cause = "slosh_mode"

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        current, model = ctx.current, ctx.model
        pend = [c.name for c in model.components if isinstance(c, Pendulum)]
        if not pend or ctx.linearisation is None or \
                not all(e.derived.inputs and "rig.x_ddot" in e.derived.inputs
                        for e in current.problem.experiments):
            return []
        f_top = frequency(current, pend[-1])
        if not math.isfinite(f_top):
            return []
        cutoff = current.problem.force_cutoff_hz or 20.0
        scan = scan_mode(ctx, 1.15 * f_top, min(0.9 * cutoff, 4.0 * f_top))
        if scan is None:
            return []
        statistic = scan.reduction / max(current.residual_variance, 1e-300)
        if statistic < MODE_SCORE:
            return []
        name, prev = f"p{len(pend) + 1}", pend[-1]
        f0, m0 = scan.frequency, scan.mass
        L0 = ctx.gravity / (2 * math.pi * f0) ** 2
        m1 = current.value(f"{pend[0]}.mass")

        def damping(m: float) -> float:  # 1 % of critical at f0
            return 2 * 0.01 * m * L0**2 * 2 * math.pi * f0

        # the scan's linear probe reads the mass off the response amplitude, which a mode
        # swinging far into its nonlinear range (tenths of a radian in a sweep through it)
        # does not have: when that start fails, the tank's prediction of the mode's mass at
        # the scanned frequency is the second (F60_sweep_0.6mm: the scan read 0.008 kg of
        # 0.048 and its fit ran out of iterations)
        retry = None
        if f"{name}.mass" in ctx.predicted:
            mp = ctx.predicted[f"{name}.mass"]
            retry = {f"{name}.mass": mp, f"{name}.length": L0, f"{name}.damping": damping(mp)}
        peaks = [p for p in ctx.evidence.unexplained_peaks() if abs(p.frequency / f0 - 1) < 0.1]
        text = (f"{100 * scan.fraction:.0f} % of the objective (score {statistic:.0f}) is the "
                f"response of an oscillator at {f0:.3g} Hz driven by the carriage"
                + (f", with a residual peak at {peaks[0].frequency:.3g} Hz (coherence "
                   f"{peaks[0].coherence:.2f}) that is not a drive harmonic" if peaks else ""))

        def plausible(r: FitResult) -> str | None:
            m, f = r.value(f"{name}.mass"), frequency(r, name)
            if not f > 1.15 * frequency(r, prev):
                return f"{name} at {f:.3g} Hz is not above the mode it would follow"
            if not m < r.value(f"{prev}.mass"):
                return f"{name} mass {m:.3g} kg is not below the lower mode's"
            if not distinct(r, f"{name}.mass"):
                return f"{name} mass {m:.3g} kg is not distinguishable from zero"
            zeta = r.derived.get(f"{name}.damping_ratio", (math.nan, 0.0))[0]
            if zeta < MIN_MODE_DAMPING:
                return (f"{name} damping ratio {zeta:.2g}: an oscillation at {f:.3g} Hz that does "
                        f"not decay over the record is a tone or a structural ringing, not slosh")
            return None

        def describe(r: FitResult) -> str:
            return (f"{text} -> an unmodelled slosh mode; adding pendulum {name} "
                    f"({r.value(f'{name}.mass'):.3g} kg, {frequency(r, name):.3g} Hz)")

        upper = min(m1, max(5 * ctx.predicted.get(f"{name}.mass", 0.0), 0.1 * m1))
        return [Proposal(
            self.cause, (name,), model + Pendulum(name) + HingeDamper(name), ctx.measurement,
            {f"{name}.mass": min(m0, 0.9 * upper), f"{name}.length": L0,
             f"{name}.damping": damping(m0)},
            bounds={f"{name}.length": (0.8 * L0, 1.25 * L0), f"{name}.mass": (1e-6, upper)},
            score=statistic, retry=retry, plausible=plausible, describe=describe)]
