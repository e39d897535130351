"""Checks of a record's samples shared by every data format: finite values, enough samples,
strictly increasing and uniform time. The CSV reader names rows by their line in the file,
the lab-format readers by their sample index."""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .case import MIN_DURATION, MIN_SAMPLES, PHYSICAL_RANGES, SPINNING_CHANNELS, TIME_STEP_RTOL

__all__ = ["MAX_LISTED_ROWS", "check_samples", "rows_text"]

MAX_LISTED_ROWS = 10
#: Unit of each measured column whose magnitude is bounded (:data:`PHYSICAL_RANGES`).
_UNITS = {"displacement": "m", "force": "N",
          **{c: "N" if c.startswith("force") else "N m" for c in SPINNING_CHANNELS}}


def rows_text(rows: Sequence[int], word: str = "line", plural: str | None = None) -> str:
    """``[3, 7]`` as ``lines 3, 7`` (at most :data:`MAX_LISTED_ROWS` listed, then a count)."""
    shown = ", ".join(str(n) for n in rows[:MAX_LISTED_ROWS])
    more = f" and {len(rows) - MAX_LISTED_ROWS} more" if len(rows) > MAX_LISTED_ROWS else ""
    many = plural or word + "s"
    return f"{word if len(rows) == 1 else many} {shown}{more}"


def check_samples(name: str, columns: Sequence[str], data: NDArray[np.float64], problems: list[str],
                  *, row: Callable[[int], int], where: Callable[[list[int]], str],
                  skip: Mapping[str, Collection[int]] | None = None, kind: str = "column",
                  quantities: Sequence[str] | None = None, uniform: bool = True) -> None:
    """Append the problems of the samples ``data`` (one column per name in ``columns``, the
    first the time in s) of the file ``name``.

    ``row(i)`` is how a problem names sample ``i`` (a line of a CSV, an index of a channel),
    ``where(rows)`` lists several; the rows in ``skip[column]`` were reported already and
    are not reported again as non-finite. ``kind`` is what a problem calls a column
    ("column" of a CSV, "channel" of a lab file); ``quantities`` are the case's column
    names of the columns (default ``columns``): a displacement, force or torque beyond
    :data:`~estimate.data.case.PHYSICAL_RANGES` (a force of 1e300 N) is refused.
    ``uniform=False`` (``[test] resample_hz``) accepts steps that are not uniform.
    """
    for j, col in enumerate(columns):
        known = (skip or {}).get(col, ())
        nonfinite = [row(i) for i in np.flatnonzero(~np.isfinite(data[:, j])) if row(i) not in known]
        if nonfinite:
            problems.append(f"{name}: {kind} `{col}`: expected finite numbers, found "
                            f"{len(nonfinite)} NaN or inf value(s) at {where(nonfinite)}")
    for j, (col, quantity) in enumerate(zip(columns, quantities or columns)):
        unit = _UNITS.get(quantity)
        if unit is None:
            continue
        high, what = PHYSICAL_RANGES[unit][1:]
        with np.errstate(invalid="ignore"):
            huge = np.flatnonzero(np.abs(data[:, j]) > high)
        if huge.size:
            at = [row(int(i)) for i in huge]
            problems.append(f"{name}: {kind} `{col}`: expected a {what} of magnitude up to "
                            f"{high:g} {unit}, found {huge.size} value(s) beyond it (the largest "
                            f"{float(np.nanmax(np.abs(data[huge, j]))):.3g}) at {where(at)}")
    n = data.shape[0]
    if n < MIN_SAMPLES:
        problems.append(f"{name}: rows: expected at least {MIN_SAMPLES} samples, found {n}")
    t = data[:, 0]
    if n < 2 or not np.isfinite(t).all():
        return
    dt = np.diff(t)
    nonincreasing = np.flatnonzero(dt <= 0.0)
    if nonincreasing.size:
        at = [row(int(i) + 1) for i in nonincreasing]
        problems.append(f"{name}: {kind} `{columns[0]}`: expected strictly increasing times, found "
                        f"{nonincreasing.size} decrease(s) or repeat(s) at {where(at)}")
    elif n >= MIN_SAMPLES and t[-1] - t[0] < MIN_DURATION:
        problems.append(f"{name}: {kind} `{columns[0]}`: expected a record of at least "
                        f"{MIN_DURATION:g} s (times in seconds), found {t[-1] - t[0]:.3g} s "
                        f"({n} samples at a step of {float(np.median(dt)):.3g} s)")
    elif uniform:
        step = float(np.median(dt))
        off = np.flatnonzero(np.abs(dt - step) > TIME_STEP_RTOL * step)
        if off.size:
            at = [row(int(i) + 1) for i in off]
            worst = int(off[np.argmax(np.abs(dt[off] - step))])
            problems.append(
                f"{name}: {kind} `{columns[0]}`: expected a uniform step (median {step:.6g} s, "
                f"tolerance {TIME_STEP_RTOL:g} relative), found {off.size} step(s) off at "
                f"{where(at)} (worst: a step of {dt[worst]:.6g} s ending at "
                f"{where([row(worst + 1)])}); receive-time or jittered timestamps: give "
                "`[test] resample_hz` (Hz) to bring the record onto a uniform time base")
