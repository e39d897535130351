"""The sign check of a six-axis record's force channels (:mod:`estimate.data.motion`): each
force channel along which the rig accelerates the tank must read a positive mass moving with
it, else the transducer's axis points against the tank's (:func:`sign_problems`, run when
a case loads).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from analogs.motion_rig import ROTATIONS, TRANSLATIONS

from .case import Case, Transducer
from .motion import CHANNELS, motion_excitation, motion_of

__all__ = ["SIGN_MIN_EXPLAINED", "rig_specific_force", "sign_problems"]

#: The check's linear model (rigid mass, one slosh mode, offset and drift) must explain this
#: share of a channel's low-passed variance before its sign is trusted: a channel it cannot
#: read (a swirling liquid, a transverse channel of noise) is not judged.
SIGN_MIN_EXPLAINED = 0.6
#: A channel is judged when the rig's own acceleration along it swings by this much
#: [m/s^2] at least (about 1 % of g): a channel the motion hardly drives says nothing.
_SIGN_MIN_ACCELERATION = 0.1
#: Frequencies searched for the slosh mode, relative to the predicted one, the points, and
#: the damping ratios tried at each.
_SIGN_BAND, _SIGN_GRID = (0.5, 2.0), 61
_SIGN_ZETAS = (0.003, 0.01, 0.03, 0.1)
#: The rigid and the slosh mass must both lie this many standard errors below zero.
_SIGN_SIGMAS = 5.0


def rig_specific_force(case: Case, values: Mapping[str, tuple] | None = None
                       ) -> dict[str, NDArray[np.float64]]:
    """The force per kilogram of a point mass at the tank origin (``a_O - g``, N/kg) along
    each transducer axis, from the measured motion of ``case``: the outputs of the case's
    rig alone (:class:`analogs.MotionRig` with a unit dry mass) at the transducer's turn."""
    from analogs import Model, MotionRig
    from derive import derive

    motion = motion_of(case)
    dm = derive(Model((MotionRig(axes=motion.axes),)))
    tr = case.rig.transducer or Transducer()
    params = {"rig.dry_mass": 1.0, "rig.gravity": case.rig.gravity,
              **{f"rig.transducer_{k}": getattr(tr, k) for k in (*TRANSLATIONS, *ROTATIONS)}}
    p = dm.parameter_vector(params)
    exc = motion_excitation(case, values)
    u = exc.values(case.time)
    n = case.time.size
    out = np.asarray(dm.outputs.map(n)(np.zeros((0, n)), u, np.tile(np.reshape(p, (-1, 1)), n),
                                       case.time.reshape(1, -1)))
    from derive import OUTPUT_NAMES

    return {c: out[OUTPUT_NAMES.index(c)] for c in CHANNELS[:3]}


def sign_problems(case: Case, *, frequency_hz: float | None = None,
                  values: Mapping[str, tuple] | None = None) -> list[str]:
    """Problems of force channels whose sign is not that of mass times acceleration.

    For each force channel of ``case`` along which the rig accelerates the tank (by
    :data:`_SIGN_MIN_ACCELERATION` or more, :func:`rig_specific_force` ``s``), the low-passed
    force is fitted by least squares as ``M s + m b + c0 + c1 t``, with ``b`` the response of
    a linear slosh mode to ``s`` (``B/A = (2 zeta w s + w^2)/(s^2 + 2 zeta w s + w^2)``, its
    frequency and damping searched on a grid around ``frequency_hz``, ``[prediction]``'s,
    or the force spectrum's peak; ``scipy.signal`` filters it from rest) and an
    offset and drift of the transducer (the mode discretised by the bilinear transform at
    four samples per period of the low-pass). Where that model explains the channel
    (:data:`SIGN_MIN_EXPLAINED`), the mass moving with the tank along it, ``M + m``, must be
    positive: a negative one is a transducer axis that points against the tank's (mounted
    turned, a cable swapped), named in the problem. The slosh term keeps a drive just above
    resonance, whose force is in antiphase with the acceleration once the liquid swings,
    from being taken for a flipped axis.
    """
    from scipy import signal

    from .signals import find_spectral_peaks, lowpass

    t = np.asarray(case.time, float)
    have = case.channels
    forces = [c for c in CHANNELS[:3] if c in have]
    if not forces:
        return []
    specific = rig_specific_force(case, values)
    dt = float(np.median(np.diff(t)))
    if frequency_hz is None and case.prediction is not None:
        frequency_hz = math.sqrt(case.rig.gravity / case.prediction.pendulum_length) / (2 * math.pi)
    out = []
    for ch in forces:
        s = specific[ch]
        if np.ptp(s) < _SIGN_MIN_ACCELERATION:
            continue
        F = np.asarray(have[ch], float)
        f0 = frequency_hz
        if not (f0 and f0 > 0):
            peaks = find_spectral_peaks(t, F, max_peaks=1)
            if not peaks:
                continue
            f0 = peaks[0].frequency
        cutoff = min(max(4.0 * f0 * _SIGN_BAND[1], 4.0), 0.4 / dt)
        # the reflected ends suffice for a sign (the end model costs a search per channel)
        Fl = lowpass(t, F, cutoff_hz=cutoff, ends="odd")
        sl = lowpass(t, s, cutoff_hz=cutoff, ends="odd")
        step = max(int(1.0 / (4.0 * cutoff * dt)), 1)  # four samples per cutoff period
        tk, Fl, sl = t[::step], Fl[::step], sl[::step]
        ds = sl - sl[0]
        best = None
        for f in f0 * np.geomspace(*_SIGN_BAND, _SIGN_GRID):
            for zeta in _SIGN_ZETAS:
                w = 2 * math.pi * f
                num, den = signal.bilinear([2 * zeta * w, w * w], [1, 2 * zeta * w, w * w],
                                           fs=1.0 / (step * dt))
                b = signal.lfilter(num, den, ds)
                X = np.column_stack([ds, b, np.ones_like(tk), tk - tk[0]])
                coef, *_ = np.linalg.lstsq(X, Fl, rcond=None)
                r = Fl - X @ coef
                cost = float(r @ r)
                if best is None or cost < best[0]:
                    best = (cost, coef, f, X)
        cost, coef, f, X = best
        total = float(np.sum((Fl - Fl.mean()) ** 2))
        explained = 1 - cost / total if total > 0 else 0.0
        # both masses negative, each by several of its standard errors (the residual's
        # variance, inflated by the low-pass's correlation): a flipped axis, not a
        # resonance the linear mode reads poorly
        cov = cost / max(tk.size - 4, 1) * np.linalg.pinv(X.T @ X) * (0.5 / (cutoff * step * dt))
        se = np.sqrt(np.clip(np.diag(cov)[:2], 0.0, None))
        flipped = all(coef[k] < -_SIGN_SIGMAS * se[k] for k in (0, 1))
        mass = float(coef[0] + coef[1])
        if explained >= SIGN_MIN_EXPLAINED and flipped:
            axis = ch[-1]
            out.append(
                f"{case.path.name}: column `{ch}`: the force along the motion has the opposite "
                f"sign of mass x acceleration: it reads {mass:.3g} kg times the rig's "
                f"acceleration along transducer {axis} (a rigid mass and a slosh mode at "
                f"{f:.3g} Hz explain {100 * explained:.0f} % of it); the transducer's {axis} "
                "axis points against the tank's: give its turn in `[rig.transducer]` (`yaw = "
                "3.141592653589793` for one mounted turned by 180 deg about the tank axis) or "
                "correct the column's sign")
    return out
