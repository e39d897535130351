"""Reading and validating the CSV of a case: header, field counts, numbers, uniform time."""

from __future__ import annotations

import csv
import io
from collections import deque
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import InputError

from ..inputs import open_input
from ._samples import MAX_LISTED_ROWS as _MAX_LISTED_ROWS
from ._samples import check_samples, rows_text
from .budget import decimation_hint, max_samples
from .case import SPINNING_CHANNELS

__all__ = ["read_csv"]

_COLUMNS_FULL = ("time", "displacement", "force")
_COLUMNS_CRANK = ("time", "force")


def _rows_text(lines: list[int]) -> str:
    return rows_text(lines, "line")


def _values_text(found: list[tuple[int, str]]) -> str:
    shown = ", ".join(f"line {ln} `{txt}`" for ln, txt in found[:_MAX_LISTED_ROWS])
    more = f" and {len(found) - _MAX_LISTED_ROWS} more" if len(found) > _MAX_LISTED_ROWS else ""
    return shown + more


def _count_lines(path: Path) -> tuple[int, bool]:
    """Lines in ``path`` ending in LF, CR LF or CR, counted in 1 MiB chunks (the number of
    its rows unless line ends are mixed), and whether the file ends with a line end."""
    lf = cr = 0
    last = b"\n"
    with open_input(path, "a CSV file") as fh:
        while chunk := fh.read(2**20):
            lf += chunk.count(b"\n")
            cr += chunk.count(b"\r")
            last = chunk[-1:]
    ended = last in (b"\n", b"\r")
    return max(lf, cr) + (not ended), ended


def _digits(text: str) -> tuple[int, int]:
    """Significant digits of a number's mantissa and digits of its exponent (``-5.2e-05``:
    (2, 2))."""
    mantissa, _, exponent = text.strip().lower().partition("e")
    digits = mantissa.lstrip("+-").replace(".", "").lstrip("0")
    return len(digits), len(exponent.lstrip("+-"))


def _cut_short(last: str, before: list[str]) -> bool:
    """Whether ``last``, the final number of a file without a final line end, has fewer
    mantissa or exponent digits than every one of the numbers ``before`` it in its column:
    the file was cut inside it (``1.2345678`` written, ``1.23`` left)."""
    if len(before) < 5:
        return False
    mine = _digits(last)
    others = [_digits(b) for b in before]
    return mine[0] < min(o[0] for o in others) or 0 < min(o[1] for o in others) > mine[1]


def _python_only(text: str) -> bool:
    """Whether ``text``, which ``float`` reads, is a number in Python's syntax only: digit
    separators (``1_000``) and non-ASCII digits, which no other CSV reader accepts."""
    return "_" in text or not text.isascii()


def read_csv(path: Path, excitation: str | None, problems: list[str],
              rig_kind: str | None = "lateral", *, uniform: bool = True,
              motion: Mapping[str, str] | None = None, decimate: int = 1
              ) -> tuple[Any, ...] | None:
    """Read and check the CSV; append problems; return (time, displacement, force, columns)
    or None (``columns``: the non-time columns of a spinning-rig CSV or of a six-axis record,
    else empty). ``motion``: the motion columns a six-axis record's ``[rig.motion]`` names
    by axis (:mod:`estimate.data.motion`).

    The file is streamed: a record with more samples than the memory budget allows
    (:mod:`estimate.data.budget`) is refused before its arrays are allocated. A UTF-8 byte
    order mark (Excel's "CSV UTF-8") is accepted. ``uniform=False`` accepts a time column
    that is not uniform (``[test] resample_hz``). A record the fit decimates by ``decimate``
    (``[test] decimate``) may hold that many times more samples.
    """
    name = path.name
    limit = max_samples() * decimate
    try:
        n_lines, ended = _count_lines(path)
        if n_lines - 1 > limit:
            problems.append(f"{name}: rows: {n_lines - 1} samples; "
                            f"{decimation_hint(n_lines - 1, decimate)}")
            return None
        with io.TextIOWrapper(open_input(path, "a CSV file"), newline="",
                              encoding="utf-8-sig") as fh:
            return _read_rows(csv.reader(fh), n_lines, name, excitation, problems, rig_kind,
                              ended=ended, uniform=uniform, motion=motion, decimate=decimate)
    except InputError as exc:  # replaced by a pipe or a device since it was checked
        problems.append(f"{name}: {str(exc).split(': ', 1)[-1]}")
        return None
    except OSError as exc:
        problems.append(f"{name}: cannot read the CSV file ({exc.strerror or exc})")
        return None
    except (UnicodeDecodeError, csv.Error) as exc:
        problems.append(f"{name}: not a readable UTF-8 CSV file ({exc})")
        return None


