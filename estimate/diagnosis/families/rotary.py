"""A rotary torque resonance of the liquid on a spinning rig (Green et al.): a rotary
oscillator (inertia on a spring and damper about the tank's radial and tangential axes),
from a matched scan of its natural frequency above the spin rate, proposed when the
residual is mostly torque and the oscillator explains clearly more of it than a rotor."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...fitting.result import FitResult
from ..scoring import distinct
from .base import Context, Family, Proposal, Score, free_name
from .rotor import scan_rotor, spin_probe_scan, torque_share

__all__ = ["RotaryOscillator", "scan_rotary", "rotary_axes"]

#: Damping ratio of the probe of :func:`scan_rotary`: more than a slosh resonance has, so
#: that a trial frequency a grid step from a sharp resonance still correlates with its
#: response.
PROBE_DAMPING = 0.05
#: The oscillator is proposed only when its scan explains this much more of the residual
#: than the rotor scan (an oscillator with a soft spring imitates a rotor), and when the
#: torques hold at least :data:`TORQUE_SHARE` of the scaled residual power.
ROTARY_MARGIN = 0.05
TORQUE_SHARE = 0.5


def rotary_axes(rig) -> str:
    """The axes of a :class:`~analogs.RotaryOscillator` about the tank's radial and
    tangential directions: ``"xy"`` when the tank axis is the spin axis, ``"zy"`` when it
    points inward (:class:`~analogs.SpinningRig` ``tank_axis``)."""
    return "xy" if rig.tank_axis == "spin" else "zy"


def scan_rotary(current: FitResult, *, case: int = 0, n: int = 24,
                ratios: tuple[float, float] = (1.05, 6.0)) -> tuple[float, float, float] | None:
    """Matched scan for an unmodelled rotary oscillator: for trial natural frequencies
    ``omega_0`` (rad/s) from ``ratios`` times the spin rate (above it, where an oscillator
    damped relative to the tank is stable), a unit-inertia oscillator with stiffness
    ``omega_0^2`` and damping ratio :data:`PROBE_DAMPING` on the case's rig motion
    (:func:`~estimate.diagnosis.families.rotor.spin_probe_scan`; its torques are
    proportional to its inertia at a given frequency and damping ratio). Returns
    ``(inertia, natural_frequency_rad_s, explained_fraction)``, or ``None``."""
    from analogs import RotaryOscillator as Oscillator
    from analogs import SpinningRig

    problem = current.problem
    rig = problem.model.rig
    spin = problem.experiments[case].case.spin
    if not isinstance(rig, SpinningRig) or spin is None or not spin.rate:
        return None
    grid = abs(spin.rate) * np.geomspace(*ratios, n)
    best = spin_probe_scan(current, Oscillator("q", axes=rotary_axes(rig)),
                           [{"q.stiffness": float(w0**2), "q.damping": 2 * PROBE_DAMPING * float(w0)}
                            for w0 in grid], case=case)
    return None if best is None else (best[0], float(grid[best[1]]), best[2])


class RotaryOscillator(Family):
    """A rotary torque resonance of the liquid on a spinning rig: a rotary oscillator from a
    matched scan of its natural frequency above the spin rate, when it explains the torques
    clearly better than a rotor."""

    cause, rig = "rotary_oscillator", "spinning"

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        from analogs import RotaryOscillator as Oscillator

        torques = torque_share(ctx)
        if torques < TORQUE_SHARE:
            return []
        rotor = ctx.once("rotor scan", lambda: scan_rotor(ctx.current))
        rotor_explained = rotor[2] if rotor is not None else 0.0
        scan = scan_rotary(ctx.current)
        if scan is None or scan[2] < rotor_explained + ROTARY_MARGIN:
            return []
        inertia, w0, explained = scan
        spin = abs(ctx.current.problem.experiments[0].case.spin.rate)
        name = free_name(ctx.model, "o")
        shares = ctx.evidence.channel_share
        top = max(shares, key=shares.get)

        def plausible(r: FitResult) -> str | None:
            for k in (f"{name}.inertia", f"{name}.stiffness"):
                if not distinct(r, k):
                    return f"`{k}` = {r.value(k):.3g} is not distinguishable from zero"
            f = r.derived.get(f"{name}.frequency_hz", (math.nan, 0.0))[0]
            if not 2 * math.pi * f > spin:
                return (f"natural frequency {f:.3g} Hz is not above the spin rate "
                        f"({spin / (2 * math.pi):.3g} Hz): unstable with damping in the tank")
            return None

        def describe(r: FitResult) -> str:
            f = r.derived.get(f"{name}.frequency_hz", (math.nan, 0.0))[0]
            zeta = r.derived.get(f"{name}.damping_ratio", (math.nan, 0))[0]
            return (f"the residual is concentrated in the torques ({100 * torques:.0f} % of the "
                    f"scaled residual power; largest share {top} {100 * shares.get(top, 0):.0f} %) "
                    f"with little force, which the pendulum cannot produce; "
                    f"{100 * explained:.0f} % of it is the torque of an oscillator resonating "
                    f"near {w0 / (2 * math.pi):.3g} Hz (a rotor explains "
                    f"{100 * rotor_explained:.0f} %) -> a rotary torque resonance of the liquid; "
                    f"adding rotary oscillator {name} (inertia {r.value(f'{name}.inertia'):.3g} "
                    f"kg m^2, natural frequency {f:.4g} Hz, damping ratio {zeta:.3g})")

        return [Proposal(
            self.cause, (name,), ctx.model + Oscillator(name, axes=rotary_axes(ctx.model.rig)),
            ctx.measurement,
            {f"{name}.inertia": inertia, f"{name}.stiffness": inertia * w0**2,
             f"{name}.damping": 2 * PROBE_DAMPING * inertia * w0},
            plausible=plausible, describe=describe)]
