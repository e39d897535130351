"""The sign check of a record's force channels (a six-axis record's, :mod:`estimate.data.motion`,
and a lateral record's force): each force channel along which the rig accelerates the tank
must read a positive mass moving with it, else the transducer's axis points against the
tank's (:func:`sign_problems`, run when a case loads).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from analogs.motion_rig import ROTATIONS, TRANSLATIONS

from .case import Case, Transducer
from .motion import CHANNELS, motion_excitation, motion_of

__all__ = ["SIGN_MIN_EXPLAINED", "mode_filters", "rig_specific_force", "sign_problems"]

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
                  values: Mapping[str, tuple] | None = None,
                  acceleration: np.ndarray | None = None) -> list[str]:
    """Problems of force channels whose sign is not that of mass times acceleration.

    For each force channel of ``case`` along which the rig accelerates the tank (by
    :data:`_SIGN_MIN_ACCELERATION` or more: :func:`rig_specific_force` ``s`` of a six-axis
    record, the carriage acceleration of a lateral one, differentiated from its
    displacement), the low-passed force is fitted by least squares as
    ``M s + m b + c0 + c1 t``, with ``b`` the response of a linear slosh mode to ``s``
    (``B/A = (2 zeta w s + w^2)/(s^2 + 2 zeta w s + w^2)``, its frequency and damping
    searched on a grid around ``frequency_hz``, ``[prediction]``'s, or the force spectrum's
    peak; ``scipy.signal`` filters it from rest) and an offset and drift of the transducer
    (the mode discretised by the bilinear transform at four samples per period of the
    low-pass). Where that model explains the channel (:data:`SIGN_MIN_EXPLAINED`), the mass
    moving with the tank along it, ``M + m``, must be positive: a negative one is a
    transducer axis that points against the tank's (mounted turned, a cable swapped), named
    in the problem. The slosh term keeps a drive just above resonance, whose force is in
    antiphase with the acceleration once the liquid swings, from being taken for a flipped
    axis. ``acceleration``: a lateral record's carriage acceleration [m/s^2] when the caller
    has differentiated it already.
    """
    t = np.asarray(case.time, float)
    if case.motion is not None:
        have = case.channels
        forces = {c: np.asarray(have[c], float) for c in CHANNELS[:3] if c in have}
        specific = rig_specific_force(case, values) if forces else {}
    elif case.displacement is not None and case.force is not None:
        from .signals import displacement_derivatives

        forces = {"force": np.asarray(case.force, float)}
        if acceleration is None:
            acceleration = displacement_derivatives(t, case.displacement)[2]
        specific = {"force": acceleration}
    else:
        return []
    if frequency_hz is None and case.prediction is not None:
        frequency_hz = math.sqrt(case.rig.gravity / case.prediction.pendulum_length) / (2 * math.pi)
    out = []
    for ch, F in forces.items():
        judged = _reversed_mass(t, F, specific[ch], frequency_hz)
        if judged is None:
            continue
        mass, f, explained = judged
        if case.motion is None:
            out.append(
                f"{case.path.name}: column `force`: the force has the opposite sign of mass x "
                f"acceleration: it reads {mass:.3g} kg times the carriage's acceleration (a "
                f"rigid mass and a slosh mode at {f:.3g} Hz explain {100 * explained:.0f} % of "
                "it); the transducer's axis points against the carriage's displacement: "
                "correct the column's sign")
            continue
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


def mode_filters(f: np.ndarray, zeta: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Numerators and denominators (rows) of the linear slosh mode's filter
    ``B/A = (2 zeta w s + w^2) / (s^2 + 2 zeta w s + w^2)`` at frequencies ``f`` [Hz] and
    damping ratios ``zeta``, by the bilinear transform ``s = 2 fs (1 - 1/z) / (1 + 1/z)``
    at the sample rate ``fs`` [Hz]: what ``scipy.signal.bilinear`` gives, in closed form for
    every mode at once (``bilinear`` takes 1.4 ms a call through NumPy's polynomial
    classes, a third of a second for the check's grid)."""
    w = 2 * np.pi * np.asarray(f, float)
    c, w2, K = 2 * np.asarray(zeta, float) * w, w * w, 2.0 * fs
    num = np.stack([c * K + w2, 2 * w2, w2 - c * K], -1)
    den = np.stack([K * K + c * K + w2, 2 * (w2 - K * K), K * K - c * K + w2], -1)
    return num / den[..., :1], den / den[..., :1]


