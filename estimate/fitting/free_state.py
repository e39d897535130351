"""Free initial states: where they start, and what a record with the carriage at rest
determines.

Where a free initial state starts: the liquid's state at the first sample, read off the
record before the fit.

A free decay (the carriage at rest, the liquid swinging at the first sample) or a window
cut from a running test starts with the liquid moving. With ``[test] initial_state =
"free"`` the state at the first sample is estimated with the parameters, but the NLP's
states need a start: a simulation from rest explains none of a free decay's force, and
IPOPT then leans on directions the record does not determine (a fixed mass times the
carriage's noise-level acceleration grew to 1e5 kg on a 12 s decay of an 8-inch sphere).

Here the state is read off the first periods of the record by linear least squares: at
the initial parameters the analog's response is, for swings of a few tenths of a radian,
close to linear in its initial state, so the measured channels minus the response from
rest are regressed on the responses to each state component alone (one simulation per
state, over the fitted window only). The states' trajectory then starts from a simulation
from that state. This is the start of an estimate, not the estimate: the NLP refines the
state with the parameters.

What a carriage at rest determines: when no case's carriage moves (its displacement holds
nothing above its noise, :func:`estimate.data.signals.motion_band`), the force is the
liquid's alone: the record fixes the modes' frequencies and damping and each swing's
force amplitude, not the masses (a rigid mass multiplies an acceleration the carriage does
not have; a mode's mass only its swing, which is estimated with it). Those masses are held
at their start values, with a note (:func:`rest_holds`), instead of being estimated along
directions the data do not determine (a fixed mass times the spline's noise-level
acceleration, 2.6e5 kg on that decay).
"""

from __future__ import annotations

import math

import numpy as np

from analogs.errors import InputError
from derive import RK4, simulate

from ..data.signals import dominant_frequency, motion_band

__all__ = ["free_starts", "rest_holds", "START_PERIODS", "LARGEST_SWING"]

#: Periods of the record's dominant force frequency the initial state is read from.
START_PERIODS = 3.0
#: Largest initial coordinate accepted (rad for a pendulum angle): a read-off beyond it is
#: clipped, the NLP takes it from there.
LARGEST_SWING = 1.0


def rest_holds(experiments, names: list[str]) -> tuple[list[str], list[str]]:
    """The masses among ``names`` (estimated parameters) that lateral records whose carriage
    never moves cannot determine, and a note saying why they are held (module docstring);
    nothing when a case's carriage moves, or is not measured.

    Raises
    ------
    InputError
        When such a record's liquid starts at rest too: nothing moves, nothing to fit.
    """
    if not experiments or any(e.case.test.rig != "lateral" or e.case.displacement is None
                              for e in experiments):
        return [], []
    if any(motion_band(e.case.time, e.case.displacement) is not None for e in experiments):
        return [], []
    still = [e.case for e in experiments if (e.case.test.initial_state or "rest") == "rest"]
    if still:
        ids = ", ".join(f"`{c.path.name}`" for c in still)
        raise InputError(f"{ids}: the carriage does not move (the displacement holds nothing "
                         "above its noise) and `[test] initial_state` is \"rest\": nothing "
                         "moves the liquid; for a free decay (the liquid swinging at the first "
                         "sample) give `[test] initial_state = \"free\"`")
    rigid = ("fixed.mass", "rig.dry_mass")
    moving = {c.split(".")[0] for e in experiments for c in e.derived.coordinates}
    held = [n for n in names if n in rigid or (n.endswith(".mass") and n.split(".")[0] in moving)]
    if not held:
        return [], []
    note = ("the carriage does not move in any case (free decays): the record determines "
            "the modes' frequencies and damping, not the masses; held at their start values: "
            + ", ".join(f"`{n}`" for n in held))
    return held, [note]


def free_starts(problem, kinds: list[str]) -> list:
    """Per case, the states a free initial state starts from
    (:class:`~estimate.fitting.terms.WarmStart` with a simulation from the state read off
    the record), ``None`` for other cases."""
    from .terms import WarmStart, _measured_force

    out: list = []
    for i, (exp, kind) in enumerate(zip(problem.experiments, kinds)):
        dm = exp.derived
        if kind != "free" or not dm.nx:
            out.append(None)
            continue
        carriage = problem.carriage[i] if problem.carriage else None
        excitation = (carriage.excitation(carriage.coefficients) if carriage is not None
                      else exp.excitation)
        values = problem.case_values(i, problem.initial)
        measured, weights = _measured_force(problem, i)
        x0 = _read_state(problem, i, values, excitation, measured, weights)
        t = np.asarray(exp.case.time, float)
        states = simulate(dm, values, t, excitation, integrator=RK4(), x0=x0).states.T
        out.append(WarmStart(dm.coordinates, states, None) if np.all(np.isfinite(states))
                   else None)
    return out


def _read_state(problem, i: int, values, excitation, measured, weights) -> np.ndarray:
    """The state at the first sample whose response best matches the first periods of the
    record (module docstring)."""
    exp = problem.experiments[i]
    dm = exp.derived
    t = np.asarray(exp.case.time, float)
    chans = problem.channels(i)
    Y = np.asarray(measured, float).reshape(t.size, len(chans), order="F")
    scale = problem.channel_scales(i)
    s = np.array([scale[c] for c in chans])
    try:
        f = dominant_frequency(t, Y[:, 0], min_frequency=2.0 / (t[-1] - t[0]))
    except (ValueError, ArithmeticError):
        f = 1.0
    n = int(min(t.size, max(20, np.searchsorted(t, t[0] + START_PERIODS / f))))
    tw = t[:n]
    w = np.asarray(weights, float)[:n, None] > 0

    def response(x0: np.ndarray | None) -> np.ndarray:
        sim = simulate(dm, values, tw, excitation, integrator=RK4(), x0=x0, outputs=chans)
        return sim.outputs / s[None, :]

    base = response(None)
    omega = 2 * math.pi * f
    nq = len(dm.coordinates)
    steps = np.array([0.05] * nq + [0.05 * omega] * nq)  # rad (or m), rad/s (or m/s)
    columns = []
    for j, step in enumerate(steps):
        x0 = np.zeros(dm.nx)
        x0[j] = step
        columns.append(((response(x0) - base) / step * w).ravel())
    A = np.column_stack(columns)
    b = ((Y[:n] / s[None, :] - base) * w).ravel()
    ok = np.all(np.isfinite(A), axis=0)
    x = np.zeros(dm.nx)
    if np.any(ok) and np.all(np.isfinite(b)):
        x[ok] = np.linalg.lstsq(A[:, ok], b, rcond=1e-10)[0]
    x[:nq] = np.clip(x[:nq], -LARGEST_SWING, LARGEST_SWING)
    x[nq:] = np.clip(x[nq:], -LARGEST_SWING * omega, LARGEST_SWING * omega)
    return x
