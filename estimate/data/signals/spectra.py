"""Welch spectra, spectral peaks refined by sinusoid fits, and the drive-frequency check."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from analogs.errors import InputError

from ._common import _MIN_SAMPLES, _as_uniform, _refine_frequency, _sine_design

__all__ = ["DriveCheck", "Peak", "Spectrum", "check_drive_frequency", "dominant_frequency", "drive_frequency",
           "find_spectral_peaks", "welch_spectrum"]



@dataclass(frozen=True)
class Spectrum:
    """A one-sided Welch power spectral density.

    Attributes
    ----------
    frequency : numpy.ndarray
        [Hz].
    psd : numpy.ndarray
        Power spectral density [unit^2/Hz].
    resolution : float
        Frequency bin width [Hz].
    """

    frequency: NDArray[np.float64]
    psd: NDArray[np.float64]
    resolution: float


@dataclass(frozen=True)
class Peak:
    """A spectral peak.

    Attributes
    ----------
    frequency : float
        Refined frequency [Hz] (least-squares sinusoid fit over the whole record).
    amplitude : float
        Amplitude of the fitted sinusoid [signal unit].
    psd : float
        Welch PSD at the peak bin [unit^2/Hz].
    welch_frequency : float
        Frequency of the Welch bin [Hz], before refinement.
    """

    frequency: float
    amplitude: float
    psd: float
    welch_frequency: float


def welch_spectrum(time: ArrayLike, values: ArrayLike, *, nperseg: int | None = None) -> Spectrum:
    """Welch power spectral density (Hann window, 50% overlap, mean removed per segment).

    Parameters
    ----------
    time : array_like
        Uniformly spaced sample times [s].
    values : array_like
        The signal.
    nperseg : int, optional
        Segment length in samples; default half the record (three averaged segments), which at
        30 s and 100 Hz gives 0.067 Hz bins.

    Returns
    -------
    Spectrum

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import welch_spectrum
    >>> t = np.arange(3001) * 0.01
    >>> s = welch_spectrum(t, np.sin(2 * np.pi * 2.0 * t))
    >>> float(s.frequency[np.argmax(s.psd)])            # doctest: +ELLIPSIS
    2.0...
    """
    from scipy import signal
    t, y, step = _as_uniform(time, values, "values")
    seg = max(_MIN_SAMPLES, t.size // 2) if nperseg is None else int(nperseg)
    if not _MIN_SAMPLES <= seg <= t.size:
        raise InputError(f"expected {_MIN_SAMPLES} <= `nperseg` <= {t.size} (the record length), "
                         f"found {nperseg!r}")
    f, p = signal.welch(y, fs=1.0 / step, window="hann", nperseg=seg, detrend="constant",
                        scaling="density")
    return Spectrum(frequency=f, psd=p, resolution=float(f[1] - f[0]))


def find_spectral_peaks(time: ArrayLike, values: ArrayLike, *, min_frequency: float = 0.1,
                        max_frequency: float | None = None, min_relative_height: float = 1e-3,
                        max_peaks: int = 8, nperseg: int | None = None,
                        refine: bool = True) -> tuple[Peak, ...]:
    """Peaks of the Welch spectrum, strongest first, with refined frequency and amplitude.

    Peaks are local maxima of the PSD (``scipy.signal.find_peaks``) at least
    ``min_relative_height`` times the highest peak in the band and standing out from their
    neighbourhood by a factor 2 (prominence in log10 PSD >= 0.3). Each is refined by fitting
    offset + trend + one sinusoid to the whole record, scanning +/- 1.5 Welch bins.

    Parameters
    ----------
    time, values : array_like
        Uniformly sampled record, [s] and any unit.
    min_frequency, max_frequency : float, optional
        Band searched [Hz]; default 0.1 Hz to the Nyquist frequency.
    min_relative_height : float, default 1e-3
        Minimum PSD relative to the highest peak in the band.
    max_peaks : int, default 8
        At most this many peaks are returned.
    nperseg : int, optional
        Welch segment length (see :func:`welch_spectrum`).
    refine : bool, default True
        Refine frequencies and amplitudes by sinusoid fits to the whole record; when False,
        frequencies are the Welch bins and amplitudes come from the PSD (Hann window,
        equivalent noise bandwidth 1.5 bins): fast, for thresholds.

    Returns
    -------
    tuple of Peak
        Sorted by decreasing PSD; empty when the band holds no peak.

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import find_spectral_peaks
    >>> t = np.arange(3001) * 0.01
    >>> y = 2.0 * np.sin(2 * np.pi * 1.855 * t) + 0.5 * np.sin(2 * np.pi * 3.71 * t)
    >>> [(round(p.frequency, 4), round(p.amplitude, 3)) for p in find_spectral_peaks(t, y)[:2]]
    [(1.855, 2.0), (3.71, 0.5)]
    """
    from scipy import signal
    t, y, _ = _as_uniform(time, values, "values")
    spec = welch_spectrum(t, y, nperseg=nperseg)
    f, p = spec.frequency, spec.psd
    hi = f[-1] if max_frequency is None else max_frequency
    band = np.flatnonzero((f >= min_frequency) & (f <= hi))
    if band.size < 3 or not np.any(p[band] > 0):
        return ()
    logp = np.log10(np.maximum(p, np.max(p) * 1e-20 + 1e-300))
    idx, _ = signal.find_peaks(logp, prominence=0.3)
    idx = idx[(f[idx] >= min_frequency) & (f[idx] <= hi)]
    if idx.size == 0:
        return ()
    idx = idx[p[idx] >= min_relative_height * p[idx].max()]
    idx = idx[np.argsort(p[idx])[::-1]][:max_peaks]
    if not refine:
        return tuple(Peak(frequency=float(f[i]), amplitude=float(np.sqrt(3.0 * p[i] * spec.resolution)),
                          psd=float(p[i]), welch_frequency=float(f[i])) for i in idx)
    tc = t - t.mean()
    freqs = [_refine_frequency(t, y, float(f[i]), 1.5 * spec.resolution) for i in idx]
    if len(freqs) > 1:
        # Back-fitting: refine each frequency with the other fitted sinusoids removed, so that
        # leakage from a strong neighbour does not bias a weaker peak.
        for _ in range(2):
            coef, *_ = np.linalg.lstsq(_sine_design(tc, freqs), y, rcond=None)
            for k in range(len(idx)):
                a = _sine_design(tc, freqs)
                mask = np.ones(coef.size, dtype=bool)
                mask[[2 + 2 * k, 3 + 2 * k]] = False
                others = a[:, mask] @ coef[mask]
                freqs[k] = _refine_frequency(t, y - others, freqs[k], 0.5 * spec.resolution)
    coef, *_ = np.linalg.lstsq(_sine_design(tc, freqs), y, rcond=None)
    peaks = [Peak(frequency=fr, amplitude=float(np.hypot(coef[2 + 2 * k], coef[3 + 2 * k])),
                  psd=float(p[i]), welch_frequency=float(f[i]))
             for k, (fr, i) in enumerate(zip(freqs, idx))]
    return tuple(peaks)


def dominant_frequency(time: ArrayLike, values: ArrayLike, *, min_frequency: float = 0.1,
                       max_frequency: float | None = None, refine: bool = True) -> float:
    """Frequency of the strongest spectral peak [Hz], refined by a sinusoid fit unless
    ``refine`` is false (then to the spectrum's resolution; see :func:`find_spectral_peaks`).

    Raises
    ------
    ValueError
        If the band holds no peak (e.g. a constant signal).

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import dominant_frequency
    >>> t = np.arange(3001) * 0.01
    >>> round(dominant_frequency(t, np.cos(2 * np.pi * 2.1 * t)), 6)
    2.1
    """
    peaks = find_spectral_peaks(time, values, min_frequency=min_frequency,
                                max_frequency=max_frequency, max_peaks=1, refine=refine)
    if not peaks:
        band = f"{min_frequency:g} Hz to " + ("Nyquist" if max_frequency is None
                                              else f"{max_frequency:g} Hz")
        raise InputError(f"no spectral peak found between {band}; is the signal constant?")
    return peaks[0].frequency


@dataclass(frozen=True)
class DriveCheck:
    """Result of :func:`check_drive_frequency`.

    Attributes
    ----------
    passed : bool
        ``relative_error <= tolerance``.
    drive_frequency : float
        The expected drive frequency [Hz].
    measured_frequency : float
        Dominant frequency of the force [Hz].
    relative_error : float
        ``|measured - drive| / drive`` [-].
    tolerance : float
        Allowed relative error [-].
    message : str
        One line for a report.
    """

    passed: bool
    drive_frequency: float
    measured_frequency: float
    relative_error: float
    tolerance: float
    message: str

    def __bool__(self) -> bool:
        return self.passed


def check_drive_frequency(time: ArrayLike, force: ArrayLike, drive_frequency: float, *,
                          tolerance: float = 0.015, min_frequency: float = 0.1,
                          max_frequency: float | None = None) -> DriveCheck:
    """Check that the dominant force frequency matches the drive frequency.

    Classical slosh tests verify that the frequency seen by a spectrum analyser and the measured
    test frequency agree within about 1.5%.

    Parameters
    ----------
    time : array_like
        Uniform sample times [s].
    force : array_like
        Measured force [N].
    drive_frequency : float
        Expected drive frequency [Hz] (e.g. ``[rig.crank] frequency``, or the dominant
        frequency of the measured displacement).
    tolerance : float, default 0.015
        Allowed relative difference.
    min_frequency, max_frequency : float, optional
        Band searched for the force peak [Hz].

    Returns
    -------
    DriveCheck
        Truthy when the check passed; carries the numbers and a message.

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import check_drive_frequency
    >>> t = np.arange(3001) * 0.01
    >>> check_drive_frequency(t, np.sin(2 * np.pi * 1.87 * t), 1.855).passed
    True
    """
    if not drive_frequency > 0:
        raise InputError(f"expected a positive `drive_frequency` in Hz, found {drive_frequency!r}")
    measured = dominant_frequency(time, force, min_frequency=min_frequency,
                                  max_frequency=max_frequency)
    err = abs(measured - drive_frequency) / drive_frequency
    passed = err <= tolerance
    verdict = "matches" if passed else "does NOT match"
    message = (f"dominant force frequency {measured:.4f} Hz {verdict} the drive frequency "
               f"{drive_frequency:.4f} Hz: difference {100 * err:.2f}% "
               f"(tolerance {100 * tolerance:.2f}%)")
    if not passed:
        message += ("; check the drive frequency in the case file, or whether a slosh resonance "
                    "or a motor tone dominates the force")
    return DriveCheck(passed=passed, drive_frequency=float(drive_frequency),
                      measured_frequency=measured, relative_error=err, tolerance=tolerance,
                      message=message)


def drive_frequency(time: ArrayLike, acceleration: ArrayLike) -> tuple[float | None, bool]:
    """Dominant frequency of a carriage ``acceleration`` sampled at ``time`` (s) [Hz], and
    whether the drive sweeps
    (less than 70 % of the power within +/-10 % of the dominant frequency); ``(None, False)``
    for a signal without power.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3001) * 0.01
    >>> f, sweep = drive_frequency(t, np.sin(2 * np.pi * 1.855 * t))
    >>> round(f, 3), sweep
    (1.855, False)
    """
    t = np.asarray(time, float)
    acc = np.asarray(acceleration, float)
    spec = welch_spectrum(t, acc)
    p = spec.psd
    if not np.any(p > 0):
        return None, False
    main = spec.frequency[int(np.argmax(p))]
    near = np.abs(spec.frequency - main) <= 0.1 * main + 2 * spec.resolution
    sweep = float(p[near].sum() / p.sum()) < 0.7
    peaks = find_spectral_peaks(t, acc, min_frequency=0.5 * main, max_frequency=1.5 * main, max_peaks=1)
    return (peaks[0].frequency if peaks else float(main)), sweep