def _reversed_mass(t: np.ndarray, F: np.ndarray, s: np.ndarray, frequency_hz: float | None
                   ) -> tuple[float, float, float] | None:
    """``(M + m, mode frequency Hz, share explained)`` of :func:`sign_problems`'s model of
    the force ``F`` [N] under the specific force ``s`` [N/kg] when both masses lie several
    standard errors below zero and the model explains the force; else None (not judged, or
    the sign is right)."""
    from scipy import signal

    from .signals import find_spectral_peaks, lowpass

    if np.ptp(s) < _SIGN_MIN_ACCELERATION:
        return None
    dt = float(np.median(np.diff(t)))
    f0 = frequency_hz
    if not (f0 and f0 > 0):
        peaks = find_spectral_peaks(t, F, max_peaks=1)
        if not peaks:
            return None
        f0 = peaks[0].frequency
    cutoff = min(max(4.0 * f0 * _SIGN_BAND[1], 4.0), 0.4 / dt)
    # the reflected ends suffice for a sign (the end model costs a search per channel)
    Fl = lowpass(t, F, cutoff_hz=cutoff, ends="odd")
    sl = lowpass(t, s, cutoff_hz=cutoff, ends="odd")
    step = max(int(1.0 / (4.0 * cutoff * dt)), 1)  # four samples per cutoff period
    tk, Fl, sl = t[::step], Fl[::step], sl[::step]
    ds = sl - sl[0]
    freqs, zetas = (g.ravel() for g in np.meshgrid(f0 * np.geomspace(*_SIGN_BAND, _SIGN_GRID),
                                                   _SIGN_ZETAS, indexing="ij"))
    nums, dens = mode_filters(freqs, zetas, 1.0 / (step * dt))
    B = np.array([signal.lfilter(b, a, ds) for b, a in zip(nums, dens)])
    # every grid point's least squares at once: its normal equations, the fixed columns
    # [ds, 1, t] shared and the mode's column b varying (column-scaled: t is tens of s)
    fixed = np.column_stack([ds, np.ones_like(tk), tk - tk[0]])
    order = [0, 3, 1, 2]  # the columns as X orders them: ds, b, 1, t
    G = np.empty((freqs.size, 4, 4))
    G[:, :3, :3] = fixed.T @ fixed
    cross = B @ fixed
    G[:, 3, :3], G[:, :3, 3], G[:, 3, 3] = cross, cross, np.einsum("ij,ij->i", B, B)
    h = np.empty((freqs.size, 4))
    h[:, :3], h[:, 3] = fixed.T @ Fl, B @ Fl
    G, h = G[:, order][:, :, order], h[:, order]
    scale = np.sqrt(np.einsum("kii->ki", G))
    scale[scale == 0] = 1.0
    coefs = np.einsum("kij,kj->ki", np.linalg.pinv(G / (scale[:, :, None] * scale[:, None, :])),
                      h / scale) / scale
    costs = float(Fl @ Fl) - np.einsum("ki,ki->k", coefs, h)
    best = int(np.argmin(costs))
    X = np.column_stack([ds, B[best], np.ones_like(tk), tk - tk[0]])
    coef, *_ = np.linalg.lstsq(X, Fl, rcond=None)
    r = Fl - X @ coef
    cost = float(r @ r)
    total = float(np.sum((Fl - Fl.mean()) ** 2))
    explained = 1 - cost / total if total > 0 else 0.0
    # both masses negative, each by several of its standard errors (the residual's
    # variance, inflated by the low-pass's correlation): a flipped axis, not a
    # resonance the linear mode reads poorly
    cov = cost / max(tk.size - 4, 1) * np.linalg.pinv(X.T @ X) * (0.5 / (cutoff * step * dt))
    se = np.sqrt(np.clip(np.diag(cov)[:2], 0.0, None))
    flipped = all(coef[k] < -_SIGN_SIGMAS * se[k] for k in (0, 1))
    if explained >= SIGN_MIN_EXPLAINED and flipped:
        return float(coef[0] + coef[1]), float(freqs[best]), explained
    return None