def _rows(reader) -> Iterator[tuple[int, list[str]]]:
    for row in reader:
        if row and any(c.strip() for c in row):  # skip blank lines
            yield reader.line_num, row


def _read_rows(reader, n_lines: int, name: str, excitation: str | None, problems: list[str],
               rig_kind: str | None, *, ended: bool = True, uniform: bool = True,
               motion: Mapping[str, str] | None = None, decimate: int = 1
               ) -> tuple[Any, ...] | None:
    limit = max_samples() * decimate
    rows = _rows(reader)
    first = next(rows, None)
    # a six-axis record reads like a spinning-rig one: named columns, all kept
    spinning = rig_kind == "spinning" or motion is not None
    spin_header = "`" + ",".join(("time",) + SPINNING_CHANNELS) + "`"
    if first is None:
        expected = spin_header if spinning else "`time,displacement,force`"
        problems.append(f"{name}: header: expected {expected}, found an empty file")
        return None
    header_line, header = first
    names = tuple(c.strip() for c in header)
    has_disp = False
    if motion is not None:
        from .motion import motion_header_problems

        header_problems = motion_header_problems(name, header_line, header, motion)
        if header_problems:
            problems.extend(header_problems)
            return None
    elif spinning:
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
    data = np.full((min(max(n_lines - 1, 16), limit), ncol), np.nan)
    lines = np.empty(data.shape[0], dtype=int)
    bad_fields: list[str] = []
    skip_lines: set[int] = set()  # rows already reported; not reported again as NaN
    bad_numbers: dict[str, list[tuple[int, str]]] = {c: [] for c in names}
    python_only: dict[str, list[tuple[int, str]]] = {c: [] for c in names}
    recent: deque[tuple[int, str]] = deque(maxlen=21)  # (line, last field) of the last rows
    i = -1
    for i, (line, row) in enumerate(rows):
        if i == data.shape[0]:  # mixed line ends: more rows than counted
            if i >= limit:
                problems.append(f"{name}: rows: more than {limit} samples; "
                                f"{decimation_hint(limit + 1, decimate)}")
                return None
            grow = min(2 * i, limit)
            data = np.vstack([data, np.full((grow - i, ncol), np.nan)])
            lines = np.concatenate([lines, np.empty(grow - i, dtype=int)])
        lines[i] = line
        if len(row) != ncol:
            bad_fields.append(f"line {line} ({len(row)} fields)")
            skip_lines.add(line)
            continue
        recent.append((line, row[-1]))
        for j, text in enumerate(row):
            try:
                data[i, j] = float(text)
            except ValueError:
                bad_numbers[names[j]].append((line, text))
                continue
            if _python_only(text):
                python_only[names[j]].append((line, text))
    data, lines = data[:i + 1], lines[:i + 1]
    if not ended and recent and i >= 0 and recent[-1][0] == lines[i] \
            and _cut_short(recent[-1][1], [t for _, t in list(recent)[:-1]]):
        line, text = recent[-1]
        problems.append(f"{name}: line {line}: the file ends inside a number: `{text.strip()}` "
                        f"(column `{names[-1]}`) has fewer digits than each of the "
                        f"{len(recent) - 1} rows before it and no line end follows; the file "
                        "was cut short: copy it again, or remove its last row")
    if bad_fields:
        shown = "; ".join(bad_fields[:_MAX_LISTED_ROWS])
        more = (f" and {len(bad_fields) - _MAX_LISTED_ROWS} more"
                if len(bad_fields) > _MAX_LISTED_ROWS else "")
        problems.append(f"{name}: rows: expected {ncol} comma-separated fields per row, found "
                        f"{len(bad_fields)} row(s) with a different count: {shown}{more}")
    for col in names:
        bad = bad_numbers[col]
        if bad:
            problems.append(f"{name}: column `{col}`: expected numbers, found {len(bad)} "
                            f"non-numeric value(s): {_values_text(bad)}")
        odd = python_only[col]
        if odd:
            problems.append(f"{name}: column `{col}`: expected plain numbers such as 1000 or "
                            f"1e3, found {len(odd)} value(s) with digit separators or non-ASCII "
                            f"digits, which only Python reads: {_values_text(odd)}")
    skip = {col: skip_lines | {ln for ln, _ in bad_numbers[col]} for col in names}
    check_samples(name, names, data, problems, row=lambda i: int(lines[i]), where=_rows_text,
                  skip=skip, uniform=uniform)
    t = data[:, 0]
    if len(problems) > 0:
        return None
    if spinning:
        columns = {c: data[:, j].copy() for j, c in enumerate(names) if j > 0}
        return t.copy(), None, None, columns
    force = data[:, -1].copy()
    disp = data[:, 1].copy() if has_disp else None
    return t.copy(), disp, force, {}


