"""Checks of what a plot shows (not only that it was written): units on the axes, measured
and simulated lines a reader can tell apart, marked frequencies, axis limits that fit the
data."""

import re

import numpy as np
from matplotlib.colors import to_rgba

#: An axis label names its unit in brackets: "force_x [N]", "frequency [Hz]".
UNIT = re.compile(r"\[[^\]]+\]")


def assert_units(ax, *, x=True):
    assert UNIT.search(ax.get_ylabel()), f"no unit in the y label {ax.get_ylabel()!r}"
    if x:
        assert UNIT.search(ax.get_xlabel()), f"no unit in the x label {ax.get_xlabel()!r}"


def line(ax, label):
    """The line whose legend label starts with ``label``."""
    found = [ln for ln in ax.get_lines() if ln.get_label().startswith(label)]
    assert found, f"no line labelled {label!r} among {[ln.get_label() for ln in ax.get_lines()]}"
    return found[0]


def assert_distinguishable(under, over):
    """Different colours, and the line drawn on top thinner or in another dash style, so
    the one below shows on both sides of it."""
    assert to_rgba(under.get_color()) != to_rgba(over.get_color())
    assert over.get_zorder() >= under.get_zorder()
    assert over.get_linewidth() < under.get_linewidth() or over.get_linestyle() != under.get_linestyle()


def marked(ax, gid):
    """x positions of the vertical markers with this gid (e.g. "drive", "mode p1")."""
    return [float(np.asarray(ln.get_xdata())[0]) for ln in ax.get_lines() if ln.get_gid() == gid]


def assert_ylim_fits(ax, data, factor):
    """The y axis holds most of ``data`` and spans at most ``factor`` times its range
    (log axes: in decades)."""
    data = np.asarray(data, float)
    lo, hi = ax.get_ylim()
    if ax.get_yscale() == "log":
        data = data[data > 0]
        span, rng = np.log10(hi / lo), np.log10(data.max() / data.min())
        inside = np.mean((data >= lo) & (data <= hi))
    else:
        span, rng = hi - lo, np.ptp(data)
        inside = np.mean((data >= lo) & (data <= hi))
    assert span <= factor * rng, f"y axis spans {span:.3g}, data {rng:.3g} (factor {factor})"
    assert inside >= 0.99, f"only {100 * inside:.1f} % of the data inside the y axis"
