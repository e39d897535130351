"""Figures of the campaign report: the analog's parameters against fill beside the tank
prediction, and against drive amplitude where the campaign varies it."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .predictions import PredictionCurves
from .table import CampaignTable, quantity_column

__all__ = ["plot_against_amplitude", "plot_against_fill", "plotted_quantities"]

#: Horizontal spread of a group's records around their fill (percent of height), so that
#: their intervals do not hide each other; the group's own estimate sits at the fill, where
#: no record is drawn.
SPREAD = 2.4
#: Gap left free at the fill on either side, a fraction of SPREAD.
_GAP = 0.2


def _spread(n: int) -> list[float]:
    """Offsets of a group's ``n`` records from their fill: half on each side (one more on
    the left), none within ``_GAP`` of the fill, where the group's estimate is drawn."""
    left = (n + 1) // 2
    gap, half = _GAP * SPREAD, SPREAD / 2
    step = (half - gap) / max(left - 1, 1)
    return ([-(gap + step * j) for j in reversed(range(left))]
            + [gap + step * j for j in range(n - left)])


_LABELS = {"fixed.mass": "fixed mass", "mass": "pendulum mass", "frequency_hz": "frequency",
           "damping_ratio": "damping ratio", "length": "pendulum length"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plotted_quantities(table: CampaignTable, pendulums: int) -> list[str]:
    """The quantities the tank module predicts and the fits estimate, in panel order."""
    wanted = ["fixed.mass"] + [f"p{i}.{q}" for i in range(1, pendulums + 1)
                               for q in ("mass", "frequency_hz", "damping_ratio")]
    return [q for q in wanted if q in table.quantities]


def _title(q: str, unit: str | None) -> str:
    """A panel's title: ``"pendulum mass (p1.mass) [kg]"``; without the unit (``None``) on
    a panel whose axis is in per cent."""
    comp, _, name = q.partition(".")
    label = _LABELS.get(q) or f"{comp} {_LABELS.get(name, name)}"
    return f"{label} ({q})" + (f" [{unit}]" if unit and unit != "-" else "")


def _values(rows: Sequence[dict[str, Any]], q: str, unit: str) -> tuple[np.ndarray, ...]:
    cols = [quantity_column(q, unit, s) for s in ("", " lo95", " hi95")]
    v, lo, hi = (np.array([r[c] for r in rows], float) for c in cols)
    return v, np.abs(np.vstack([v - lo, hi - v]))


def _panels(n: int, plt, width: float = 12.0):
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(width, 3.6 * rows + 0.8), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return fig, axes.ravel()[:n]


def _paired_panels(n: int, plt, width: float = 12.0):
    """Per quantity a main panel and, beneath it on the same fill axis, a deviation panel."""
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig = plt.figure(figsize=(width, 5.4 * rows + 1.0))
    outer = fig.add_gridspec(rows, cols, hspace=0.28, wspace=0.22)
    pairs = []
    for k in range(n):
        inner = outer[divmod(k, cols)].subgridspec(2, 1, height_ratios=[2.2, 1.3], hspace=0.06)
        main = fig.add_subplot(inner[0])
        pairs.append((main, fig.add_subplot(inner[1], sharex=main)))
        main.tick_params(labelbottom=False)
    return fig, pairs


def _points(ax, rows, x, v, err, *, outliers: bool) -> None:
    """Records (grey, 95 % bars) and outliers (red crosses, named)."""
    flag = np.array([r["outlier"] is True for r in rows], bool)
    for sel, color, marker, size, label in ((~flag, "0.45", "o", 4, "record (95 %)"),
                                            (flag, "red", "X", 8, "outlier (95 %)")):
        if sel.any():
            ax.errorbar(x[sel], v[sel], yerr=err[:, sel], fmt=marker, color=color, ms=size,
                        lw=1, capsize=2, label=label, zorder=3)
    for xi, vi, r in zip(x[flag], v[flag], [r for r, f in zip(rows, flag) if f]):
        if outliers:
            ax.annotate(r["id"], (xi, vi), xytext=(5, 4), textcoords="offset points", fontsize=7,
                        color="red")


def plot_against_fill(table: CampaignTable, curves: Sequence[PredictionCurves],
                      quantities: Sequence[str], path: str | Path, *,
                      reference: Mapping[str, Mapping[str, float]], title: str = "") -> Path:
    """Parameters against fill beside the tank prediction.

    Per quantity, a main panel: each record (95 % interval; outliers red, named), each
    group's fit without its outliers (black diamond), the exact tank prediction (solid) and
    the legacy SLOSH-code one (dashed) of each tank series; and beneath it the same in
    percent from the exact prediction, where the disagreements are visible. ``reference``
    holds each group's exact prediction at its fill.
    """
    plt = _pyplot()
    fig, pairs = _paired_panels(len(quantities), plt)
    ok = [r for r in table.rows if r["status"] in ("ok", "not_converged")]
    groups = [r for r in ok if r["kind"] == "group"]
    records = [r for r in ok if r["kind"] == "record"]
    offsets: dict[str, float] = {}
    for g in {r["group"] for r in records}:
        ids = sorted(r["id"] for r in records if r["group"] == g)
        offsets |= dict(zip(ids, _spread(len(ids))))
    for (ax, dev), q in zip(pairs, quantities):
        unit = table.quantities[q]
        for i, c in enumerate(curves):
            tag = "" if len(curves) == 1 else f" ({c.setup.shape} {c.setup.size_name})"
            exact = c.values.get("exact", {}).get(q)
            for method, style in (("exact", "-"), ("legacy", "--")):
                if q in c.values.get(method, {}):
                    name = "exact" if method == "exact" else "legacy (SLOSH code)"
                    y = c.values[method][q]
                    ax.plot(100 * c.fills, y, style, color=f"C{i}", lw=1.6,
                            label=f"tank prediction, {name}{tag}")
                    if exact is not None:
                        dev.plot(100 * c.fills, 100 * (y / exact - 1), style, color=f"C{i}", lw=1.6)
        for sel, panel in ((records, "records"), (groups, "groups")):
            rows = [r for r in sel if q in reference.get(r["group"], {})]
            if not rows:
                continue
            v, err = _values(rows, q, unit)
            ref = np.array([reference[r["group"]][q] for r in rows])
            x = np.array([100 * r["fill_fraction"] + offsets.get(r["id"], 0.0) for r in rows])
            for axis, y, e in ((ax, v, err), (dev, 100 * (v / ref - 1), 100 * err / ref)):
                if panel == "records":
                    _points(axis, rows, x, y, e, outliers=axis is ax)
                else:
                    axis.errorbar(x, y, yerr=e, fmt="D", color="black", ms=7, mfc="white",
                                  mew=1.6, lw=1.6, capsize=4, zorder=4,
                                  label="group fit without outliers (95 %)")
        ax.set_title(_title(q, unit), fontsize=10)
        dev.set_ylabel("% from exact", fontsize=9)
        dev.set_xlabel("fill [% of tank height]")
        for axis in (ax, dev):
            axis.grid(alpha=0.3)
    handles, labels = pairs[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(title or "Analog parameters against fill and the tank prediction", fontsize=12)
    fig.subplots_adjust(left=0.08, right=0.98, top=0.93, bottom=0.1)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def amplitude_varies(table: CampaignTable, ratio: float = 1.2) -> bool:
    """Whether some group's records differ in drive amplitude by more than ``ratio``."""
    by_group: dict[str, list[float]] = {}
    for r in table.rows:
        a = r["drive_amplitude [m]"]
        if r["kind"] == "record" and r["group"] and math.isfinite(a) and a > 0:
            by_group.setdefault(r["group"], []).append(a)
    return any(max(a) > ratio * min(a) for a in by_group.values())


def plot_against_amplitude(table: CampaignTable, quantities: Sequence[str], path: str | Path
                           ) -> Path:
    """Parameters against drive amplitude (log scale) in percent from their group's fit,
    one colour per group: records with 95 % intervals (outliers as crosses) and the group
    fit's 95 % interval as a band. A diaphragm or a nonlinear damper shows as a trend."""
    from matplotlib.ticker import LogLocator, NullLocator

    plt = _pyplot()
    fig, axes = _panels(len(quantities), plt)
    ok = [r for r in table.rows if r["status"] in ("ok", "not_converged")]
    groups = [r for r in ok if r["kind"] == "group"]
    for ax, q in zip(axes, quantities):
        unit = table.quantities[q]
        for i, g in enumerate(groups):
            sel = [r for r in ok if r["kind"] == "record" and r["group"] == g["id"]
                   and math.isfinite(r["drive_amplitude [m]"])]
            if not sel:
                continue
            v, err = _values(sel, q, unit)
            gv, gerr = _values([g], q, unit)
            # groups side by side (4 % apart) so that their bars at one amplitude stay apart
            shift = 1 + 0.04 * (i - (len(groups) - 1) / 2)
            a = 1e3 * shift * np.array([r["drive_amplitude [m]"] for r in sel])
            color = f"C{i % 10}"
            for flag, marker in ((False, "o"), (True, "X")):
                m = np.array([r["outlier"] is flag for r in sel])
                if m.any():
                    ax.errorbar(a[m], 100 * (v[m] / gv[0] - 1), yerr=100 * err[:, m] / gv[0],
                                fmt=marker, color=color, ms=9 if flag else 5, capsize=2, lw=1,
                                label=None if flag else f"{g['id']} (fill {100 * g['fill_fraction']:g} %)")
            span = np.array([a.min() / 1.15, a.max() * 1.15])
            ax.fill_between(span, -100 * gerr[0, 0] / gv[0], 100 * gerr[1, 0] / gv[0],
                            color=color, alpha=0.15)
        ax.axhline(0, color="0.3", lw=0.8)
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 3.0, 5.0)))
        ax.xaxis.set_major_formatter(lambda x, _: f"{x:g}")
        ax.xaxis.set_minor_locator(NullLocator())
        ax.set_title(_title(q, None), fontsize=10)  # the axis is in per cent, not in the unit
        ax.set_ylabel("% from the group fit", fontsize=9)
        ax.set_xlabel("drive amplitude [mm]")
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle("Analog parameters against drive amplitude, relative to each group's fit "
                 "(bands: its 95 % interval; crosses: outliers)", fontsize=11)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
