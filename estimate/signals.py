"""Signal processing for tank-test records: zero-phase filtering, spectra, derivatives.

All functions take uniformly sampled ``time`` [s] and a signal of the same length, and never
modify their inputs.

* :func:`lowpass` - zero-phase Butterworth low-pass (default 10 Hz, as the seed's workflow),
  ``scipy.signal.butter(..., output="sos")`` + ``sosfiltfilt``.
* :func:`welch_spectrum`, :func:`find_spectral_peaks`, :func:`dominant_frequency` - Welch power
  spectrum and its peaks; each peak frequency is refined by a least-squares sinusoid fit to the
  whole record (a "zoom" around the Welch bin), which resolves a drive frequency to far better
  than 0.1% on a 20-30 s record.
* :func:`check_drive_frequency` - the seed's data check: the dominant force frequency must match
  the drive frequency within 1.5%.
* :func:`displacement_derivatives` - carriage position, velocity and acceleration from a measured
  noisy displacement with no phase lag and controlled noise amplification.

End effects
-----------
Zero-phase filters distort the first and last ~0.5 s of a record when the signal is padded by
reflection (``sosfiltfilt``'s odd padding makes the second derivative jump at the end point
unless the signal's curvature happens to vanish there). Here each end is instead *extended* by a
model fitted to the last ``max(1 s, 2 periods)`` of data: a straight line plus a sinusoid and
its 2nd and 3rd harmonics, at the local frequency found by a least-squares search. The filter
runs over the extended signal and the extension is cut off again, so the ends see the same
filter as the middle of the record. Limitation: a strong component above the cutoff that the
end model does not hold (e.g. a 30 Hz tone) leaks partly into the end fit; the first and last
samples then carry an error of order 10% of that component's amplitude.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize, signal

__all__ = [
    "DriveCheck",
    "Peak",
    "Spectrum",
    "check_drive_frequency",
    "displacement_derivatives",
    "dominant_frequency",
    "find_spectral_peaks",
    "lowpass",
    "welch_spectrum",
]

_UNIFORM_RTOL = 1e-3          # same tolerance as the case loader (estimate.case.TIME_STEP_RTOL)
_MIN_SAMPLES = 16
_AUTO_CUTOFF_MIN_HZ = 4.0     # the estimation notes: 4-6 Hz cutoffs gave < 1% fixed-mass error
_AUTO_CUTOFF_FACTOR = 1.6     # order-8 Butterworth, |H|^2 at f/fc = 1/1.6: 1 - 5e-4
_DERIV_ORDER = 8
_SAVGOL_RTOL = 1e-3           # allowed 2nd-derivative gain error of the S-G filter at the signal
_SIGNIFICANT = 1e-2           # acceleration amplitude relative to the dominant component
_FLOOR_RATIO = 100.0          # a significant peak's PSD over the median PSD (noise floor)


# ----------------------------------------------------------------------------------------------
# helpers


def _as_uniform(time: ArrayLike, values: ArrayLike, name: str = "signal"
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    t = np.asarray(time, dtype=float)
    y = np.asarray(values, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"expected 1-D `time` and `{name}` of equal length, found shapes "
                         f"{t.shape} and {y.shape}")
    if t.size < _MIN_SAMPLES:
        raise ValueError(f"expected at least {_MIN_SAMPLES} samples, found {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError(f"expected finite `time` and `{name}`, found NaN or inf; load data "
                         "through `estimate.case.load_case`, which reports the rows")
    dt = np.diff(t)
    step = float(np.median(dt))
    if not step > 0 or np.any(np.abs(dt - step) > _UNIFORM_RTOL * step):
        raise ValueError("expected uniformly sampled, strictly increasing `time` (every step "
                         f"within {_UNIFORM_RTOL:g} of the median step), found steps from "
                         f"{dt.min():.6g} s to {dt.max():.6g} s")
    return t, y, step


def _sine_design(t: NDArray[np.float64], freqs: list[float]) -> NDArray[np.float64]:
    cols = [np.ones_like(t), t]
    for f in freqs:
        w = 2.0 * np.pi * f
        cols += [np.cos(w * t), np.sin(w * t)]
    return np.column_stack(cols)


def _sine_fit(t: NDArray[np.float64], y: NDArray[np.float64], f: float, harmonics: int = 1
              ) -> tuple[float, NDArray[np.float64]]:
    """Least-squares fit of offset + trend + sinusoids at f, 2f, ...; (residual SS, coeffs)."""
    a = _sine_design(t, [k * f for k in range(1, harmonics + 1)])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    r = y - a @ coef
    return float(r @ r), coef


def _sine_costs(t: NDArray[np.float64], y: NDArray[np.float64], freqs: NDArray[np.float64]
                ) -> NDArray[np.float64]:
    """Residual sum of squares of offset + trend + one sinusoid, for every frequency at once
    (batched normal equations; ``t`` should be centred on the window for conditioning)."""
    w = 2.0 * np.pi * np.asarray(freqs, float)[:, None] * t[None, :]
    ones = np.ones_like(w)
    A = np.stack([ones, np.broadcast_to(t, w.shape), np.cos(w), np.sin(w)], axis=-1)
    scale = np.sqrt(np.einsum("gnk,gnk->gk", A, A))
    A = A / scale[:, None, :]
    AtA = np.einsum("gnk,gnl->gkl", A, A)
    Aty = np.einsum("gnk,n->gk", A, y)
    coef = np.linalg.solve(AtA + 1e-12 * np.eye(4), Aty[..., None])[..., 0]
    r = y[None, :] - np.einsum("gnk,gk->gn", A, coef)
    return np.einsum("gn,gn->g", r, r)


def _refine_frequency(t: NDArray[np.float64], y: NDArray[np.float64], f0: float,
                      half_width: float, harmonics: int = 1) -> float:
    """Frequency minimising the sinusoid-fit residual within f0 +/- half_width [Hz].

    The residual has side lobes spaced 1/T apart (T the record length), so a grid finer than
    1/T locates the main lobe before a bounded scalar minimisation polishes it.
    """
    tc = t - t.mean()
    span = float(t[-1] - t[0])
    lo, hi = max(f0 - half_width, 1e-6), f0 + half_width
    grid = np.arange(lo, hi + 1e-12, 1.0 / (4.0 * span))
    if grid.size < 3:
        grid = np.linspace(lo, hi, 3)
    costs = (_sine_costs(tc, y, grid) if harmonics == 1
             else [_sine_fit(tc, y, f, harmonics)[0] for f in grid])
    i = int(np.argmin(costs))
    step = grid[1] - grid[0]
    a, b = max(grid[i] - step, lo), min(grid[i] + step, hi)
    res = optimize.minimize_scalar(lambda f: _sine_fit(tc, y, f, harmonics)[0],
                                   bounds=(a, b), method="bounded",
                                   options={"xatol": 1e-7 * max(f0, 1e-3)})
    return float(res.x) if res.fun <= costs[i] else float(grid[i])


def _end_model(t_win: NDArray[np.float64], x_win: NDArray[np.float64], t_new: NDArray[np.float64],
               fs: float) -> NDArray[np.float64]:
    """Fit line + sinusoid (with 2nd, 3rd harmonics) to one end window; evaluate at t_new."""
    t0 = t_win[-1] if t_new[0] > t_win[-1] else t_win[0]
    tw, tn = t_win - t0, t_new - t0
    span = float(t_win[-1] - t_win[0])
    f_lo, f_hi = 1.0 / span, min(0.2 * fs, 25.0)
    grid = np.geomspace(f_lo, f_hi, 160)

    def harmonics(f: float) -> int:
        return max(1, min(3, int(0.45 * fs / f)))

    # Search the fundamental with one sinusoid: with harmonics in the model, f/2 and f/3 would
    # fit a pure sine exactly as well and the search could lock onto a sub-harmonic.
    costs = _sine_costs(tw, x_win, grid)
    i = int(np.argmin(costs))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = optimize.minimize_scalar(lambda f: _sine_fit(tw, x_win, f)[0],
                                   bounds=(a, b), method="bounded")
    f = float(res.x) if res.fun <= costs[i] else float(grid[i])
    h = harmonics(f)
    _, coef = _sine_fit(tw, x_win, f, h)
    return _sine_design(tn, [k * f for k in range(1, h + 1)]) @ coef


def _extend(t: NDArray[np.float64], x: NDArray[np.float64], step: float, pad_seconds: float
            ) -> tuple[NDArray[np.float64], int]:
    """Extend both ends by a fitted model (see the module docstring); return (x_ext, n_pad)."""
    n = t.size
    fs = 1.0 / step
    n_pad = int(np.ceil(pad_seconds * fs))
    n_win = min(n, max(int(round(1.0 * fs)), 16))
    # two periods of the record's dominant frequency when that is longer than 1 s
    try:
        f_dom = dominant_frequency(t, x, min_frequency=2.0 / (t[-1] - t[0]))
        n_win = min(n, max(n_win, int(round(2.0 * fs / f_dom))))
    except ValueError:
        pass
    k = np.arange(1, n_pad + 1)
    left = _end_model(t[:n_win], x[:n_win], t[0] - k[::-1] * step, fs)
    right = _end_model(t[-n_win:], x[-n_win:], t[-1] + k * step, fs)
    return np.concatenate([left, x, right]), n_pad


# ----------------------------------------------------------------------------------------------
# filtering


def lowpass(time: ArrayLike, values: ArrayLike, *, cutoff_hz: float = 10.0, order: int = 4,
            ends: Literal["extend", "odd"] = "extend") -> NDArray[np.float64]:
    """Zero-phase Butterworth low-pass filter.

    The filter runs forwards and backwards (``sosfiltfilt``), so the result has no phase lag and
    the magnitude response is ``1 / (1 + (f / cutoff_hz)^(2 order))`` (the square of the
    single-pass Butterworth response: -6 dB at ``cutoff_hz``).

    Parameters
    ----------
    time : array_like
        Uniformly spaced sample times [s].
    values : array_like
        The signal (any unit).
    cutoff_hz : float, default 10.0
        Cutoff frequency [Hz] (the seed's workflow used 10 Hz at 100 Hz sampling).
    order : int, default 4
        Butterworth order of one pass.
    ends : {"extend", "odd"}, default "extend"
        ``"extend"`` pads each end with a fitted line + sinusoid model (see the module
        docstring); ``"odd"`` is ``sosfiltfilt``'s own odd reflection.

    Returns
    -------
    numpy.ndarray
        Filtered signal, same unit and length.

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.signals import lowpass
    >>> t = np.arange(3001) * 0.01
    >>> y = np.sin(2 * np.pi * 1.855 * t) + 0.1 * np.sin(2 * np.pi * 30 * t)
    >>> err = lowpass(t, y) - np.sin(2 * np.pi * 1.855 * t)
    >>> bool(np.max(np.abs(err[100:-100])) < 1e-5), bool(np.max(np.abs(err)) < 0.02)
    (True, True)
    """
    t, y, step = _as_uniform(time, values, "values")
    fs = 1.0 / step
    if not 0.0 < cutoff_hz < 0.5 * fs:
        raise ValueError(f"expected 0 < `cutoff_hz` < Nyquist frequency {0.5 * fs:g} Hz, "
                         f"found {cutoff_hz!r}")
    if order < 1:
        raise ValueError(f"expected `order` >= 1, found {order!r}")
    sos = signal.butter(order, cutoff_hz, btype="low", output="sos", fs=fs)
    if ends == "odd":
        return signal.sosfiltfilt(sos, y)
    if ends != "extend":
        raise ValueError(f'expected `ends` "extend" or "odd", found {ends!r}')
    ext, n_pad = _extend(t, y, step, _pad_seconds(cutoff_hz, order))
    return signal.sosfiltfilt(sos, ext, padtype=None)[n_pad:n_pad + t.size]


def _pad_seconds(cutoff_hz: float, order: int) -> float:
    # The Butterworth impulse response has decayed to ~1e-4 after about `order` periods of the
    # cutoff frequency; 1 s keeps at least a second of model beyond each end.
    return max(1.0, 1.5 * order / cutoff_hz)


# ----------------------------------------------------------------------------------------------
# spectra


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
    >>> from estimate.signals import welch_spectrum
    >>> t = np.arange(3001) * 0.01
    >>> s = welch_spectrum(t, np.sin(2 * np.pi * 2.0 * t))
    >>> float(s.frequency[np.argmax(s.psd)])            # doctest: +ELLIPSIS
    2.0...
    """
    t, y, step = _as_uniform(time, values, "values")
    seg = max(_MIN_SAMPLES, t.size // 2) if nperseg is None else int(nperseg)
    if not _MIN_SAMPLES <= seg <= t.size:
        raise ValueError(f"expected {_MIN_SAMPLES} <= `nperseg` <= {t.size} (the record length), "
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
    >>> from estimate.signals import find_spectral_peaks
    >>> t = np.arange(3001) * 0.01
    >>> y = 2.0 * np.sin(2 * np.pi * 1.855 * t) + 0.5 * np.sin(2 * np.pi * 3.71 * t)
    >>> [(round(p.frequency, 4), round(p.amplitude, 3)) for p in find_spectral_peaks(t, y)[:2]]
    [(1.855, 2.0), (3.71, 0.5)]
    """
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
            for k, i in enumerate(idx):
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
                       max_frequency: float | None = None) -> float:
    """Frequency of the strongest spectral peak [Hz], refined (see :func:`find_spectral_peaks`).

    Raises
    ------
    ValueError
        If the band holds no peak (e.g. a constant signal).

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.signals import dominant_frequency
    >>> t = np.arange(3001) * 0.01
    >>> round(dominant_frequency(t, np.cos(2 * np.pi * 2.1 * t)), 6)
    2.1
    """
    peaks = find_spectral_peaks(time, values, min_frequency=min_frequency,
                                max_frequency=max_frequency, max_peaks=1)
    if not peaks:
        band = f"{min_frequency:g} Hz to " + ("Nyquist" if max_frequency is None
                                              else f"{max_frequency:g} Hz")
        raise ValueError(f"no spectral peak found between {band}; is the signal constant?")
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

    The seed's workflow verified that the frequency seen by a spectrum analyser and the measured
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
    >>> from estimate.signals import check_drive_frequency
    >>> t = np.arange(3001) * 0.01
    >>> check_drive_frequency(t, np.sin(2 * np.pi * 1.87 * t), 1.855).passed
    True
    """
    if not drive_frequency > 0:
        raise ValueError(f"expected a positive `drive_frequency` in Hz, found {drive_frequency!r}")
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


# ----------------------------------------------------------------------------------------------
# derivatives of a measured displacement


def _significant_frequencies(t: NDArray[np.float64], x: NDArray[np.float64]) -> list[float]:
    """Frequencies of displacement components whose *acceleration* is >= 1% of the largest.

    Spectral peaks cover sines and cranks; for broadband drives (sweeps, steps) the upper
    edge of the band where the displacement stands 20 dB above the noise floor and its
    acceleration power is at least 1e-4 of the strongest is added, so a sweep's top
    frequency is never filtered away.
    """
    peaks = find_spectral_peaks(t, x, min_frequency=2.0 / (t[-1] - t[0]),
                                min_relative_height=1e-8, max_peaks=12, refine=False)
    if not peaks:
        raise ValueError("no spectral peak found in the displacement; cannot choose a filter "
                         "cutoff: pass `cutoff_hz` (butterworth) or `window` (savgol)")
    # Noise makes peaks too, and weighting by (2 pi f)^2 favours high-frequency noise: keep
    # only peaks 20 dB above the noise floor (median PSD: the spectrum is mostly floor).
    spec = welch_spectrum(t, x)
    floor = float(np.median(spec.psd))
    peaks = tuple(p for p in peaks if p.psd >= _FLOOR_RATIO * floor) or peaks[:1]
    acc = np.array([(2 * np.pi * p.frequency) ** 2 * p.amplitude for p in peaks])
    freqs = [p.frequency for p, a in zip(peaks, acc) if a >= _SIGNIFICANT * acc.max()]
    acc_psd = (2 * np.pi * spec.frequency) ** 4 * spec.psd
    band = (spec.psd >= _FLOOR_RATIO * floor) & (acc_psd >= _SIGNIFICANT**2 * acc_psd.max())
    if np.any(band):
        freqs.append(float(spec.frequency[np.flatnonzero(band)[-1]]))
    return freqs


def _savgol_window(freqs: list[float], step: float, polyorder: int, n: int) -> int:
    """Largest odd window whose 2nd-derivative gain error at `freqs` is <= _SAVGOL_RTOL."""
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
    window: int | None = None, polyorder: int = 8,
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
        significant component, capped at 0.4 times the sampling rate.
    order : int, default 8
        Butterworth order of one pass (steep, so the cutoff can sit close to the signal).
    window : int, optional
        Savitzky-Golay window in samples (odd). Default: the largest window whose
        second-derivative gain error is at most 0.1% at every significant component.
    polyorder : int, default 8
        Savitzky-Golay polynomial order (8 allows windows about 4 times longer than 4 at
        the same gain error, hence less noise).

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
    >>> from estimate.signals import displacement_derivatives
    >>> t = np.arange(3001) * 0.01
    >>> w = 2 * np.pi * 1.855
    >>> noisy = 0.0075 * np.sin(w * t) + np.random.default_rng(0).normal(0, 2e-5, t.size)
    >>> x, xd, xdd = displacement_derivatives(t, noisy)
    >>> bool(np.max(np.abs(xdd + w**2 * 0.0075 * np.sin(w * t))) < 0.02)   # m/s^2
    True
    """
    t, x, step = _as_uniform(time, displacement, "displacement")
    fs = 1.0 / step
    if method == "butterworth":
        if cutoff_hz is None:
            f_max = max(_significant_frequencies(t, x))
            cutoff_hz = min(max(_AUTO_CUTOFF_MIN_HZ, _AUTO_CUTOFF_FACTOR * f_max), 0.4 * fs)
        if not 0.0 < cutoff_hz < 0.5 * fs:
            raise ValueError(f"expected 0 < `cutoff_hz` < Nyquist frequency {0.5 * fs:g} Hz, "
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
            window = _savgol_window(_significant_frequencies(t, x), step, polyorder, t.size)
        if window % 2 == 0 or window <= polyorder or window > t.size:
            raise ValueError(f"expected an odd `window` > polyorder ({polyorder}) and <= "
                             f"{t.size} samples, found {window!r}")
        ext, n_pad = _extend(t, x, step, max(1.0, window * step))
        sl = slice(n_pad, n_pad + t.size)
        out = [signal.savgol_filter(ext, window, polyorder, deriv=d, delta=step)[sl]
               for d in (0, 1, 2)]
        return out[0], out[1], out[2]
    raise ValueError(f'expected `method` "butterworth" or "savgol", found {method!r}')
