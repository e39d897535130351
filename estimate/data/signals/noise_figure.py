"""One noise figure per recorded channel, read where the signal lives.

A force transducer low-passes internally and quantises: above its filter the spectrum holds
little but quantisation, while the noise inside the band of the mechanics is several times
larger and coloured (1/f, structural lines). The noise figure of a channel is therefore read
inside the band, in one of two ways:

* from **quiet segments** of the record (:func:`quiet_segments`): the rest before the drive
  (carriage and liquid at rest) and a settled end (carriage at rest, no slosh left). Each
  segment loses its offset and linear drift (a transducer's offset is not noise); what is left
  is the noise as the channel records it.
* else from the **residual** of a fit (:func:`residual_noise`): the residual's spectrum,
  averaged over time segments by their median (a residual confined to part of the record, such
  as a sweep passing a missed mode or a transport move, does not count) and with its spectral
  peaks removed (a residual at the drive frequency, its harmonics or a missed mode does not
  count): what remains is the broadband, stationary part, the noise.

Either way the noise's colour is described by an autoregressive model
(:attr:`NoiseFigure.ar`, Yule-Walker, order by AIC) and its standard deviation by
:attr:`NoiseFigure.std`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ._common import _as_uniform

__all__ = ["NoiseFigure", "quiet_segments", "segment_noise", "residual_noise", "quiet_wander"]

#: Shortest quiet segment used [s] (and at least QUIET_MIN_SAMPLES samples).
QUIET_MIN_SECONDS = 0.5
QUIET_MIN_SAMPLES = 64
#: The quarters of a quiet segment have variances within this ratio (noise is stationary; a
#: force that starts to follow the motion is not).
QUIET_VARIANCE_RATIO = 4.0
#: ... and the half nearest the motion is not noisier than the other by an F-test at this
#: level (a force that starts to follow a smooth start grows).
QUIET_F_LEVEL = 0.001
#: A settled end's variance is at most this many times that of the rest before the drive.
SETTLED_VARIANCE_RATIO = 2.0
#: The carriage is at rest while its displacement stays within this many displacement noise
#: standard deviations of its value at the segment's end of the record.
REST_SIGMAS = 6.0
#: A quiet segment stops this long before the displacement leaves rest (at least), and this
#: fraction of the rest: the force sees a smooth start before the displacement does.
REST_MARGIN_SECONDS = 0.25
REST_MARGIN_FRACTION = 0.4
#: A segment is not quiet when one sinusoid (in the band of the mechanics, two cycles at
#: least) explains more than this many times the share of its variance that the best
#: sinusoid takes of pure noise...
SINE_SHARE_FACTOR = 4.0
#: ... or than this share (1/f noise puts a third of a short segment's variance in one low
#: bin; a sloshing liquid puts nearly all of it at its frequency).
SINE_SHARE_MAX = 0.5
#: Spectral bins this many times above the running median of their neighbours are peaks
#: (model error at one frequency), not noise.
PEAK_FACTOR = 2.5
#: Half width of the running median a bin is compared with [Hz] (at least 6 bins).
PEAK_WINDOW_HZ = 1.5
#: Residual segments whose variance about their own straight line is at most this many
#: times a quiet figure's are noise-like: their wander joins that figure
#: (:func:`quiet_wander`).
WANDER_SEGMENT_FACTOR = 2.0
#: Largest autoregressive order of a noise model.
MAX_AR_ORDER = 12


@dataclass(frozen=True)
class NoiseFigure:
    """The measurement noise of one recorded channel inside the band of the signal.

    Attributes
    ----------
    std : float
        Standard deviation of the noise as the channel records it (the channel's unit: N,
        N m, m).
    source : str
        ``"quiet"`` (quiet segments of the record), ``"residual"`` (a fit's residual without
        its peaks and bursts) or ``"spectrum"`` (the white level above the signal band: a
        provisional figure, used only to weigh a first fit).
    ar : tuple of float
        Coefficients ``a_1..a_p`` of the noise's autoregressive model,
        ``n_t = a_1 n_{t-1} + ... + a_p n_{t-p} + e_t`` (empty: white).
    seconds : float
        Length of data the figure was read from [s].
    detail : str
        Where it was read, in words (``"rest before the drive, 0-0.83 s"``).
    """

    std: float
    source: str
    ar: tuple[float, ...] = ()
    seconds: float = math.nan
    detail: str = ""

    def describe(self, unit: str) -> str:
        """``"0.0119 N (rest before the drive, 0-0.83 s; coloured, AR(4))"``: the figure in
        ``unit`` (its SI unit, ``"N"``), where it comes from and its colour."""
        colour = f"coloured, AR({len(self.ar)})" if self.ar else "white"
        return f"{self.std:.3g} {unit} ({self.detail}; {colour})"

    def psd(self, frequency: ArrayLike, fs: float) -> np.ndarray:
        """One-sided power spectral density of the noise model at ``frequency`` [Hz] for the
        sampling rate ``fs`` [Hz] (unit^2/Hz); it integrates to ``std**2`` over 0..fs/2."""
        f = np.asarray(frequency, float)
        grid = np.linspace(0.0, fs / 2, 2049)
        shape = _ar_shape(self.ar, grid, fs)
        total = float(np.trapezoid(shape, grid))
        return self.std**2 * _ar_shape(self.ar, f, fs) / total

    def to_dict(self) -> dict:
        return {"std": self.std, "source": self.source, "ar": list(self.ar),
                "seconds": self.seconds, "detail": self.detail}


def _ar_shape(ar: tuple[float, ...], f: np.ndarray, fs: float) -> np.ndarray:
    if not ar:
        return np.ones_like(f)
    z = np.exp(-2j * np.pi * np.outer(f / fs, np.arange(1, len(ar) + 1)))
    return 1.0 / np.abs(1.0 - z @ np.asarray(ar)) ** 2


def _rest_run(x: np.ndarray, tol: float, from_end: bool) -> int:
    """Number of samples from the start (or the end) during which ``x`` stays within ``tol``
    of its value there (median of the first 10 samples)."""
    y = x[::-1] if from_end else x
    ref = float(np.median(y[:10]))
    away = np.flatnonzero(np.abs(y - ref) > tol)
    return int(away[0]) if away.size else y.size


def _sine_share(t: np.ndarray, y: np.ndarray, top_hz: float, cycles: float = 2.0
                ) -> tuple[float, float]:
    """Share of ``y``'s (detrended) variance the best single sinusoid between
    ``cycles / T`` and ``top_hz`` explains, and the share the best one takes of white noise
    of that length."""
    from scipy import signal
    n = y.size
    fs = 1.0 / float(t[1] - t[0])
    f, p = signal.periodogram(y, fs=fs, detrend="linear", scaling="spectrum")
    band = (f >= cycles / (t[-1] - t[0])) & (f <= top_hz)
    if not np.any(band) or p.sum() <= 0:
        return 0.0, 1.0
    share = float(2 * p[band].max() / p.sum()) if p.sum() > 0 else 0.0  # cos and sin parts
    m = max(int(np.count_nonzero(band)), 1)
    expected = 2.0 * (math.log(m) + 0.5772) / max(n / 2, 1)  # max of m exponentials / sum
    return min(share, 1.0), min(expected, 1.0)


def quiet_segments(time: ArrayLike, displacement: ArrayLike | None, values: ArrayLike, *,
                   displacement_noise: float, band_hz: float, starts_at_rest: bool | None = None
                   ) -> tuple[tuple[int, int], ...]:
    """Index ranges ``(start, stop)`` of the quiet segments of a record (``values`` and the
    ``displacement`` sampled at ``time``, s): the rest before the drive and the settled
    end.

    The carriage is at rest while the ``displacement`` [m] stays within
    :data:`REST_SIGMAS` ``displacement_noise`` [m] of its first (last) value; a segment stops
    a margin before the motion shows in the displacement (the force sees a smooth start
    first). A segment is quiet when no sinusoid below ``band_hz`` [Hz] (the mechanics) stands
    out of ``values`` and its variance is steady (:func:`_quiet`): a liquid still sloshing,
    released at the first sample, or a force already following the motion makes it not
    quiet. ``starts_at_rest=False`` (the case says the record does not start at rest)
    leaves out the rest before the drive. A rest before the drive that is not quiet is
    shortened by a quarter from the motion's side until it is; a settled end must be quiet
    over its whole rest (a liquid still ringing looks steady on a short window) and no
    noisier than the rest before the drive (:data:`SETTLED_VARIANCE_RATIO`). Segments
    shorter than :data:`QUIET_MIN_SECONDS` do not count. Without a displacement (a crank
    drive) there is none.
    """
    if displacement is None:
        return ()
    t, y, step = _as_uniform(time, values, "values")
    x = np.asarray(displacement, float)
    tol = REST_SIGMAS * max(displacement_noise, 1e-12)
    n_min = max(QUIET_MIN_SAMPLES, int(math.ceil(QUIET_MIN_SECONDS / step)))
    out = []
    for from_end in (False, True):
        if not from_end and starts_at_rest is False:
            continue
        run = _rest_run(x, tol, from_end)
        if run >= t.size - 1:
            continue  # never moves: not a drive record (a free decay, or no motion at all)
        keep = run - max(int(round(REST_MARGIN_SECONDS / step)),
                         int(round(REST_MARGIN_FRACTION * run)))
        if keep < n_min:
            continue
        if from_end:
            # a settled end is settled over the whole rest: a liquid still ringing looks
            # steady on a short window, and it must not be noisier than the rest before
            seg = (t.size - keep, t.size)
            piece = y[seg[0]:seg[1]]
            if _quiet(t[seg[0]:seg[1]], piece[::-1], band_hz, cycles=1.0) and (
                    not out or _variance(piece) <= SETTLED_VARIANCE_RATIO * _variance(
                        y[out[0][0]:out[0][1]])):
                out.append(seg)
            continue
        while keep >= n_min:
            seg = (0, keep)
            if _quiet(t[:keep], y[:keep], band_hz):
                out.append(seg)
                break
            keep = int(0.75 * keep)  # the part nearest the motion is the likeliest to move
    return tuple(out)


def _variance(y: np.ndarray) -> float:
    d = _detrended(y)
    return float(d @ d) / max(d.size - 2, 1)


def _quiet(t: np.ndarray, y: np.ndarray, band_hz: float, cycles: float = 2.0) -> bool:
    """Whether ``y`` looks like stationary noise: its quarters (about the segment's straight
    line) have variances within :data:`QUIET_VARIANCE_RATIO` of each other, its second half
    is not noisier than its first (:data:`QUIET_F_LEVEL`), and no sinusoid below ``band_hz``
    stands out (:data:`SINE_SHARE_FACTOR`). The rest before the drive is tested as is, the
    settled end reversed (its part nearest the motion first)."""
    from scipy import stats
    d = _detrended(y)  # quarters and halves about the segment's line, not their own
    v = np.array([float(q @ q) / q.size for q in np.array_split(d, 4)])
    if v.min() <= 0 or v.max() > QUIET_VARIANCE_RATIO * v.min():
        return False
    first, second = np.array_split(d, 2)
    ratio = (float(second @ second) / second.size) / (float(first @ first) / first.size)
    if ratio > stats.f.ppf(1.0 - QUIET_F_LEVEL, second.size - 1, first.size - 1):
        return False  # the part nearest the motion is noisier: the force follows it
    share, expected = _sine_share(t, y, band_hz, cycles)
    return share <= max(SINE_SHARE_FACTOR * expected, SINE_SHARE_MAX)


def _detrended(y: np.ndarray) -> np.ndarray:
    from scipy import signal
    return signal.detrend(y, type="linear")


def _autocovariance(pieces: list[np.ndarray], lags: int) -> np.ndarray:
    """Pooled biased autocovariance of zero-mean pieces at lags 0..lags."""
    acov = np.zeros(lags + 1)
    count = 0
    for p in pieces:
        n = p.size
        for k in range(min(lags, n - 1) + 1):
            acov[k] += float(p[: n - k] @ p[k:])
        count += n
    return acov / max(count, 1)


def _yule_walker(acov: np.ndarray, n: int) -> tuple[float, ...]:
    """AR coefficients from an autocovariance, the order chosen by AIC (``n`` samples)."""
    from scipy import linalg
    if acov[0] <= 0:
        return ()
    best, best_aic = (), n * math.log(acov[0])
    for p in range(1, min(MAX_AR_ORDER, acov.size - 1, n // 10) + 1):
        a = linalg.solve_toeplitz(acov[:p], acov[1:p + 1])
        s2 = float(acov[0] - a @ acov[1:p + 1])
        if s2 <= 0:
            break
        aic = n * math.log(s2) + 2 * p
        if aic < best_aic - 1e-9:
            best, best_aic = tuple(float(v) for v in a), aic
    return best


def segment_noise(time: ArrayLike, values: ArrayLike, segments: tuple[tuple[int, int], ...],
                  *, detail: str = "") -> NoiseFigure:
    """The noise figure of ``values`` (sampled at ``time``, s) from quiet ``segments`` (index
    ranges): the standard deviation about each segment's own straight line (offset and
    drift are not noise; two degrees of freedom per segment), and the AR model of the
    pooled segments; ``detail`` says where they are, for reports."""
    t, y, step = _as_uniform(time, values, "values")
    pieces = [_detrended(y[a:b]) for a, b in segments]
    n = sum(p.size for p in pieces)
    dof = n - 2 * len(pieces)
    std = math.sqrt(sum(float(p @ p) for p in pieces) / max(dof, 1))
    ar = _yule_walker(_autocovariance(pieces, MAX_AR_ORDER), n)
    if not detail:
        detail = "quiet segments " + ", ".join(f"{t[a]:.3g}-{t[b - 1]:.3g} s" for a, b in segments)
    return NoiseFigure(std, "quiet", ar, n * step, detail)


def _expected_median(k: int) -> float:
    """Expected sample median of ``k`` independent unit exponentials (the periodogram bins of
    ``k`` segments of Gaussian noise, in units of their mean)."""
    def order(r: int) -> float:  # E of the r-th smallest of k: sum_{j=k-r+1}^{k} 1/j
        return float(np.sum(1.0 / np.arange(k - r + 1, k + 1)))
    if k % 2:
        return order((k + 1) // 2)
    return 0.5 * (order(k // 2) + order(k // 2 + 1))


def _segments(r: np.ndarray, weights, samples: float) -> tuple[np.ndarray, list[int], int]:
    """``(keep, starts, nper)``: the samples with ``weights`` > 0, and the starts of the
    non-overlapping segments of ``nper`` (about ``samples``; at least 8 segments when the
    kept samples allow, at least 32 samples) lying wholly inside the kept samples."""
    keep = np.ones(r.size, bool) if weights is None else np.asarray(weights, float) > 0
    nper = max(min(int(round(samples)), int(np.count_nonzero(keep)) // 8), 32)
    starts = []
    i = 0
    while i + nper <= r.size:
        gaps = np.flatnonzero(~keep[i:i + nper])
        if gaps.size == 0:
            starts.append(i)
            i += nper
        else:
            i += int(gaps[-1]) + 1
    return keep, starts, nper


def _wander(t: np.ndarray, r: np.ndarray, keep: np.ndarray, starts: list[int], nper: int
            ) -> tuple[np.ndarray, np.ndarray]:
    """Per segment (``nper`` samples from each of ``starts``), once the straight line
    through the ``keep`` samples of ``r`` is removed: the variance the segment's own
    straight line holds (the wander below the segments' resolution, less an offset and a
    drift over the record) and the variance about it."""
    from scipy import signal
    tc = t - float(np.mean(t[keep]))
    A = np.column_stack([np.ones(int(np.count_nonzero(keep))), tc[keep]])
    c = np.linalg.lstsq(A, r[keep], rcond=None)[0]
    rg = r - c[0] - c[1] * tc
    segs = np.array([rg[s:s + nper] for s in starts])
    about = np.mean(signal.detrend(segs, axis=1, type="linear") ** 2, axis=1)
    return np.mean(segs**2, axis=1) - about, about


def quiet_wander(time: ArrayLike, residual: ArrayLike, weights: ArrayLike | None,
                 figure: NoiseFigure, *, segment_seconds: float = 2.0) -> NoiseFigure:
    """A quiet-segment ``figure`` with the wander of a fit's ``residual`` below the
    segments added: a rest of a second or two cannot show a transducer's 1/f noise
    wandering over a minute (60 s records with a 1.3 s rest left a correct model 1.15-1.25
    x that figure). The wander is the mean variance the straight lines of the residual's
    ``segment_seconds`` segments hold once the record's straight line is removed
    (:func:`residual_noise`), over the noise-like segments only: those whose variance about
    their own line is at most :data:`WANDER_SEGMENT_FACTOR` times the figure's (a
    misfit's burst, such as a missed mode after a transport move, does not count)."""
    t, r, step = _as_uniform(time, residual, "residual")
    keep, starts, nper = _segments(r, weights, segment_seconds / step)
    if len(starts) < 3 or not figure.std > 0:
        return figure
    wander, about = _wander(t, r, keep, starts, nper)
    calm = about <= WANDER_SEGMENT_FACTOR * figure.std**2
    if not np.any(calm):
        return figure
    extra = max(float(np.mean(wander[calm])), 0.0)
    return replace(figure, std=math.sqrt(figure.std**2 + extra),
                   detail=(figure.detail or "quiet segments")
                   + f"; with the fit residual's wander below {nper * step:.3g} s")


