"""Measurement noise of a record: the white-noise level seen above the signal band, and
whether the record starts quiet (tank and carriage at rest)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ._common import _as_uniform, _refine_frequency

__all__ = ["noise_level", "remove_tones", "starts_quiet"]

#: Fraction of the Nyquist frequency up to which the noise band reaches (anti-alias filters
#: of acquisition systems roll off near Nyquist).
_BAND_TOP = 0.9


def _linear_detrend(segments: np.ndarray) -> np.ndarray:
    """Each segment (last axis) minus its least-squares line: SciPy's ``detrend="linear"``
    for all segments at once (it solves one least-squares problem per segment)."""
    n = segments.shape[-1]
    x = np.arange(n) - (n - 1) / 2
    mean = segments.mean(axis=-1, keepdims=True)
    slope = (segments @ x)[..., None] / (x @ x)
    return segments - mean - slope * x


def noise_level(time: ArrayLike, values: ArrayLike, *, above_hz: float) -> float:
    """Standard deviation of the white noise on ``values`` (same unit; sampled at the
    uniform ``time``, s), from the Welch spectrum between ``above_hz`` and 0.9 times the
    Nyquist frequency.

    The median PSD of that band is used, so tones (motor, mains) and a few harmonics of the
    signal do not count; a white noise of standard deviation ``s`` has the one-sided PSD
    ``2 s^2 / fs``. When the band is empty (``above_hz`` at or beyond Nyquist) the upper
    half of the spectrum is used.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3001) * 0.01
    >>> y = np.sin(2 * np.pi * 1.9 * t) + np.random.default_rng(1).normal(0, 0.02, t.size)
    >>> round(noise_level(t, y, above_hz=10.0), 3)
    0.02
    """
    from scipy import signal
    t, y, step = _as_uniform(time, values, "values")
    fs = 1.0 / step
    f, p = signal.welch(y, fs=fs, window="hann", nperseg=min(t.size, 256),
                        detrend=_linear_detrend)
    band = (f >= above_hz) & (f <= _BAND_TOP * fs / 2)
    if np.count_nonzero(band) < 4:
        band = (f >= fs / 4) & (f <= _BAND_TOP * fs / 2)
    return float(np.sqrt(np.median(p[band]) * fs / 2))


#: A tone's amplitude in each quarter of the record is at least this fraction of the largest.
STEADY_RATIO = 0.5


def _steady(t: np.ndarray, y: np.ndarray, frequency: float) -> bool:
    """Whether the sinusoid at ``frequency`` has a steady amplitude over the quarters of the
    record (offset, trend and the sinusoid fitted in each)."""
    amps = []
    for tq, yq in zip(np.array_split(t, 4), np.array_split(y, 4)):
        tc = tq - tq.mean()
        w = 2 * np.pi * frequency
        A = np.column_stack([np.ones_like(tc), tc, np.cos(w * tc), np.sin(w * tc)])
        coef, *_ = np.linalg.lstsq(A, yq, rcond=None)
        amps.append(float(np.hypot(coef[2], coef[3])))
    return min(amps) >= STEADY_RATIO * max(amps)


def starts_quiet(time: ArrayLike, values: ArrayLike, noise: float, *,
                 seconds: float = 0.1, factor: float = 3.0) -> bool:
    """Whether the first ``seconds`` of ``values`` (sampled at ``time``, s) hold nothing but
    noise of standard deviation ``noise``: their spread about their mean is below
    ``factor * noise``."""
    t, y, step = _as_uniform(time, values, "values")
    n = max(int(round(seconds / step)), 8)
    head = y[:n]
    return bool(np.std(head) <= factor * max(noise, 1e-300))


def remove_tones(time: ArrayLike, values: ArrayLike, *, above_hz: float,
                 prominence: float = 30.0, max_tones: int = 8
                 ) -> tuple[np.ndarray, tuple[tuple[float, float], ...]]:
    """``values`` (sampled at ``time``, s) without the spectral lines (motor and electrical
    tones) above ``above_hz``, at most ``max_tones`` of them, and the lines removed as
    ``(frequency Hz, amplitude)``.

    A line is a Welch peak above ``above_hz`` whose PSD exceeds ``prominence`` times the
    median PSD of that band and whose amplitude is steady over the record (each quarter's
    within a factor :data:`STEADY_RATIO` of the largest: a burst, such as a transport move's
    force or a servo's ripple while moving, is no tone, and a sinusoid fitted across the
    whole record would add it where it is absent); its frequency is refined and all lines
    are fitted together (offset, trend and one sinusoid each) and subtracted. Only the band
    above the signal is searched, so nothing of the mechanics is removed.
    """
    from scipy import signal
    t, y, step = _as_uniform(time, values, "values")
    fs = 1.0 / step
    top = _BAND_TOP * fs / 2
    if above_hz >= top:
        return y.copy(), ()
    nper = min(t.size, 256)
    f, p = signal.welch(y, fs=fs, window="hann", nperseg=nper, detrend=_linear_detrend)
    band = np.flatnonzero((f >= above_hz) & (f <= top))
    if band.size < 4:
        return y.copy(), ()
    floor = float(np.median(p[band]))
    idx, _ = signal.find_peaks(p[band], height=prominence * floor)
    idx = band[idx[np.argsort(p[band][idx])[::-1][:max_tones]]]
    if idx.size == 0:
        return y.copy(), ()
    freqs = [_refine_frequency(t, y, float(f[i]), fs / nper) for i in idx]
    freqs = [fk for fk in freqs if _steady(t, y, fk)]
    if not freqs:
        return y.copy(), ()
    tc = t - t.mean()
    cols = [np.ones_like(tc), tc]
    for fk in freqs:
        w = 2 * np.pi * fk
        cols += [np.cos(w * tc), np.sin(w * tc)]
    A = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    lines = A[:, 2:] @ coef[2:]
    tones = tuple((fk, float(np.hypot(coef[2 + 2 * k], coef[3 + 2 * k])))
                  for k, fk in enumerate(freqs))
    return y - lines, tones
