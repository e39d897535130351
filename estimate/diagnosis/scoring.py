"""How a diagnosis scores a fit: the residual over the measurement noise (one place:
:func:`noise_figure`), held-out blocks, the held-out residual and chi-square, the BIC,
whether an estimate is distinct from zero, the rows of a case in the fit's residual vector,
and whether the current fit is a poor place to start a candidate."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..data.signals import welch_spectrum
from ..fitting.noise_figures import MODEL_ERROR_MARGIN
from ..fitting.result import FitResult

__all__ = ["ResidualOverNoise", "noise_figure", "noise_floor", "within_noise", "holdout_weights",
           "heldout", "bic", "distinct", "case_rows", "far_from_noise", "poor_start",
           "NOISE_MARGIN", "MIN_SCORE", "POOR_START_RATIO", "HOLDOUT_BLOCKS", "HELD_OUT_BLOCKS"]

#: A residual this many times the measurement noise is within the noise: the fit's own
#: margin, above which its intervals take the model error.
NOISE_MARGIN = MODEL_ERROR_MARGIN
#: Score statistic a screened term (or a profiled sensor delay) needs to be fitted (5
#: standard deviations for one new parameter: a dozen terms are screened each round).
MIN_SCORE = 25.0
#: The diagnosis cuts each record into this many blocks of equal length ...
HOLDOUT_BLOCKS = 10
#: ... and leaves these blocks (0-based: 3 of 10, spread over the record) out of every fit
#: but the final one; the candidates are scored on them.
HELD_OUT_BLOCKS = (1, 4, 7)


@dataclass(frozen=True)
class ResidualOverNoise:
    """A fit's residual against the measurement noise, as the report prints it:
    ``ratio == residual / noise`` exactly, both in ``unit``; ``how`` says in one clause how
    the two numbers were read."""

    residual: float
    noise: float
    unit: str
    how: str

    @property
    def ratio(self) -> float:
        return self.residual / max(self.noise, 1e-300)

    @property
    def within(self) -> bool:
        """The residual is within :data:`NOISE_MARGIN` of the noise."""
        return within_noise(self.ratio)

    def text(self) -> str:
        """``"residual 0.0755 N against noise 0.0739 N: 1.02 x the noise (...)"``."""
        return (f"residual {self.residual:.3g} {self.unit} against noise {self.noise:.3g} "
                f"{self.unit}: {self.ratio:.2f} x the noise ({self.how})")


def within_noise(ratio: float) -> bool:
    """A residual ``ratio`` times the noise is within :data:`NOISE_MARGIN` of it."""
    return ratio <= NOISE_MARGIN


def noise_floor(time: np.ndarray, force: np.ndarray, cutoff_hz: float | None) -> float:
    """RMS of white measurement noise inside the fitted band (N), from the raw force's PSD
    between 1.5 and 4 times the cutoff (median, so tones do not count)."""
    fs = 1.0 / float(np.median(np.diff(time)))
    cut = cutoff_hz if cutoff_hz is not None else 0.2 * fs
    spec = welch_spectrum(time, force)
    band = (spec.frequency >= 1.5 * cut) & (spec.frequency <= min(4.0 * cut, 0.45 * fs))
    if not np.any(band):
        band = spec.frequency >= 0.6 * (fs / 2)
    level = float(np.median(spec.psd[band]))
    return math.sqrt(level * min(cut, fs / 2))


def noise_figure(result: FitResult, case: int = 0) -> ResidualOverNoise:
    """The residual of ``result`` over the measurement noise: the one place the diagnosis
    reads it (verdict, report, poor starts, the floor a candidate reaches), from the fit's
    own noise figure (:attr:`~estimate.fitting.result.FitResult.noise_figures`, the one
    the fit report prints): the RMS residual on the fitted samples over the figure. For
    several channels both numbers are in channel scales (RMS over the channels). A fit
    without figures falls back to the white noise of the raw force inside the fitted
    band."""
    problem = result.problem
    exp = problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    keep = result.weights[case] > 0 if result.weights else np.ones(t.size, bool)
    figures = result.noise_figures[case] if result.noise_figures else {}
    if result.channels and len(result.channels[case]) > 1:
        scales = result.channel_scales[case]
        r = result.scaled_residuals(case)[keep]
        noise = [figures[c].std / scales[c] if c in figures else
                 noise_floor(t, np.asarray(exp.case.channels[c], float), problem.force_cutoff_hz)
                 / scales[c] for c in result.channels[case]]
        return ResidualOverNoise(float(np.sqrt(np.mean(r**2))),
                                 float(np.sqrt(np.mean(np.square(noise)))), "(channel scales)",
                                 "RMS over all channels on the fitted samples; each channel's "
                                 "noise figure")
    r = np.asarray(result.residuals[case])[keep]
    rms = float(np.sqrt(np.mean(r**2)))
    figure = next(iter(figures.values()), None)
    if figure is not None and math.isfinite(figure.std) and figure.std > 0:
        return ResidualOverNoise(rms, float(figure.std), "N",
                                 f"RMS on the fitted samples; noise figure {figure.describe('N')}")
    return ResidualOverNoise(rms, noise_floor(t, exp.case.force, problem.force_cutoff_hz), "N",
                             "RMS on the fitted samples; white noise of the raw force inside "
                             "the fitted band, read above it")


def distinct(res: FitResult, name: str, factor: float = 3.0) -> bool:
    """``name`` is estimated and ``factor`` standard errors of the noise
    (:attr:`FitResult.noise_stderr`: a candidate that leaves another effect unexplained is
    not less distinct for it) or more away from zero."""
    i = res.names.index(name) if name in res.names else None
    return i is not None and abs(res.values[i]) > factor * res.noise_stderr[i]


def case_rows(res: FitResult, case: int) -> slice:
    """The rows of case ``case``'s measured-channel residuals (channel-major for several
    channels) in the fit's residual vector and :attr:`FitResult.sensitivity` (each case:
    its channel residuals, then its displacement residuals when the carriage motion is
    estimated)."""
    start = 0
    for k in range(case):
        start += int(np.size(res.residuals[k]))
        if res.displacement_residuals and res.displacement_residuals[k] is not None:
            start += int(np.size(res.displacement_residuals[k]))
    return slice(start, start + int(np.size(res.residuals[case])))


def holdout_weights(n: int, *, blocks: int = HOLDOUT_BLOCKS,
                    held: Sequence[int] = HELD_OUT_BLOCKS) -> np.ndarray:
    """Weights leaving out interleaved blocks (default :data:`HELD_OUT_BLOCKS`, 3 of
    :data:`HOLDOUT_BLOCKS`) of an ``n``-sample record."""
    w = np.ones(n)
    edges = np.linspace(0, n, blocks + 1).astype(int)
    for b in held:
        w[edges[b]:edges[b + 1]] = 0.0
    return w


def heldout(res: FitResult) -> tuple[float, float]:
    """Held-out RMS residual (N, or channel scales) and held-out chi-square (residuals in
    units of the noise: the estimated noise levels, or for several channels fitted without
    them, each channel's white-noise level from its spectrum).

    With an estimated input, the carriage motion in held-out blocks rests on the
    displacement alone, whose noise makes acceleration noise above the signal band: the
    held-out residuals are low-passed to the band of the mechanics (where the noise levels
    were read from, :attr:`RecordNoise.band_hz`) before they are compared, and the
    chi-square counts one independent sample per ``fs / (2 band)`` samples."""
    from ..data.signals import lowpass

    num = chi2 = 0.0
    cnt = 0
    for i, w in enumerate(res.weights):
        out = res.problem.held_out(i, w)
        if not np.any(out):
            continue
        chans = res.channels[i] if res.channels else ("force_x",)
        report = np.array([res.channel_scales[i][c] for c in chans]) if res.channel_scales \
            else np.ones(len(chans))
        cost = np.array([res.problem.channel_scales(i)[c] for c in chans])
        r = res.residuals[i] if res.residuals[i].ndim == 2 else res.residuals[i][:, None]
        noise = res.problem.noise[i] if res.problem.noise else None
        factor = 1.0
        if noise is not None:
            t = res.problem.experiments[i].case.time
            fs = 1.0 / float(np.median(np.diff(t)))
            if noise.band_hz < 0.45 * fs:
                r = np.column_stack([lowpass(t, r[:, j], cutoff_hz=noise.band_hz)
                                     for j in range(r.shape[1])])
                factor = min(2 * noise.band_hz / fs, 1.0)
                cost = cost * np.sqrt(factor)
        elif len(chans) > 1:
            # several channels scaled by their RMS (the spinning rig): the chi-square in
            # units of each channel's white noise, so that its threshold means the same
            # on every record
            cost = _channel_noise(res, i, chans)
        r = r[out]
        num += float(np.sum((r / report) ** 2))
        chi2 += float(np.sum((r / cost) ** 2)) * factor
        cnt += r.size
    return (math.sqrt(num / cnt), chi2) if cnt else (res.rms_residual, math.nan)


def _channel_noise(res: FitResult, i: int, chans: Sequence[str]) -> np.ndarray:
    """White-noise level of each measured channel of case ``i`` (N, N m), read from its
    spectrum above the rig's mechanics (:func:`estimate.fitting.carriage.record_noise`:
    tones removed, above 3 times the fastest rig rate and at least 12 Hz)."""
    from ..fitting.carriage import record_noise

    case = res.problem.experiments[i].case
    spin = case.spin
    top = 0.0 if spin is None else max(abs(spin.rate), abs(2 * math.pi * spin.nutation_frequency),
                                       abs(spin.rate - 2 * math.pi * spin.nutation_frequency))
    return np.array([record_noise(case.time, case.channels[c], top / (2 * math.pi)).force_noise
                     for c in chans])


def _weighted(res: FitResult) -> bool:
    return bool(res.problem.noise) and any(n is not None for n in res.problem.noise)


def bic(res: FitResult, extra_params: int = 0) -> float:
    """Bayesian information criterion (up to a constant): the objective when the residuals
    are in units of their noise, else ``n log(cost / n)``."""
    n = res.n_samples
    k = len(res.names) + extra_params
    if _weighted(res):
        return res.objective + k * math.log(n)
    return n * math.log(res.cost / n) + k * math.log(n)


#: Residual over the noise (:func:`noise_figure`) above which the current fit is a poor
#: place to start a candidate.
POOR_START_RATIO = 2.0


def far_from_noise(current: FitResult) -> bool:
    """The fit is a poor place to start a candidate: its residual is more than
    :data:`POOR_START_RATIO` times the noise, or it holds estimates at their bounds (a
    missing element bends a fit there: a baseline without a diaphragm's spring ends with
    its length and damping at their bounds, at 2 x the noise)."""
    ratio = noise_figure(current).ratio
    pinned = any(b is not None for b in current.at_bound)
    return pinned or (math.isfinite(ratio) and ratio > POOR_START_RATIO)


def poor_start(current: FitResult, res: FitResult) -> bool:
    """The current estimates are far from the data and the candidate fit ``res`` did not
    reach the noise."""
    return far_from_noise(current) and (not res.converged or not noise_figure(res).within)
