"""Rotational slosh on a spinning rig: a rotor about the tank's tangential axis (inertia
coupled to the tank by a damper), found by a matched scan of its coupling rate on the
six-channel residual."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...fitting.result import FitResult
from ..scoring import case_rows, distinct
from .base import Context, Family, Proposal, Score, free_name

__all__ = ["Rotor", "scan_rotor", "spin_probe_scan", "torque_share"]


def _probe_regression(probe: np.ndarray, J: np.ndarray, r: np.ndarray) -> tuple[float, float]:
    """Regress the residual ``r`` on a unit probe response and the fit's sensitivity ``J``
    (one Gauss-Newton step of the extended model). Returns the probe's size (the residual is
    simulated - measured, so a missing element enters with minus its size) and the explained
    fraction of the residual."""
    A = np.column_stack([probe, J])
    coef, *_ = np.linalg.lstsq(A, r, rcond=None)
    explained = 1 - float(np.sum((r - A @ coef) ** 2) / np.sum(r**2))
    return -float(coef[0]), explained


def spin_probe_scan(current: FitResult, component, trials: list[dict], *, case: int = 0
                    ) -> tuple[float, int, float] | None:
    """Simulate ``component`` (unit inertia ``q.inertia``) alone on the rig motion of
    ``case`` with each of ``trials``' parameter values and regress the fit's scaled,
    channel-major residual on its outputs together with the fit's sensitivity rows. Returns
    ``(inertia, trial index, explained_fraction)`` of the best trial with a positive
    inertia, or ``None``."""
    from analogs import Model
    from derive import RK4, derive, simulate

    problem = current.problem
    exp = problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    chans = current.channels[case]
    scales = np.array([current.channel_scales[case][c] for c in chans])
    w = np.tile(current.weights[case] > 0, len(chans))
    r = (current.residuals[case] / scales).ravel(order="F")[w]
    J = current.sensitivity[case_rows(current, case)][w]
    probe = derive(Model((problem.model.rig,)) + component)
    values = {k: v for k, v in problem.case_values(case, current.values).items()
              if k.startswith("rig.")}
    values["rig.dry_mass"] = 0.0
    best = None
    for k, trial in enumerate(trials):
        sim = simulate(probe, {**values, "q.inertia": 1.0, **trial}, t, exp.excitation,
                       integrator=RK4(), outputs=chans)
        y = (sim.outputs / scales[None, :]).ravel(order="F")[w]
        inertia, explained = _probe_regression(y, J, r)
        if inertia > 0 and (best is None or explained > best[2]):
            best = (inertia, k, explained)
    return best


def scan_rotor(current: FitResult, *, case: int = 0, n: int = 16,
               rates: tuple[float, float] = (0.05, 20.0)) -> tuple[float, float, float] | None:
    """Matched scan for an unmodelled rotor on a rotating rig: for trial coupling rates
    ``c/J`` (1/s) in ``rates``, a unit-inertia rotor about the tangential axis on the
    case's rig motion (:func:`spin_probe_scan`). Returns ``(inertia, damping,
    explained_fraction)`` of the best trial, or ``None`` (the rig does not rotate, or
    nothing explained)."""
    from analogs import Rotor as RotorComponent
    from analogs import SpinningRig

    from ...data.models import ROTOR_AXIS

    if not isinstance(current.problem.model.rig, SpinningRig):
        return None
    grid = np.geomspace(*rates, n)
    best = spin_probe_scan(current, RotorComponent("q", axis=ROTOR_AXIS),
                           [{"q.damping": float(rate)} for rate in grid], case=case)
    return None if best is None else (best[0], best[0] * float(grid[best[1]]), best[2])


def torque_share(ctx: Context) -> float:
    """The torques' share of the scaled residual power (0..1)."""
    return sum(v for k, v in ctx.evidence.channel_share.items() if k.startswith("torque"))


class Rotor(Family):
    """Rotational slosh on a spinning rig: a rotor about the tank's tangential axis, coupled
    by a damper, from a matched scan of its coupling rate."""

    cause, rig = "rotor", "spinning"

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        from analogs import Rotor as RotorComponent

        from ...data.models import ROTOR_AXIS

        scan = ctx.once("rotor scan", lambda: scan_rotor(ctx.current))
        if scan is None:
            return []
        inertia, damping, explained = scan
        name = free_name(ctx.model, "r")
        shares = ctx.evidence.channel_share
        top = max(shares, key=shares.get) if shares else "torque_y"
        tangential = f"torque_{ROTOR_AXIS}"
        torques = torque_share(ctx)

        def plausible(r: FitResult) -> str | None:
            for k in (f"{name}.inertia", f"{name}.damping"):
                if not distinct(r, k):
                    return f"`{k}` = {r.value(k):.3g} is not distinguishable from zero"
            return None

        def describe(r: FitResult) -> str:
            return (f"the residual is concentrated in the torques ({100 * torques:.0f} % of the "
                    f"scaled residual power; largest share {top} {100 * shares.get(top, 0):.0f} %, "
                    f"tangential {tangential} {100 * shares.get(tangential, 0):.0f} %), which the "
                    f"pendulum, tied to the forces, cannot produce; {100 * explained:.0f} % of the "
                    f"residual is the torque of a rotor about the tangential axis driven by the "
                    f"nutation -> rotational slosh; adding rotor {name} (inertia "
                    f"{r.value(f'{name}.inertia'):.3g} kg m^2, damping "
                    f"{r.value(f'{name}.damping'):.3g} N m s/rad)")

        return [Proposal(self.cause, (name,), ctx.model + RotorComponent(name, axis=ROTOR_AXIS),
                         ctx.measurement, {f"{name}.inertia": inertia, f"{name}.damping": damping},
                         plausible=plausible, describe=describe)]
