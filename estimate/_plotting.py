"""Shared look of the project's plots: measured vs simulated styles, robust axis limits,
start-up marking, frequency markers, figures that display inline in a notebook and save
without touching the global backend from a script."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Measured traces: a thick, light line drawn first, so the thin simulated line on top of it
#: leaves it visible on both sides.
MEASURED = {"color": "#7fb2e5", "lw": 2.6, "solid_capstyle": "butt", "zorder": 2}
#: Simulated traces: thin, dark, dashed.
SIMULATED = {"color": "#b2182b", "lw": 0.9, "ls": (0, (5, 2)), "zorder": 3}
#: Residual traces.
RESIDUAL = {"color": "0.15", "lw": 0.7, "zorder": 3}
#: The drive frequency and the fitted mode frequencies on spectra.
DRIVE = {"color": "#1b7837", "lw": 1.2, "ls": "-", "alpha": 0.8, "zorder": 1}
MODE = {"color": "#762a83", "lw": 1.2, "ls": "--", "alpha": 0.8, "zorder": 1}
NOISE = {"color": "0.45", "lw": 1.0, "ls": ":", "zorder": 1}
#: Shading of time or fill ranges the reader should discount (start-up, not converged).
DISCOUNT = {"color": "0.5", "alpha": 0.15, "lw": 0, "zorder": 0}
#: Font sizes (pt) of a zoom inset's title and tick labels: readable in the saved figure
#: (matplotlib's "x-small", 6.9 pt at the default 10 pt, was not).
INSET_TITLE_PT = 8.5
INSET_TICKS_PT = 7.5
#: A force trace with two zoom insets above it: its axis runs from -1.1 to ZOOM_TOP times
#: the trace's peak, and the insets' boxes (axes fractions: the start-up's, the steady
#: end's) leave room above them for their titles under the axis' top line.
ZOOM_TOP = 3.2
ZOOM_BOXES = ((0.04, 0.56, 0.42, 0.35), (0.54, 0.56, 0.42, 0.35))


def figure(path: str | Path | None, **kwargs):
    """A figure with constrained layout: managed by pyplot when it is to be shown
    (``path`` None: inline in a notebook), a bare :class:`~matplotlib.figure.Figure` when it
    is only saved (no global backend switch, no figure left open)."""
    kwargs.setdefault("layout", "constrained")
    if path is None:
        import matplotlib.pyplot as plt

        return plt.figure(**kwargs)
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def save(fig, path: str | Path | None, *, dpi: int = 110) -> None:
    """Save ``fig`` to ``path`` when given."""
    if path is not None:
        fig.savefig(path, dpi=dpi)


def label_inset(inset, title: str) -> None:
    """Title and tick labels of a zoom inset, at :data:`INSET_TITLE_PT` and
    :data:`INSET_TICKS_PT`."""
    inset.tick_params(labelsize=INSET_TICKS_PT)
    inset.set_title(title, fontsize=INSET_TITLE_PT, pad=2)


def unit_of(channel: str) -> str:
    """SI unit of a measured channel (forces N, torques N m)."""
    return "N m" if channel.startswith("torque") else "N"


def startup_end(time: np.ndarray, *, seconds: float = 2.0, fraction: float = 0.1) -> float:
    """End of the start-up window: ``seconds`` after the first sample, at most ``fraction``
    of the record (zero-phase filters and the analog's initial state err there)."""
    t = np.asarray(time, float)
    return float(t[0] + min(seconds, fraction * (t[-1] - t[0])))


def robust_limit(values: np.ndarray, keep: np.ndarray | None = None, *, margin: float = 1.3) -> float:
    """Half-height of a symmetric axis for ``values``: ``margin`` times the 99.5th percentile
    of ``|values|`` on the ``keep`` samples (a few spikes do not set the scale)."""
    v = np.abs(np.asarray(values, float))
    if keep is not None and np.any(keep):
        v = v[keep]
    top = float(np.percentile(v, 99.5)) if v.size else 0.0
    return margin * top if top > 0 else 1.0


def mark_startup(ax, time: np.ndarray, values: np.ndarray, end: float, limit: float, unit: str) -> None:
    """Shade the start-up window and, when the trace leaves the axis there, say by how much."""
    t = np.asarray(time, float)
    ax.axvspan(t[0], end, **DISCOUNT, label="start-up (not scaling the axis)")
    early = t <= end
    peak = float(np.max(np.abs(values[early]))) if np.any(early) else 0.0
    if peak > limit:
        ax.annotate(f"start-up peak {peak:.3g} {unit} (off scale)", xy=(end, 0.97),
                    xycoords=ax.get_xaxis_transform(), xytext=(4, 0), textcoords="offset points",
                    ha="left", va="top", fontsize="small", color="0.3")


def mark_frequency(ax, frequency: float, label: str, style: dict, *, gid: str) -> None:
    """A vertical line at ``frequency`` (Hz) named in the legend and over the axis."""
    ax.axvline(frequency, label=label, gid=gid, **style)


def spectrum_limits(curves: list[np.ndarray], floor: float | None = None) -> tuple[float, float]:
    """Log-axis limits that hold the plotted densities (ignoring the lowest 1 %: filter
    roll-off and window leakage) and the noise floor, with a little room."""
    vals = np.concatenate([np.asarray(c, float)[np.asarray(c) > 0] for c in curves] or [np.ones(1)])
    lo = float(np.percentile(vals, 1.0))
    hi = float(np.max(vals))
    if floor is not None and floor > 0:
        lo, hi = min(lo, floor), max(hi, floor)
    return lo / 2.0, hi * 2.0
