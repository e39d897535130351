"""How a diagnosis scores a fit: held-out blocks, the held-out residual and chi-square,
the BIC, and whether the current fit is a poor place to start a candidate."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..fitting.result import FitResult
from .evidence import NOISE_MARGIN

__all__ = ["holdout_weights", "heldout", "bic", "far_from_noise", "poor_start",
           "POOR_START_VARIANCE"]


def holdout_weights(n: int, *, blocks: int = 10, held: Sequence[int] = (1, 4, 7)) -> np.ndarray:
    """Weights leaving out interleaved blocks (default 3 of 10) of an ``n``-sample record."""
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
        out = w == 0
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


#: Residual variance (in units of the noise variance) above which the current fit is a
#: poor place to start a candidate: its residual is more than twice the noise.
POOR_START_VARIANCE = 4.0


def far_from_noise(current: FitResult) -> bool:
    """The fit's residual variance (in units of the noise variance) is above
    :data:`POOR_START_VARIANCE`."""
    v0 = current.residual_variance
    return math.isfinite(v0) and v0 > POOR_START_VARIANCE


def poor_start(current: FitResult, res: FitResult) -> bool:
    """The current estimates are far from the data and the candidate fit ``res`` did not
    reach the noise (residual variances in units of the noise variance)."""
    return far_from_noise(current) and (not res.converged
                                        or not res.residual_variance <= NOISE_MARGIN**2)
