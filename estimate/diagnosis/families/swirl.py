"""Swirl: the liquid of a tank driven along one axis near its first mode moves across the
drive as well. Above a threshold amplitude the planar slosh solution is unstable (Miles;
Abramson, NASA SP-106 ch. 3) and the free surface rotates; a planar pendulum cannot follow,
a :class:`~analogs.SphericalPendulum` can. On a six-axis record with a planar drive the
transverse channels (``force_y``, ``torque_x``, ``torque_z``) then carry a slosh-band signal
the planar analog leaves in the residual; the family replaces each planar pendulum by a
spherical one with the same parameters (the model's motion carries the drive's small
cross-axis part, which seeds the swirl as it does on the rig). A record of the force along
the drive alone shows a swirl only as a slosh-band misfit (the planar swing beats instead
of growing); the family is then proposed when the drive has a cross-axis part to seed it in
the model, and the fit's gain decides - else the diagnosis says "unexplained"."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from analogs import Model, Pendulum, SphericalPendulum

from ...data.signals import welch_spectrum
from ...fitting.result import FitResult
from .base import Context, Family, Proposal, Score, frequency

__all__ = ["Swirl", "transverse_band_ratio", "swirl_evidence", "transverse_drive", "TRANSVERSE_CHANNELS",
           "PLANAR_DRIVE"]

#: The channels only slosh out of the drive's plane (x-z) moves.
TRANSVERSE_CHANNELS = ("force_y", "torque_x", "torque_z")
#: The slosh band around the fitted first mode, as fractions of its frequency: a swirling
#: surface beats between the planar and the rotating response within it.
BAND = (0.7, 1.4)
#: The transverse residual is swirl evidence when its power density in :data:`BAND` is at
#: least this many times its median elsewhere (white noise gives about 1; a tone outside
#: the band does not move the median).
MIN_BAND_RATIO = 10.0
#: A six-axis record's drive is planar (x-z) when its cross-axis specific force is at most
#: this fraction of the in-plane one (:func:`transverse_drive`): a carriage's guide lets
#: through about 1 %. The diagnosis then starts from planar pendulums, and transverse slosh
#: is swirl; a larger cross-axis drive moves the liquid across by force, and the baseline's
#: pendulums are spherical.
PLANAR_DRIVE = 0.05


def transverse_drive(case) -> float:
    """The cross-axis over the in-plane lateral specific force of a six-axis record
    (``[rig.motion]``): the RMS of ``a_y + g roll`` over that of ``a_x - g pitch`` (small
    angles; yaw of an axisymmetric tank drives no slosh), from the measured motion smoothed
    and differentiated as the fit does (:func:`estimate.data.motion.motion_values`).
    0 for a record without cross-axis motion; ``inf`` when it has no in-plane one."""
    from ...data.motion import motion_values

    if getattr(case, "motion", None) is None:
        return 0.0
    values = motion_values(case)
    g = case.rig.gravity
    n = case.time.size
    zero = np.zeros(n)

    def acc(axis: str) -> np.ndarray:
        return values[axis][2] if axis in values else zero

    def angle(axis: str) -> np.ndarray:
        return values[axis][0] - values[axis][0][0] if axis in values else zero

    across = float(np.std(acc("y") + g * angle("roll")))
    along = float(np.std(acc("x") - g * angle("pitch")))
    if across == 0.0:
        return 0.0
    return across / along if along > 0 else math.inf


def transverse_band_ratio(result: FitResult, case: int = 0, *,
                          channels: Sequence[str] = TRANSVERSE_CHANNELS) -> tuple[float, str | None]:
    """The largest ratio, over the fitted ``channels`` of ``case`` (default: the transverse
    ones), of the residual's power density in the first mode's band (:data:`BAND`) to its
    median outside it, and the channel it is on (``(0.0, None)`` when the case fits none
    of them or the fit has no first-mode frequency)."""
    f1 = frequency(result, "p1")
    chans = result.channels[case] if result.channels else ()
    if not math.isfinite(f1) or not chans:
        return 0.0, None
    t = np.asarray(result.problem.experiments[case].case.time, float)
    fs = 1.0 / float(np.median(np.diff(t)))
    res = np.asarray(result.residuals[case], float).reshape(t.size, -1)
    best, where = 0.0, None
    for k, c in enumerate(chans):
        if c not in channels:
            continue
        spec = welch_spectrum(t, res[:, k], nperseg=min(t.size, int(round(16 * fs / f1))))
        f, p = spec.frequency, spec.psd
        band = (f >= BAND[0] * f1) & (f <= BAND[1] * f1)
        out = ~band & (f > 0)
        floor = float(np.median(p[out])) if out.any() else 0.0
        if not band.any() or floor <= 0:
            continue
        ratio = float(np.mean(p[band])) / floor
        if ratio > best:
            best, where = ratio, c
    return best, where


def swirl_evidence(result: FitResult, case: int = 0) -> tuple[float, str | None]:
    """The slosh-band ratio (:func:`transverse_band_ratio`) swirl is proposed on: of the
    transverse channels when the record has one; else, on a record whose drive has a
    cross-axis part that can seed a swirl (:func:`transverse_drive` above 0), of the channels
    along the drive (a swirl takes energy out of the planar swing: the force along the drive
    beats where a planar pendulum's keeps growing)."""
    chans = result.channels[case] if result.channels else ()
    if any(c in TRANSVERSE_CHANNELS for c in chans):
        return transverse_band_ratio(result, case)
    if transverse_drive(result.problem.experiments[case].case) > 0:
        return transverse_band_ratio(result, case, channels=chans)
    return 0.0, None


def _spherical(model: Model) -> tuple[Model, tuple[str, ...]]:
    """``model`` with every planar :class:`Pendulum` replaced by a spherical one of the same
    name (same parameters), and the names replaced."""
    names = tuple(c.name for c in model.components if type(c) is Pendulum)
    return Model(SphericalPendulum(c.name) if type(c) is Pendulum else c
                 for c in model.components), names


class Swirl(Family):
    """Swirl: on a six-axis record of a planar drive the transverse channels carry a
    slosh-band signal a planar pendulum cannot make; each planar pendulum becomes a
    spherical one (same parameters), whose cross-axis swing the fit measures."""

    cause, rig = "swirl", "motion"

    def applies(self, ctx: Context) -> bool:
        return (super().applies(ctx)
                and any(type(c) is Pendulum for c in ctx.model.components))

    def why_not(self, ctx: Context) -> str | None:
        ratio, chan = ctx.once("swirl band", lambda: swirl_evidence(ctx.current))
        if ratio >= MIN_BAND_RATIO:
            return None
        if chan is None:
            return ("swirl not tried: the record has no transverse channel and its drive no "
                    "cross-axis part to seed one")
        return (f"swirl not tried: the residual ({chan}) holds no slosh-band signal "
                f"({ratio:.1f} x its level elsewhere, below {MIN_BAND_RATIO:g})")

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        ratio, chan = ctx.once("swirl band", lambda: swirl_evidence(ctx.current))
        if chan is None or ratio < MIN_BAND_RATIO:
            return []
        model, names = _spherical(ctx.model)
        f1 = frequency(ctx.current, "p1")

        transverse = chan in TRANSVERSE_CHANNELS
        look = TRANSVERSE_CHANNELS if transverse else (chan,)

        def plausible(r: FitResult) -> str | None:
            after, _ = transverse_band_ratio(r, channels=look)
            if not after < ratio:
                return (f"the spherical pendulum leaves the slosh band of {chan} as it was "
                        f"({after:.1f} x the level elsewhere, was {ratio:.1f} x)")
            return None

        def describe(r: FitResult) -> str:
            after, _ = transverse_band_ratio(r, channels=look)
            seen = ("the transverse channels carry a slosh-band signal" if transverse else
                    "the force along the drive holds a slosh-band residual")
            return (f"the drive is planar, yet {seen} ({chan}: {ratio:.0f} x the residual's "
                    f"level elsewhere, around the first mode's {f1:.3g} Hz) that a planar "
                    f"pendulum cannot make -> the liquid swirls; {', '.join(names)} made "
                    f"spherical (same parameters; the band falls to {after:.1f} x)")

        return [Proposal(self.cause, tuple(f"{n}:spherical" for n in names), model,
                         ctx.measurement, {}, score=ratio, first=True,
                         plausible=plausible, describe=describe)]
