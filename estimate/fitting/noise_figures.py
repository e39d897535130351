"""The noise figure of every fitted channel, and the residual over it.

One figure per record and channel (:class:`~estimate.data.signals.noise_figure.NoiseFigure`),
used alike by the fit's residual weights, its report and covariance, the diagnosis verdict
and the campaign:

* a record with quiet segments (the rest before the drive, a settled end) has its figure
  before any fit (:func:`estimate.fitting.carriage.record_noise`), and that figure weighs
  the force residuals; after the fit the residual's wander below its 2 s segments joins it
  (:func:`~estimate.data.signals.noise_figure.quiet_wander`: a second of rest cannot show
  a transducer's 1/f noise wandering over a minute);
* otherwise a first fit is weighed by the force's white level above the signal band (a
  provisional figure), and the figure is read from that fit's residual
  (:func:`~estimate.data.signals.noise_figure.residual_noise`); when the two differ by more
  than a factor :data:`REWEIGH_TOLERANCE` the fit is repeated once, weighed by the
  residual's figure,
  and later fits of the record (a diagnosis fits many models to it) start weighed by it.

"x the noise" (:func:`residual_over_noise`) is the RMS residual on the fitted samples over
the figure: the two numbers the reports print.

A residual well above its figure is model error, which no covariance of the noise bounds:
a model that lacks an effect excited by the same motion as the modelled ones is biased along
the motion, coherently, by more than a covariance that treats the misfit as a random series
allows (a transport record hiding a second mode of 5 % of the first's mass: the first mode's
estimates 1.7-4.0 robust standard errors off on eight draws, the residual 2.6-3.0 x the
figure). :func:`model_error_factor` is the widening the robust intervals then take, the
residual over the noise (the Birge ratio of metrology's scale factors, with the noise
figure as the expected scatter): on those draws it leaves the first mode 0.6-1.4 widened
standard errors off.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..data.signals.noise_figure import NoiseFigure, quiet_wander, residual_noise
from .carriage import adopt_noise

if TYPE_CHECKING:  # pragma: no cover
    from .problem import FitProblem
    from .result import FitResult

__all__ = ["REWEIGH_TOLERANCE", "MODEL_ERROR_MARGIN", "case_figures", "residual_over_noise",
           "model_error_factor", "reweighed"]

#: A fit weighed by a provisional force noise is repeated, weighed by its residual's figure,
#: when the two differ by more than this factor (the weight sets how much the estimated
#: carriage motion follows the force rather than the displacement). A transducer's low-pass
#: puts the provisional white level 4-10 times below the noise in the band; a model that is
#: still wrong (a diagnosis's baseline) leaves a figure some 30 % high, and re-weighing by
#: it moved such a baseline to another local optimum.
REWEIGH_TOLERANCE = 2.0
#: A residual up to this many times its noise figure is within the noise: correct models
#: leave 0.99-1.06 times the figure on the reference simulator's records and 0.86-1.16 on
#: transport moves whose figure comes from a short rest before the move (the figure's own
#: sampling error). Above it the fit's intervals take the model error
#: (:func:`model_error_factor`) and the diagnosis looks for its cause.
MODEL_ERROR_MARGIN = 1.15


def case_figures(problem: "FitProblem", case: int, residual: np.ndarray,
                 weights: np.ndarray) -> dict[str, NoiseFigure]:
    """Per fitted channel of ``case`` (N, N m), its noise figure: the quiet segments' (known
    before the fit; with the ``residual``'s wander below its segments) or the fit's
    ``residual``'s (samples with ``weights`` > 0)."""
    t = np.asarray(problem.experiments[case].case.time, float)
    names = problem.channels(case)
    known = problem.noise[case] if problem.noise else None
    out = {}
    for j, name in enumerate(names):
        r = residual if residual.ndim == 1 else residual[:, j]
        if known is not None and known.figure is not None and known.figure.source == "quiet" \
                and len(names) == 1:
            out[name] = quiet_wander(t, r, weights, known.figure)
            continue
        out[name] = residual_noise(t, r, weights,
                                   peaks_below_hz=None if known is None else known.band_hz)
    return out


def residual_over_noise(result: "FitResult", case: int = 0) -> float:
    """The residual of ``case`` over its noise figure: the RMS residual on the fitted samples
    over the figure (for several channels, the RMS of each channel's ratio). A correct model
    leaves about 1; the diagnosis calls a fit within the noise up to
    :data:`estimate.diagnosis.scoring.NOISE_MARGIN`."""
    figures = result.noise_figures[case] if result.noise_figures else {}
    w = result.weights[case] if result.weights else None
    return _over_figures(figures, [result.channel(n, case)[1] for n in figures], w)


def _over_figures(figures: Mapping[str, NoiseFigure], residuals, weights) -> float:
    """The RMS over channels of each channel's RMS residual (samples with ``weights`` > 0)
    over its figure; NaN without figures."""
    if not figures:
        return math.nan
    ratios = []
    for fig, r in zip(figures.values(), residuals):
        keep = np.ones(r.size, bool) if weights is None else np.asarray(weights) > 0
        rms = float(np.sqrt(np.mean(np.asarray(r)[keep] ** 2)))
        ratios.append(rms / max(fig.std, 1e-300))
    return float(np.sqrt(np.mean(np.square(ratios))))


def model_error_factor(figures: tuple[Mapping[str, NoiseFigure], ...], residuals: tuple,
                       weights: tuple) -> float:
    """The widening of the robust standard errors for model error: the largest residual
    over its noise figure among the cases (``figures``, ``residuals`` and sample ``weights``
    per case; a residual of several channels has one column each) when it exceeds
    :data:`MODEL_ERROR_MARGIN`, else 1."""
    worst = 1.0
    for figs, r, w in zip(figures, residuals, weights):
        cols = [r] if np.ndim(r) == 1 else [r[:, j] for j in range(r.shape[1])]
        ratio = _over_figures(figs, cols, w)
        if math.isfinite(ratio) and ratio > MODEL_ERROR_MARGIN:
            worst = max(worst, ratio)
    return worst


def reweighed(problem: "FitProblem", figures: tuple[Mapping[str, NoiseFigure], ...]
              ) -> "FitProblem | None":
    """A copy of ``problem`` whose force residuals are weighed by the residual ``figures``
    where a provisional weight differs from them by more than a factor
    :data:`REWEIGH_TOLERANCE`;
    ``None`` when none does (or the weights already came from a residual)."""
    if not problem.noise:
        return None
    noise = list(problem.noise)
    changed = False
    for i, rn in enumerate(noise):
        if rn is None or rn.figure is None or rn.figure.source != "spectrum":
            continue
        fig = next(iter(figures[i].values()), None) if i < len(figures) else None
        if fig is None or not math.isfinite(fig.std) or fig.std <= 0:
            continue
        if not 1.0 / REWEIGH_TOLERANCE <= fig.std / rn.force_noise <= REWEIGH_TOLERANCE:
            noise[i] = rn.weighed_by(fig)
            adopt_noise(rn, noise[i])  # the record's later fits start weighed by it
            changed = True
    return replace(problem, noise=tuple(noise)) if changed else None
