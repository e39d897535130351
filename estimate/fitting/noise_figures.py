"""The noise figure of every fitted channel, and the residual over it.

One figure per record and channel (:class:`~estimate.data.signals.noise_figure.NoiseFigure`),
used alike by the fit's residual weights, its report and covariance, the diagnosis verdict
and the campaign:

* a record with quiet segments (the rest before the drive, a settled end) has its figure
  before any fit (:func:`estimate.fitting.carriage.record_noise`), and that figure weighs
  the force residuals;
* otherwise a first fit is weighed by the force's white level above the signal band (a
  provisional figure), and the figure is read from that fit's residual
  (:func:`~estimate.data.signals.noise_figure.residual_noise`); when the two differ by more
  than a factor :data:`REWEIGH_TOLERANCE` the fit is repeated once, weighed by the
  residual's figure,
  and later fits of the record (a diagnosis fits many models to it) start weighed by it.

"x the noise" (:func:`residual_over_noise`) is the RMS residual on the fitted samples over
the figure: the two numbers the reports print.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..data.signals.noise_figure import NoiseFigure, residual_noise
from .carriage import adopt_noise

if TYPE_CHECKING:  # pragma: no cover
    from .problem import FitProblem
    from .result import FitResult

__all__ = ["REWEIGH_TOLERANCE", "case_figures", "residual_over_noise", "reweighed"]

#: A fit weighed by a provisional force noise is repeated, weighed by its residual's figure,
#: when the two differ by more than this factor (the weight sets how much the estimated
#: carriage motion follows the force rather than the displacement). A transducer's low-pass
#: puts the provisional white level 4-10 times below the noise in the band; a model that is
#: still wrong (a diagnosis's baseline) leaves a figure some 30 % high, and re-weighing by
#: it moved such a baseline to another local optimum.
REWEIGH_TOLERANCE = 2.0


def case_figures(problem: "FitProblem", case: int, residual: np.ndarray,
                 weights: np.ndarray) -> dict[str, NoiseFigure]:
    """Per fitted channel of ``case`` (N, N m), its noise figure: the quiet segments' (known
    before the fit) or the fit's ``residual``'s (samples with ``weights`` > 0)."""
    t = np.asarray(problem.experiments[case].case.time, float)
    names = problem.channels(case)
    known = problem.noise[case] if problem.noise else None
    out = {}
    for j, name in enumerate(names):
        if known is not None and known.figure is not None and known.figure.source == "quiet" \
                and len(names) == 1:
            out[name] = known.figure
            continue
        r = residual if residual.ndim == 1 else residual[:, j]
        out[name] = residual_noise(t, r, weights,
                                   peaks_below_hz=None if known is None else known.band_hz)
    return out


def residual_over_noise(result: "FitResult", case: int = 0) -> float:
    """The residual of ``case`` over its noise figure: the RMS residual on the fitted samples
    over the figure (for several channels, the RMS of each channel's ratio). A correct model
    leaves about 1; the diagnosis calls a fit within the noise up to
    :data:`estimate.diagnosis.scoring.NOISE_MARGIN`."""
    figures = result.noise_figures[case] if result.noise_figures else {}
    if not figures:
        return math.nan
    w = result.weights[case] if result.weights else None
    ratios = []
    for name, fig in figures.items():
        _, r = result.channel(name, case)
        keep = np.ones(r.size, bool) if w is None else w > 0
        rms = float(np.sqrt(np.mean(r[keep] ** 2)))
        ratios.append(rms / max(fig.std, 1e-300))
    return float(np.sqrt(np.mean(np.square(ratios))))


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