def residual_noise(time: ArrayLike, residual: ArrayLike, weights: ArrayLike | None = None, *,
                   segment_seconds: float = 2.0, peaks_below_hz: float | None = None
                   ) -> NoiseFigure:
    """The noise figure of a fit's ``residual`` at the sample times ``time`` (s; samples with
    ``weights`` > 0 only): its stationary, broadband part.

    The residual is cut into non-overlapping segments of about ``segment_seconds`` [s]
    (at least 8 segments when the record allows) lying wholly inside the fitted samples; the
    spectrum of each segment (Hann window, linear detrend) is taken and, per frequency, the
    median over the segments (corrected for the median's bias: a burst confined to a few
    segments does not count). Bins standing :data:`PEAK_FACTOR` times above the running
    median of their neighbours (:data:`PEAK_WINDOW_HZ` either side), and the two bins either
    side, are replaced by it (a residual at one frequency does not count), below
    ``peaks_below_hz`` [Hz] when given (the band of the mechanics: above it a line is the
    transducer's, noise like the rest). To that spectrum's lowest bin is added what the
    segments' own straight lines take from the residual once the record's straight line is
    removed (their mean): a transducer's 1/f noise wanders below the segments' resolution
    (on 20 s records through a transducer model half the residual's variance lay below
    1 Hz, and a figure without it put a correct model's residual at 1.15-1.37 times the
    noise), while an offset and a drift over the record (the ``sensor_offset`` family's
    effect) stay out. The figure is the square root of the integral of what remains, and
    its AR model is fitted to the autocovariance that spectrum implies.
    """
    from scipy import signal
    from scipy.ndimage import median_filter
    t, r, step = _as_uniform(time, residual, "residual")
    fs = 1.0 / step
    keep, starts, nper = _segments(r, weights, segment_seconds * fs)
    n_kept = int(np.count_nonzero(keep))
    if len(starts) < 3:
        std = float(np.std(r[keep])) if n_kept else math.nan
        return NoiseFigure(std, "residual", (), n_kept * step,
                           "fit residual (too short for its spectrum: its standard deviation)")
    window = signal.get_window("hann", nper)
    segs = np.array([signal.detrend(r[s:s + nper], type="linear") for s in starts])
    spec = np.abs(np.fft.rfft(segs * window, axis=1)) ** 2
    scale = 2.0 / (fs * float(window @ window))
    psd = np.median(spec, axis=0) * scale / _expected_median(len(starts))
    psd[0] *= 0.5
    if nper % 2 == 0:
        psd[-1] *= 0.5
    df = fs / nper
    width = max(int(round(PEAK_WINDOW_HZ / df)), 6)
    smooth = median_filter(psd, size=2 * width + 1, mode="nearest")
    # a peak and its window's leakage (two bins either side) is model error
    peak = np.convolve(psd > PEAK_FACTOR * smooth, np.ones(5), mode="same") > 0
    if peaks_below_hz is not None:
        peak &= np.arange(psd.size) * (fs / nper) < peaks_below_hz
    ordinary = ~peak
    # the running median of exponential-like bins sits below their mean: rescale it by the
    # bins that are not peaks, so a flat spectrum keeps its level
    level = float(np.sum(psd[ordinary])) / max(float(np.sum(smooth[ordinary])), 1e-300)
    clean = np.where(ordinary, psd, smooth * level)
    clean[0] += float(np.mean(_wander(t, r, keep, starts, nper)[0])) / df
    variance = float(np.sum(clean) * df)
    two_sided = np.r_[clean, clean[-2:0:-1] if nper % 2 == 0 else clean[-1:0:-1]] * fs / 2
    acov = np.fft.ifft(two_sided).real[: MAX_AR_ORDER + 1]
    ar = _yule_walker(acov, n_kept)
    secs = len(starts) * nper * step
    return NoiseFigure(math.sqrt(variance), "residual", ar, secs,
                       f"fit residual without its spectral peaks and bursts, "
                       f"{len(starts)} segments of {nper * step:.3g} s")
