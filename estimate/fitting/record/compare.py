"""Fits side by side (``slosh compare``): every parameter and derived quantity of two or more
fit records with its 95 % interval, and each fit's difference from the first in units of
their combined standard error."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analogs.errors import InputError

from .reader import Fit

__all__ = ["Comparison", "Quantity", "compare_fits"]

#: A difference beyond this many combined standard errors is marked in the table.
NOTABLE_Z = 2.0


@dataclass(frozen=True)
class Quantity:
    """One parameter or derived quantity across the fits.

    Attributes
    ----------
    name, unit : str
        Dotted name and SI unit.
    derived : bool
        A derived quantity (frequency, damping ratio), not an estimate.
    values, stderr : tuple of float
        Per fit; NaN where the fit does not have it (or no standard error: a fixed value or
        an estimate at a bound).
    intervals : tuple of (float, float)
        Per fit, the 95 % interval of its record (NaN where there is none).
    """

    name: str
    unit: str
    derived: bool
    values: tuple[float, ...]
    stderr: tuple[float, ...]
    intervals: tuple[tuple[float, float], ...]

    def difference(self, i: int, j: int = 0) -> tuple[float, float, float]:
        """``(value_i - value_j, combined standard error, z)`` of fits ``i`` and ``j``
        (default 0, the reference): the combined standard error
        is ``sqrt(se_i^2 + se_j^2)`` (independent fits), ``z`` the difference over it (NaN
        when either fit lacks the value or its standard error)."""
        d = self.values[i] - self.values[j]
        se = math.hypot(self.stderr[i], self.stderr[j])
        z = d / se if math.isfinite(se) and se > 0 else math.nan
        return d, se, z


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare_fits`.

    Attributes
    ----------
    fits : tuple of Fit
        The fit records, the reference first.
    labels : tuple of str
        Their labels in the table (the files' stems).
    quantities : tuple of Quantity
        Every estimate and derived quantity, each with its differences from the first fit
        (:meth:`Quantity.difference`).
    notes : tuple of str
        What the table's reader should know (the same data files, different models, old
        records).
    """

    fits: tuple[Fit, ...] = field(repr=False)
    labels: tuple[str, ...]
    quantities: tuple[Quantity, ...]
    notes: tuple[str, ...] = ()

    def quantity(self, name: str) -> Quantity:
        """The quantity called ``name``."""
        for q in self.quantities:
            if q.name == name:
                return q
        raise InputError(f"{name!r} is in none of the fits; they have "
                         f"{', '.join(q.name for q in self.quantities)}")

    def report(self) -> str:
        """The comparison as text: a row per quantity, the fits' values +/- standard errors
        and 95 % intervals side by side, then each fit's difference from the first and its
        z (combined standard errors)."""
        from .text import _aligned

        head = ["quantity", "unit"]
        for k, label in enumerate(self.labels):
            head += [label, "95 % interval"]
            if k:
                head += [f"{label} - {self.labels[0]}", "z"]
        rows = [head]
        for q in self.quantities:
            row = [q.name, q.unit or "-"]
            for k in range(len(self.fits)):
                row += [_value(q.values[k], q.stderr[k]), _band(q.intervals[k])]
                if k:
                    d, _, z = q.difference(k)
                    mark = " *" if math.isfinite(z) and abs(z) > NOTABLE_Z else ""
                    row += [f"{d:+.4g}" if math.isfinite(d) else "-",
                            (f"{z:+.2f}{mark}" if math.isfinite(z) else "-")]
            rows.append(row)
        lines = ["Fits compared: " + "; ".join(f"{lab} = {f.path or '(fit)'} ({f.model_spec})"
                                                for lab, f in zip(self.labels, self.fits))]
        lines += _aligned(rows, indent="  ")
        lines.append(f"z: the difference over the combined standard error sqrt(se_a^2 + se_b^2) "
                     f"(independent fits); * |z| > {NOTABLE_Z:g}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The JSON form of ``slosh compare --json``."""
        out: dict[str, Any] = {
            "fits": [{"label": lab, "path": str(f.path) if f.path else None,
                      "model_spec": f.model_spec, "schema": f.schema}
                     for lab, f in zip(self.labels, self.fits)],
            "reference": self.labels[0], "quantities": {}, "notes": list(self.notes)}
        for q in self.quantities:
            entry: dict[str, Any] = {"unit": q.unit, "derived": q.derived, "fits": {}}
            for k, lab in enumerate(self.labels):
                item = {"value": q.values[k], "stderr": q.stderr[k],
                        "interval_95": list(q.intervals[k])}
                if k:
                    d, se, z = q.difference(k)
                    item |= {"difference": d, "combined_stderr": se, "z": z}
                entry["fits"][lab] = item
            out["quantities"][q.name] = entry
        return out

    def plot(self, path: str | Path | None = None):
        """One panel per quantity: each fit's estimate with its 95 % interval, the first
        fit's interval shaded across; the z of each difference beside it. Returns the
        figure (saved to ``path`` when given)."""
        import numpy as np
        from matplotlib.ticker import MaxNLocator

        from ..._plotting import figure, save

        shown = [q for q in self.quantities if any(math.isfinite(v) for v in q.values)]
        ncols = 2 if len(shown) > 3 else 1
        nrows = math.ceil(len(shown) / ncols)
        n = len(self.fits)
        fig = figure(path, figsize=(6.2 * ncols, 0.55 * n * nrows + 1.1 * nrows + 0.6))
        axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
        colors = [f"C{k}" for k in range(n)]
        y = np.arange(n)[::-1]
        for ax, q in zip(axes, shown):
            lo0, hi0 = q.intervals[0]
            if math.isfinite(lo0) and math.isfinite(hi0):
                ax.axvspan(lo0, hi0, color=colors[0], alpha=0.12, lw=0)
            labels = list(self.labels)
            for k in range(n):
                v, (lo, hi) = q.values[k], q.intervals[k]
                if not math.isfinite(v):
                    labels[k] += "\n(not in this fit)"
                    continue
                err = ([[v - lo], [hi - v]] if math.isfinite(lo) and math.isfinite(hi)
                       else None)
                if err is None:
                    labels[k] += "\n(no interval)"
                ax.errorbar([v], [y[k]], xerr=err, fmt="o", color=colors[k], capsize=4,
                            ms=5, lw=1.6)
                z = q.difference(k)[2] if k else math.nan
                if math.isfinite(z):
                    labels[k] += f"\nz = {z:+.2f}"
            ax.set_yticks(y, labels, fontsize=9)
            for k, tick in enumerate(ax.get_yticklabels()):
                z = q.difference(k)[2] if k else math.nan
                if math.isfinite(z) and abs(z) > NOTABLE_Z:
                    tick.set_color("#b2182b")
            ax.set_ylim(-0.7, n - 0.3)
            ax.set_title(f"{q.name} [{q.unit or '-'}]", fontsize=10)
            ax.xaxis.set_major_locator(MaxNLocator(5))
            ax.grid(axis="x", alpha=0.3)
        for ax in axes[len(shown):]:
            ax.set_visible(False)
        fig.suptitle("Fits compared: estimates with 95 % intervals (shaded: "
                     f"{self.labels[0]}); z = difference / combined standard error",
                     fontsize=10)
        save(fig, path)
        return fig


def _value(v: float, se: float) -> str:
    if not math.isfinite(v):
        return "-"
    return f"{v:.6g} +/- {se:.3g}" if math.isfinite(se) else f"{v:.6g}"


def _band(band: tuple[float, float]) -> str:
    lo, hi = band
    return f"[{lo:.6g}, {hi:.6g}]" if math.isfinite(lo) and math.isfinite(hi) else "-"


def _labels(fits: Sequence[Fit]) -> tuple[str, ...]:
    """The files' stems, or their paths where two stems are the same."""
    stems = [f.path.stem if f.path else f"fit{k + 1}" for k, f in enumerate(fits)]
    if len(set(stems)) == len(stems):
        return tuple(stems)
    return tuple(str(f.path) if f.path else s for f, s in zip(fits, stems))


def _same_records(fits: Sequence[Fit]) -> bool:
    """Whether every fit was made from the same data files (by their SHA-256)."""
    digests = []
    for f in fits:
        files = (f.provenance or {}).get("files") or []
        sums = tuple(sorted(str(x.get("data_sha256")) for x in files if isinstance(x, dict)))
        if not sums or "None" in sums:
            return False
        digests.append(sums)
    return len(set(digests)) == 1


def compare_fits(fits: Sequence[Fit]) -> Comparison:
    """Compare two or more fit records ``fits`` (:func:`~estimate.fitting.record.read_fit`):
    every parameter estimated by any of them and every derived quantity, in the order they
    first appear, with each fit's difference from the first.

    Raises
    ------
    InputError
        With fewer than two fits, or when the fits give one quantity different units.

    Examples
    --------
    >>> from estimate.fitting.record import compare_fits, read_fit
    >>> c = compare_fits([read_fit("A1_fit.json"), read_fit("A1_filtered.json")])  # doctest: +SKIP
    >>> c.quantity("p1.mass").difference(1)                                       # doctest: +SKIP
    (-0.0042, 0.0031, -1.35)
    """
    fits = tuple(fits)
    if len(fits) < 2:
        raise InputError(f"compare needs at least two fit records, got {len(fits)}")
    names: list[str] = []
    for f in fits:
        names += [n for n in f.estimated if n not in names]
    derived: list[str] = []
    for f in fits:
        derived += [n for n in f.derived if n not in derived]
    quantities, problems = [], []
    nan2 = (math.nan, math.nan)
    for name in names:
        units = {f.units.get(name) for f in fits if name in f.values} - {None}
        if len(units) > 1:
            problems.append(f"`{name}`: the fits give it in different units ({', '.join(sorted(units))})")
        quantities.append(Quantity(
            name, next(iter(units), ""), False,
            tuple(f.values.get(name, math.nan) for f in fits),
            tuple(f.stderr.get(name, math.nan) for f in fits),
            tuple(f.intervals.get(name, nan2) for f in fits)))
    for name in derived:
        quantities.append(Quantity(
            name, next((f.derived[name][2] for f in fits if name in f.derived), ""), True,
            tuple(f.derived[name][0] if name in f.derived else math.nan for f in fits),
            tuple(f.derived[name][1] if name in f.derived else math.nan for f in fits),
            tuple(f.derived_intervals.get(name, nan2) for f in fits)))
    if problems:
        raise InputError("; ".join(problems))
    notes = []
    if _same_records(fits):
        notes.append("the fits were made from the same data files (same SHA-256): their "
                     "errors are correlated, so the combined standard error overstates the "
                     "spread of the difference and |z| is on the low side")
    specs = {f.model_spec for f in fits}
    if len(specs) > 1:
        notes.append("the fits are of different models (" + ", ".join(sorted(specs)) + "): a "
                     "parameter one model lacks is shown for the others only")
    for f in fits:
        notes += [n for n in f.notes]
    return Comparison(fits, _labels(fits), tuple(quantities), tuple(notes))
