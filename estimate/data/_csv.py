"""Reading and validating the CSV of a case: header, field counts, numbers, uniform time."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from .case import MIN_SAMPLES, SPINNING_CHANNELS, TIME_STEP_RTOL

__all__ = ["read_csv"]

_COLUMNS_FULL = ("time", "displacement", "force")
_COLUMNS_CRANK = ("time", "force")
_MAX_LISTED_ROWS = 10


def _rows_text(lines: list[int]) -> str:
    shown = ", ".join(str(n) for n in lines[:_MAX_LISTED_ROWS])
    more = f" and {len(lines) - _MAX_LISTED_ROWS} more" if len(lines) > _MAX_LISTED_ROWS else ""
    return f"line{'s' if len(lines) != 1 else ''} {shown}{more}"


def read_csv(path: Path, excitation: str | None, problems: list[str],
              rig_kind: str | None = "lateral") -> tuple[Any, ...] | None:
    """Read and check the CSV; append problems; return (time, displacement, force, columns)
    or None (``columns``: the non-time columns of a spinning-rig CSV, else empty)."""
    name = path.name
    try:
        with path.open("r", newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            rows = [(reader.line_num, row) for row in reader]
    except OSError as exc:
        problems.append(f"{name}: cannot read the CSV file ({exc.strerror or exc})")
        return None
    except (UnicodeDecodeError, csv.Error) as exc:
        problems.append(f"{name}: not a readable UTF-8 CSV file ({exc})")
        return None
    rows = [(n, r) for n, r in rows if r and any(c.strip() for c in r)]  # skip blank lines
    spinning = rig_kind == "spinning"
    spin_header = "`" + ",".join(("time",) + SPINNING_CHANNELS) + "`"
    if not rows:
        expected = spin_header if spinning else "`time,displacement,force`"
        problems.append(f"{name}: header: expected {expected}, found an empty file")
        return None
    header_line, header = rows[0]
    names = tuple(c.strip() for c in header)
    has_disp = False
    if spinning:
        missing = [c for c in SPINNING_CHANNELS if c not in names]
        repeated = sorted({c for c in names if names.count(c) > 1})
        if not names or names[0] != "time" or missing or repeated:
            found = []
            if not names or names[0] != "time":
                found.append(f"first column `{names[0] if names else ''}` instead of `time`")
            if missing:
                found.append("no column" + ("s " if len(missing) > 1 else " ")
                             + ", ".join(f"`{c}`" for c in missing))
            if repeated:
                found.append("repeated column(s) " + ", ".join(f"`{c}`" for c in repeated))
            problems.append(f"{name}: header (line {header_line}): expected {spin_header} "
                            f"(extra columns allowed) for `rig = \"spinning\"`, found "
                            f"`{','.join(header)}` ({'; '.join(found)})")
            return None
    elif names == _COLUMNS_FULL:
        has_disp = True
    elif names == _COLUMNS_CRANK:
        has_disp = False
    else:
        expected = "`time,displacement,force`"
        if excitation == "crank":
            expected += " or `time,force`"
        problems.append(f"{name}: header (line {header_line}): expected {expected}, "
                        f"found `{','.join(header)}`")
        return None
    if not spinning and not has_disp and excitation != "crank":
        problems.append(
            f"{name}: column `displacement`: missing, but `[test] excitation = \"measured\"` "
            "needs the carriage displacement (expected header `time,displacement,force`; "
            "use `excitation = \"crank\"` with a `[rig.crank]` table otherwise)")

    ncol = len(names)
    data = np.full((len(rows) - 1, ncol), np.nan)
    lines = np.empty(len(rows) - 1, dtype=int)
    bad_fields: list[str] = []
    skip_lines: set[int] = set()  # rows already reported; not reported again as NaN
    bad_numbers: dict[str, list[tuple[int, str]]] = {c: [] for c in names}
    for i, (line, row) in enumerate(rows[1:]):
        lines[i] = line
        if len(row) != ncol:
            bad_fields.append(f"line {line} ({len(row)} fields)")
            skip_lines.add(line)
            continue
        for j, text in enumerate(row):
            try:
                data[i, j] = float(text)
            except ValueError:
                bad_numbers[names[j]].append((line, text))
    if bad_fields:
        shown = "; ".join(bad_fields[:_MAX_LISTED_ROWS])
        more = (f" and {len(bad_fields) - _MAX_LISTED_ROWS} more"
                if len(bad_fields) > _MAX_LISTED_ROWS else "")
        problems.append(f"{name}: rows: expected {ncol} comma-separated fields per row, found "
                        f"{len(bad_fields)} row(s) with a different count: {shown}{more}")
    for j, col in enumerate(names):
        bad = bad_numbers[col]
        if bad:
            shown = ", ".join(f"line {ln} `{txt}`" for ln, txt in bad[:_MAX_LISTED_ROWS])
            more = f" and {len(bad) - _MAX_LISTED_ROWS} more" if len(bad) > _MAX_LISTED_ROWS else ""
            problems.append(f"{name}: column `{col}`: expected numbers, found {len(bad)} "
                            f"non-numeric value(s): {shown}{more}")
        skip = skip_lines | {ln for ln, _ in bad}
        nonfinite = [int(lines[i]) for i in np.flatnonzero(~np.isfinite(data[:, j]))
                     if int(lines[i]) not in skip]
        if nonfinite:
            problems.append(f"{name}: column `{col}`: expected finite numbers, found "
                            f"{len(nonfinite)} NaN or inf value(s) at {_rows_text(nonfinite)}")

    n = data.shape[0]
    if n < MIN_SAMPLES:
        problems.append(f"{name}: rows: expected at least {MIN_SAMPLES} samples, found {n}")

    t = data[:, 0]
    finite_t = np.isfinite(t)
    if n >= 2 and finite_t.all():
        dt = np.diff(t)
        nonincreasing = np.flatnonzero(dt <= 0.0)
        if nonincreasing.size:
            where = [int(lines[i + 1]) for i in nonincreasing]
            problems.append(f"{name}: column `time`: expected strictly increasing times, found "
                            f"{nonincreasing.size} decrease(s) or repeat(s) at {_rows_text(where)}")
        else:
            step = float(np.median(dt))
            off = np.flatnonzero(np.abs(dt - step) > TIME_STEP_RTOL * step)
            if off.size:
                where = [int(lines[i + 1]) for i in off]
                worst = int(off[np.argmax(np.abs(dt[off] - step))])
                problems.append(
                    f"{name}: column `time`: expected a uniform step (median {step:.6g} s, "
                    f"tolerance {TIME_STEP_RTOL:g} relative), found {off.size} step(s) off at "
                    f"{_rows_text(where)} (worst: a step of {dt[worst]:.6g} s ending at line "
                    f"{lines[worst + 1]})")
    if len(problems) > 0:
        return None
    if spinning:
        columns = {c: data[:, j].copy() for j, c in enumerate(names) if j > 0}
        return t.copy(), None, None, columns
    force = data[:, -1].copy()
    disp = data[:, 1].copy() if has_disp else None
    return t.copy(), disp, force, {}


