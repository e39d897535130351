"""The spinning rig's motion from a case: measured rig angles (smoothed without phase lag
and differentiated, as the lateral carriage displacement is) or schedules, as the rig's
input signals."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from analogs.errors import InputError
from analogs.spinning import MOTION_INPUTS
from derive import Excitation, Sampled
from derive.schedule import Schedule, SmoothRamp, Stacked

from .case import Case, Spin

__all__ = ["rig_angle_derivatives", "spin_column_problems", "spin_excitation", "spin_angles"]

#: A measured rig angle is smoothed on at most this many points: longer or faster records
#: are averaged in blocks of consecutive samples first (rig motion is slow: a spin-up over
#: seconds, a cone ramp, coning below a few Hz), which keeps the cross-validation fast.
ANGLE_POINTS = 1200
#: The measured spin rate over the last tenth of the record may differ from `[rig.spin]
#: rate` by this fraction (plus 0.05 rad/s) before the case is refused as inconsistent.
RATE_MISMATCH = 0.05


def rig_angle_derivatives(time: NDArray[np.float64], angle: NDArray[np.float64], *,
                          wrapped: bool = True
                          ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """A measured rig angle (rad) smoothed without phase lag, with its rate (rad/s) and
    acceleration (rad/s^2).

    The angle is unwrapped (``wrapped``: an encoder reading modulo 2 pi) and fitted by a
    cubic smoothing spline whose smoothing the data choose by generalized cross-validation
    (:func:`scipy.interpolate.make_smoothing_spline`); the spline and its first two
    derivatives are evaluated on ``time``. A spin-up is not periodic, so the lateral
    displacement's filter (:func:`estimate.data.signals.displacement_derivatives`, whose end
    extension assumes a periodic drive) would distort the ends of the record. Records of
    more than :data:`ANGLE_POINTS` samples are first averaged in blocks. The spline's
    natural ends have zero acceleration: the table at rest or at a steady rate there.
    """
    from scipy.interpolate import make_smoothing_spline

    t = np.asarray(time, float)
    y = np.unwrap(np.asarray(angle, float)) if wrapped else np.asarray(angle, float)
    k = max(1, -(-t.size // ANGLE_POINTS))
    m = t.size // k
    tb = t[:m * k].reshape(m, k).mean(axis=1)
    yb = y[:m * k].reshape(m, k).mean(axis=1)
    if m * k < t.size:  # the last samples as one more (shorter) block
        tb, yb = np.r_[tb, t[m * k:].mean()], np.r_[yb, y[m * k:].mean()]
    spline = make_smoothing_spline(tb, yb)
    return spline(t), spline(t, 1), spline(t, 2)


def spin_angles(case: Case) -> dict[str, NDArray[np.float64]]:
    """The measured rig angles of ``case`` by input name (rad): the spin angle (from a
    measured rate: its integral from 0), the nutation phase and the cone angle."""
    from scipy.integrate import cumulative_trapezoid
    spin = _spin(case)
    cols = case.channels
    out = {}
    if spin.spin_angle is not None:
        out["spin_angle"] = np.unwrap(cols[spin.spin_angle])
    elif spin.spin_rate is not None:
        out["spin_angle"] = cumulative_trapezoid(cols[spin.spin_rate], case.time, initial=0.0)
    if spin.nutation_phase is not None:
        out["nutation_phase"] = np.unwrap(cols[spin.nutation_phase])
    if spin.cone_angle is not None:
        out["cone_angle"] = np.asarray(cols[spin.cone_angle], float)
    return out


def spin_excitation(case: Case) -> Excitation:
    """The input signals of :class:`analogs.SpinningRig` (``motion="input"``) for ``case``:
    each measured angle (:func:`spin_angles`) smoothed and differentiated
    (:func:`rig_angle_derivatives`) and interpolated (:class:`derive.Sampled`), the others
    from the schedules of ``[rig.spin]`` (:class:`derive.schedule.SmoothRamp`, times from
    the first sample), in the order of :data:`analogs.spinning.MOTION_INPUTS`."""
    spin = _spin(case)
    t = np.asarray(case.time, float)
    t0 = float(t[0])
    measured = spin_angles(case)
    scheduled = {
        "spin_angle": SmoothRamp(spin.rate, spin.spin_up, t0 if spin.spin_up else 0.0, "rate"),
        "nutation_phase": SmoothRamp(2 * math.pi * spin.nutation_frequency, kind="rate"),
        "cone_angle": SmoothRamp(spin.nutation_angle, spin.nutation_ramp,
                                 t0 + spin.ramp_start if spin.nutation_ramp else 0.0),
    }
    parts: list[Excitation] = []
    for name in MOTION_INPUTS:
        if name in measured:
            x, xd, xdd = rig_angle_derivatives(t, measured[name], wrapped=name != "cone_angle")
            parts.append(Sampled(t, np.vstack([x, xd, xdd])))
        else:
            parts.append(Schedule((scheduled[name],)))
    if all(isinstance(p, Schedule) for p in parts):
        return Schedule(tuple(s for p in parts for s in p.signals))
    return Stacked(tuple(parts))


def spin_column_problems(fname: str, spin: Spin | None, columns: Mapping[str, np.ndarray],
                         time: np.ndarray) -> list[str]:
    """Problems of the measured-motion columns ``[rig.spin]`` names: missing from the CSV,
    or a spin angle or rate that disagrees with the nominal ``rate`` at the end of the
    record (by more than :data:`RATE_MISMATCH`)."""
    if spin is None:
        return []
    problems = []
    for key, col in spin.columns.items():
        if col not in columns:
            problems.append(f"{fname}: [rig.spin] {key}: the CSV has no column `{col}` (its "
                            f"columns are {', '.join(f'`{c}`' for c in columns)})")
    if problems or not (spin.spin_angle or spin.spin_rate):
        return problems
    t = np.asarray(time, float)
    tail = slice(int(0.9 * t.size), None)
    if spin.spin_angle is not None:
        y = np.unwrap(columns[spin.spin_angle])
        rate = float(np.polyfit(t[tail], y[tail], 1)[0])
        col = spin.spin_angle
    else:
        col = spin.spin_rate
        rate = float(np.median(columns[col][tail]))
    if abs(rate - spin.rate) > RATE_MISMATCH * abs(spin.rate) + 0.05:
        problems.append(f"{fname}: [rig.spin] rate: {spin.rate!r} rad/s, but column `{col}` "
                        f"turns at {rate:.4g} rad/s over the last tenth of the record; `rate` "
                        "is the nominal (final) spin rate of the test")
    return problems


def _spin(case: Case) -> Spin:
    if case.spin is None:
        raise InputError(f"{case.path}: not a spinning-rig case (no `[rig.spin]` table)")
    return case.spin
