"""The carriage motion as part of the estimate (errors in variables).

A measured displacement is noisy, and differentiating it twice to drive the model turns
that noise, and every filter's error during the start-up ramp, into force the fit must
explain: it moves the mass split and reports intervals that treat the input as exact. Here
the carriage displacement is instead a quintic B-spline whose coefficients are decision
variables of the same NLP as the parameters. Two residuals tie it to the record: the
measured displacement (weighted by the displacement noise) and the measured force
(weighted by the force noise), so the acceleration that drives the model is the one both
measurements support together.

The knots are uniform, spaced ``1 / (12 f_top)`` with ``f_top`` the highest significant
frequency of the carriage motion (:func:`estimate.data.signals.motion_band`, or the case's
``[test] motion_band_hz``; at least one sample, at most :data:`MAX_SPACING` - also the
spacing of a carriage at rest, whose displacement holds nothing above its noise): a quintic
spline then represents the carriage acceleration to ~2e-4 of its amplitude. The noise band
starts above the carriage motion's frequencies, or, when the carriage stands still, above
the force's own (a free decay's force rings at the slosh frequency). The force residuals
are weighed by the force's noise figure (:mod:`estimate.data.signals.noise_figure`): read
from the record's quiet segments (the rest before the drive, a settled end) when it has
them, else provisionally from the white level above the signal band, and then from the
fit's residual (:mod:`estimate.fitting.noise_figures`). The displacement noise is its white
level above the signal band (:func:`estimate.data.signals.noise_level`), or its quiet
segments' level when that is larger (a low-passed displacement sensor), or the start
spline's misfit when that is clearly larger still: noise that is not white, as a
displacement integrated from an accelerometer has, :data:`COLOURED_FACTOR`. A record that
starts quiet starts with the carriage at rest (zero velocity and acceleration at the first
sample).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg  # noqa: F401  (sps.linalg)

from ..data.signals import (
    motion_band,
    noise_level,
    remove_tones,
    significant_frequencies,
    starts_quiet,
)
from ..data.signals.noise_figure import NoiseFigure, quiet_segments, segment_noise
from .carriage_spline import CarriageInput, CarriageSpline, SplineExcitation, _rest_basis

__all__ = ["CarriageSpline", "CarriageInput", "SplineExcitation", "RecordNoise",
           "carriage_input", "noise_band", "record_noise"]

#: Knots per period of the highest significant carriage frequency.
KNOTS_PER_PERIOD = 6
#: Largest knot spacing [s], also of the knots where the carriage rests (before and after a
#: transport move): there the spline has nothing to follow but would absorb force noise.
MAX_SPACING = 0.25
#: The carriage rests while its displacement stays within this many noise standard
#: deviations of its first (last) value; the knots are dense from MOTION_MARGIN s before it
#: leaves rest to MOTION_MARGIN s after it comes back (the force sees a smooth start first).
REST_SIGMAS = 6.0
MOTION_MARGIN = 0.3
#: The noise band starts this factor above the highest significant carriage frequency, and
#: never below NOISE_BAND_MIN_HZ (the slosh modes and their harmonics live below).
NOISE_BAND_FACTOR = 3.0
NOISE_BAND_MIN_HZ = 12.0
#: Noise levels are floored at this fraction of the signal's RMS: a noiseless synthetic
#: record must not get an infinite weight.
NOISE_FLOOR = 1e-6
#: The displacement noise is taken from the start spline's misfit when that exceeds the
#: white level above the band by this factor (white noise: the two agree within a few per
#: cent; a displacement integrated from an accelerometer: its red noise between the
#: spline's resolution and the band, 10-100 times the level above the band).
COLOURED_FACTOR = 1.5


@dataclass(frozen=True)
class RecordNoise:
    """The force of a record as the estimated-input fit uses it.

    Attributes
    ----------
    force_noise : float
        The force noise (N) the force residuals are divided by: ``figure.std``.
    force : numpy.ndarray
        The recorded force without the tones above ``band_hz`` (N).
    tones : tuple of (float, float)
        The tones removed: frequency (Hz) and amplitude (N).
    band_hz : float
        Lower edge of the band above the mechanics (Hz) where tones were read.
    figure : NoiseFigure
        The force's noise figure as known before the fit: from quiet segments
        (``source == "quiet"``), else the white level above ``band_hz`` (``"spectrum"``,
        provisional: the fit reads the figure from its residual,
        :mod:`estimate.fitting.noise_figures`), or a residual's figure when a fit was
        re-weighed by it (``"residual"``).
    quiet : tuple of (int, int)
        Index ranges of the record's quiet segments.
    """

    force_noise: float
    force: np.ndarray = field(repr=False)
    tones: tuple[tuple[float, float], ...]
    band_hz: float
    figure: NoiseFigure | None = None
    quiet: tuple[tuple[int, int], ...] = ()

    def weighed_by(self, figure: NoiseFigure) -> "RecordNoise":
        """A copy whose force residuals are divided by ``figure``."""
        return replace(self, force_noise=float(figure.std), figure=figure)


def noise_band(top_frequency: float) -> float:
    """Lower edge [Hz] of the band above mechanics reaching up to ``top_frequency`` [Hz]."""
    return max(NOISE_BAND_FACTOR * top_frequency, NOISE_BAND_MIN_HZ)


def record_noise(time: np.ndarray, force: np.ndarray, top_frequency: float, *,
                 quiet: tuple[tuple[int, int], ...] = (),
                 without_tones: tuple[np.ndarray, tuple] | None = None) -> RecordNoise:
    """Noise figure and tones of a recorded force (N) whose mechanics reach up to
    ``top_frequency`` (Hz): tones read above ``max(3 top_frequency, 12 Hz)``; the figure from
    the ``quiet`` segments (index ranges) when there are any, else provisionally the white
    level above that band. ``without_tones``: what :func:`remove_tones` gave for this force
    and band, when the caller has it."""
    band = noise_band(top_frequency)
    F = np.asarray(force, float)
    clean, tones = without_tones or remove_tones(time, F, above_hz=band)
    floor = NOISE_FLOOR * float(np.sqrt(np.mean(F**2)))
    if quiet:
        figure = segment_noise(time, clean, quiet, detail=_quiet_text(time, quiet))
    else:
        figure = NoiseFigure(noise_level(time, clean, above_hz=band), "spectrum", (),
                             float(time[-1] - time[0]),
                             f"white level above {band:.3g} Hz, provisional")
    if figure.std < floor:
        figure = replace(figure, std=floor)
    return RecordNoise(figure.std, clean, tones, band, figure, tuple(quiet))


def _quiet_text(time: np.ndarray, quiet: tuple[tuple[int, int], ...]) -> str:
    names = []
    for a, b in quiet:
        what = "rest before the drive" if a == 0 else "settled end"
        names.append(f"{what} {time[a]:.3g}-{time[b - 1]:.3g} s")
    return "quiet segments: " + ", ".join(names)


def carriage_input(time: np.ndarray, displacement: np.ndarray, *,
                   at_rest: bool | None = None,
                   force: np.ndarray | None = None,
                   motion_band_hz: float | None = None) -> tuple[CarriageInput, RecordNoise]:
    """Spline, start values and noise levels for estimating the carriage motion of a record
    (``time`` s, ``displacement`` m, ``force`` N), and the force's noise. ``at_rest=None``
    detects a quiet start (:func:`estimate.data.signals.starts_quiet` on both channels);
    ``motion_band_hz`` (Hz) is the carriage motion's highest frequency, which sets the knot
    spacing (default: :func:`estimate.data.signals.motion_band` of the displacement).

    The last few records' results are kept (keyed by the samples' bytes): the diagnosis
    builds a problem per candidate model of the same record. The returned objects are
    shared; treat them as read-only."""
    arrays = [None if a is None else np.ascontiguousarray(a, float)
              for a in (time, displacement, force)]
    key = (hashlib.sha256(b"".join(b"" if a is None else a.tobytes() for a in arrays)).hexdigest(),
           tuple(-1 if a is None else a.size for a in arrays), at_rest, motion_band_hz)
    if key not in _RECENT:
        _RECENT[key] = _carriage_input(arrays[0], arrays[1], arrays[2], at_rest=at_rest,
                                       motion_band_hz=motion_band_hz)
        while len(_RECENT) > _RECENT_SIZE:
            _RECENT.pop(next(iter(_RECENT)))
    return _RECENT[key]


_RECENT: dict = {}
_RECENT_SIZE = 4


def adopt_noise(old: RecordNoise, new: RecordNoise) -> None:
    """Keep ``new`` in place of ``old`` among the kept :func:`carriage_input` results: later
    problems built on the same record are weighed by ``new`` at once (a figure read from a
    fit's residual, :func:`estimate.fitting.noise_figures.reweighed`)."""
    for key, (ci, rn) in list(_RECENT.items()):
        if rn is old:
            _RECENT[key] = (ci, new)


def forget_records() -> None:
    """Drop the kept :func:`carriage_input` results (benchmarks time a first fit of a
    record with it)."""
    _RECENT.clear()


def _carriage_input(time: np.ndarray, displacement: np.ndarray, force: np.ndarray, *,
                    at_rest: bool | None, motion_band_hz: float | None = None
                    ) -> tuple[CarriageInput, RecordNoise]:
    t = np.asarray(time, float)
    x = np.asarray(displacement, float)
    dt = float(np.median(np.diff(t)))
    f_motion = motion_band_hz or motion_band(t, x)
    spacing = MAX_SPACING if f_motion is None else \
        min(max(1.0 / (KNOTS_PER_PERIOD * f_motion), dt), MAX_SPACING)
    if f_motion is None:  # a carriage at rest: the force's own mechanics (a free decay's)
        f_top = max(significant_frequencies(t, np.asarray(force, float), derivative=0),
                    default=0.0)
    else:
        f_top = f_motion
    band = noise_band(f_top)
    x_clean, x_tones = remove_tones(t, x, above_hz=band)
    sx = max(noise_level(t, x_clean, above_hz=band), NOISE_FLOOR * float(np.std(x)))
    F_clean, F_tones = remove_tones(t, np.asarray(force, float), above_hz=band)
    quiet = quiet_segments(t, x_clean, F_clean, displacement_noise=sx, band_hz=band,
                           starts_at_rest=at_rest)
    noise = record_noise(t, force, f_top, quiet=quiet, without_tones=(F_clean, F_tones))
    if quiet:
        sx = max(sx, segment_noise(t, x_clean, quiet).std)
    if at_rest is None:
        at_rest = starts_quiet(t, x_clean, sx) and starts_quiet(t, noise.force, noise.force_noise)
    spline = CarriageSpline.graded(float(t[0]), float(t[-1]), spacing,
                                   _moving(t, x_clean, REST_SIGMAS * sx,
                                           1.0 / f_top if f_top > 0 else MAX_SPACING),
                                   MAX_SPACING)
    basis = _rest_basis(spline, float(t[0])) if at_rest else None
    B = spline.design(t) if basis is None else (spline.design(t) @ basis).tocsr()
    coefficients = _least_squares(B, x_clean)
    s_fit = _misfit(B, coefficients, x_clean)
    coloured = s_fit > COLOURED_FACTOR * sx
    if coloured:
        # a drifting displacement leaks into the tone fit (offset and trend only): look
        # for tones in what the spline does not follow, then fit the spline again
        smooth = B @ _least_squares(B, x)
        rest, x_tones = remove_tones(t, x - smooth, above_hz=noise.band_hz)
        x_clean = smooth + rest
        coefficients = _least_squares(B, x_clean)
        s_fit = _misfit(B, coefficients, x_clean)
        coloured = s_fit > COLOURED_FACTOR * sx
    ci = CarriageInput(spline, basis, coefficients, s_fit if coloured else sx, x_clean, x_tones,
                       bool(at_rest), coloured_noise=coloured)
    return ci, noise


def _misfit(B: sps.spmatrix, coefficients: np.ndarray, x: np.ndarray) -> float:
    """Standard deviation of what the spline (design ``B``) misses of ``x`` (its degrees of
    freedom: samples less coefficients)."""
    r = x - B @ coefficients
    return float(np.sqrt(r @ r / max(x.size - B.shape[1], 1)))


def _moving(t: np.ndarray, x: np.ndarray, tolerance: float, period: float
            ) -> tuple[float, float]:
    """The span (s) in which the carriage moves: from a margin before the displacement ``x``
    (m) first leaves ``tolerance`` of its first value to a margin after it last leaves
    that of its final one; the margin is :data:`MOTION_MARGIN` s, at least ``period``."""
    away = np.flatnonzero(np.abs(x - np.median(x[:10])) > tolerance)
    back = np.flatnonzero(np.abs(x - np.median(x[-10:])) > tolerance)
    if away.size == 0 or back.size == 0:
        return float(t[0]), float(t[-1])
    margin = max(MOTION_MARGIN, period)
    return float(t[away[0]] - margin), float(t[back[-1]] + margin)


def _least_squares(B: sps.spmatrix, x: np.ndarray) -> np.ndarray:
    """Coefficients of the spline (design ``B``) through the samples ``x``."""
    A = (B.T @ B).tocsc()
    # a ridge far below the data's weight keeps every coefficient defined
    A = A + 1e-10 * A.diagonal().mean() * sps.identity(A.shape[0], format="csc")
    return np.asarray(sps.linalg.spsolve(A, B.T @ x)).ravel()
