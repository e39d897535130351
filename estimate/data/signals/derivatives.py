"""Carriage velocity and acceleration from a measured, noisy displacement."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from analogs.errors import InputError

from ._common import (
    _AUTO_CUTOFF_FACTOR,
    _AUTO_CUTOFF_MIN_HZ,
    _DERIV_ORDER,
    _FLOOR_RATIO,
    _SAVGOL_RTOL,
    _SIGNIFICANT,
    _as_uniform,
)
from .filters import _extend, _pad_seconds
from .spectra import find_spectral_peaks, welch_spectrum

__all__ = ["displacement_derivatives", "motion_band", "significant_frequencies"]


def significant_frequencies(t: NDArray[np.float64], x: NDArray[np.float64], *,
                            derivative: int = 2) -> list[float]:
    """Frequencies [Hz] of the components of ``x`` (sampled at the uniform times ``t``, s)
    whose ``derivative``-th time derivative
    (default 2: the acceleration of a displacement) is >= 1% of the largest; empty when
    ``x`` holds nothing above its noise (a carriage at rest).

    Spectral peaks cover sines and cranks; for broadband content (sweeps, steps, transport
    moves, drifts) the upper edge of the band where ``x`` stands 20 dB above the noise
    floor and the derivative's power is at least 1e-4 of the strongest is added, so a
    sweep's top frequency is never filtered away. A peak counts only when it stands 20 dB
    above the noise floor (the median PSD): the strongest bin of pure noise is not a
    frequency of the motion.
    """
    spec = welch_spectrum(t, x)
    floor = float(np.median(spec.psd))
    peaks = find_spectral_peaks(t, x, min_frequency=2.0 / (t[-1] - t[0]),
                                min_relative_height=1e-8, max_peaks=12, refine=False)
    # Noise makes peaks too, and weighting by (2 pi f)^2 favours high-frequency noise: keep
    # only peaks 20 dB above the noise floor (median PSD: the spectrum is mostly floor).
    peaks = tuple(p for p in peaks if p.psd >= _FLOOR_RATIO * floor)
    power = (2 * np.pi * spec.frequency) ** (2 * derivative) * spec.psd
    freqs = []
    if peaks:
        amp = np.array([(2 * np.pi * p.frequency) ** derivative * p.amplitude for p in peaks])
        freqs = [p.frequency for p, a in zip(peaks, amp) if a >= _SIGNIFICANT * amp.max()]
    band = (spec.psd >= _FLOOR_RATIO * floor) & (power >= _SIGNIFICANT**2 * power.max())
    band[0] = False  # the mean is not a frequency of the motion
    if np.any(band):
        freqs.append(float(spec.frequency[np.flatnonzero(band)[-1]]))
    return freqs


def motion_band(time: ArrayLike, displacement: ArrayLike) -> float | None:
    """Highest significant frequency of a carriage motion [Hz], the ``displacement`` [m]
    sampled at ``time`` [s] (the top of :func:`significant_frequencies` of the
    displacement: its acceleration decides), or
    ``None`` when the displacement holds nothing above its noise (the carriage at rest, a
    free decay). It sets the displacement filter's cutoff (:func:`displacement_derivatives`)
    and the estimated carriage spline's knot spacing; a case file's ``[test]
    motion_band_hz`` (``slosh fit --motion-band``) gives it when the record cannot.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3001) * 0.01
    >>> round(motion_band(t, 0.005 * np.sin(2 * np.pi * 1.855 * t)), 2)
    1.86
    >>> motion_band(t, np.random.default_rng(0).normal(0, 2e-5, t.size)) is None
    True
    """
    t, x, _ = _as_uniform(time, displacement, "displacement")
    freqs = significant_frequencies(t, x)
    return max(freqs) if freqs else None


def _savgol_window(freqs: list[float], step: float, polyorder: int, n: int) -> int:
    """Largest odd window whose 2nd-derivative gain error at `freqs` is <= _SAVGOL_RTOL."""
    from scipy import signal
    best = polyorder + 1 if polyorder % 2 == 0 else polyorder + 2  # smallest odd window
    w_max = min(n - (1 - n % 2), int(2.0 / step) | 1)
    for window in range(best, w_max + 1, 2):
        c = signal.savgol_coeffs(window, polyorder, deriv=2, delta=step)
        j = np.arange(window) - window // 2
        ok = True
        for f in freqs:
            w = 2 * np.pi * f
            gain = float(np.sum(c * np.cos(w * j * step))) / (-w * w)
            if abs(gain - 1.0) > _SAVGOL_RTOL:
                ok = False
                break
        if not ok:
            break
        best = window
    return best


def displacement_derivatives(
    time: ArrayLike, displacement: ArrayLike, *,
    method: Literal["butterworth", "savgol"] = "butterworth",
    cutoff_hz: float | None = None, order: int = _DERIV_ORDER,
    window: int | None = None, polyorder: int = 8, motion_band_hz: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Smoothed carriage displacement, velocity and acceleration, without phase lag.

    Differentiating twice amplifies noise by ``(2 pi f)^2``, so the displacement is low-passed
    as hard as the signal allows: the cutoff (or window) is chosen from the spectrum so that
    every displacement component whose acceleration is at least 1% of the largest passes with
    less than 0.1% gain error, and everything above is suppressed. Both methods are
    zero-phase, and both run over the record extended at each end by a fitted line + sinusoid
    model (module docstring), so the first and last seconds are as accurate as the middle.

    Parameters
    ----------
    time : array_like
        Uniformly spaced sample times [s].
    displacement : array_like
        Measured carriage displacement [m].
    method : {"butterworth", "savgol"}, default "butterworth"
        ``"butterworth"``: zero-phase Butterworth low-pass (``sosfiltfilt``) then fourth-order
        central differences (relative error ``(2 pi f dt)^4 / 90``, 2e-6 at 1.9 Hz and 100 Hz).
        ``"savgol"``: Savitzky-Golay smoothing and differentiation (``savgol_filter`` with
        ``deriv`` 0, 1, 2).
    cutoff_hz : float, optional
        Butterworth cutoff [Hz]. Default: ``max(4 Hz, 1.6 f_max)``, with ``f_max`` the highest
        significant component (:func:`motion_band`; 0 for a carriage at rest), capped at 0.4
        times the sampling rate.
    order : int, default 8
        Butterworth order of one pass (steep, so the cutoff can sit close to the signal).
    window : int, optional
        Savitzky-Golay window in samples (odd). Default: the largest window whose
        second-derivative gain error is at most 0.1% at every significant component.
    polyorder : int, default 8
        Savitzky-Golay polynomial order (8 allows windows about 4 times longer than 4 at
        the same gain error, hence less noise).
    motion_band_hz : float, optional
        The carriage motion's highest frequency [Hz] (a case's ``[test] motion_band_hz``),
        used for ``f_max`` instead of reading it from the record.

    Returns
    -------
    x : numpy.ndarray
        Smoothed displacement [m].
    xd : numpy.ndarray
        Velocity [m/s].
    xdd : numpy.ndarray
        Acceleration [m/s^2].

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import displacement_derivatives
    >>> t = np.arange(3001) * 0.01
    >>> w = 2 * np.pi * 1.855
    >>> noisy = 0.0075 * np.sin(w * t) + np.random.default_rng(0).normal(0, 2e-5, t.size)
    >>> x, xd, xdd = displacement_derivatives(t, noisy)
    >>> bool(np.max(np.abs(xdd + w**2 * 0.0075 * np.sin(w * t))) < 0.02)   # m/s^2
    True
    """
    from scipy import signal
    t, x, step = _as_uniform(time, displacement, "displacement")
    fs = 1.0 / step
    if method == "butterworth":
        if cutoff_hz is None:  # a carriage at rest: any cutoff keeps its (constant) position
            f_max = motion_band_hz or motion_band(t, x) or 0.0
            cutoff_hz = min(max(_AUTO_CUTOFF_MIN_HZ, _AUTO_CUTOFF_FACTOR * f_max), 0.4 * fs)
        if not 0.0 < cutoff_hz < 0.5 * fs:
            raise InputError(f"expected 0 < `cutoff_hz` < Nyquist frequency {0.5 * fs:g} Hz, "
                             f"found {cutoff_hz!r}")
        sos = signal.butter(order, cutoff_hz, btype="low", output="sos", fs=fs)
        ext, n_pad = _extend(t, x, step, _pad_seconds(cutoff_hz, order))
        xs = signal.sosfiltfilt(sos, ext, padtype=None)
        d1 = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / (12.0 * step)
        d2 = np.array([-1.0, 16.0, -30.0, 16.0, -1.0]) / (12.0 * step * step)
        sl = slice(n_pad, n_pad + t.size)
        # np.correlate applies the stencil in the written order: x[i-2] ... x[i+2]
        xd = np.correlate(xs, d1, mode="same")[sl]
        xdd = np.correlate(xs, d2, mode="same")[sl]
        return xs[sl].copy(), xd, xdd
    if method == "savgol":
        if window is None:
            freqs = [motion_band_hz] if motion_band_hz else significant_frequencies(t, x)
            window = _savgol_window(freqs or [_AUTO_CUTOFF_MIN_HZ], step, polyorder, t.size)
        if window % 2 == 0 or window <= polyorder or window > t.size:
            raise InputError(f"expected an odd `window` > polyorder ({polyorder}) and <= "
                             f"{t.size} samples, found {window!r}")
        ext, n_pad = _extend(t, x, step, max(1.0, window * step))
        sl = slice(n_pad, n_pad + t.size)
        out = [signal.savgol_filter(ext, window, polyorder, deriv=d, delta=step)[sl]
               for d in (0, 1, 2)]
        return out[0], out[1], out[2]
    raise InputError(f'expected `method` "butterworth" or "savgol", found {method!r}')
