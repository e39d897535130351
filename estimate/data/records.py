"""Which cases can be fitted together: a record given twice would count its evidence twice
(and shrink the standard errors by sqrt(2)); records of different tanks, fills or liquids
have different analogs, which one shared fit cannot hold."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import fields

from .case import Case, CaseError

__all__ = ["record_digest", "refuse_mixed", "refuse_repeated", "setup_differences"]


def record_digest(case: Case) -> str:
    """SHA-256 of the samples of ``case`` (time, displacement, force and other channels):
    equal for the same record however it is named."""
    h = hashlib.sha256()
    arrays = {"time": case.time, "displacement": case.displacement, "force": case.force,
              **case.columns}
    for name in sorted(arrays):
        if arrays[name] is not None:
            h.update(name.encode() + b"\0" + arrays[name].tobytes())
    return h.hexdigest()


def refuse_repeated(cases: Sequence[Case]) -> None:
    """Raise :class:`CaseError` naming every case file given twice and every pair of case
    files whose samples are identical."""
    problems = []
    first: dict[str, Case] = {}
    for case in cases:
        other = first.setdefault(record_digest(case), case)
        if other is case:
            continue
        if other.path == case.path:
            problems.append(f"{case.path.name}: given twice; give each record once")
        else:
            problems.append(f"{case.path.name}: holds the same samples as {other.path.name} "
                            f"({case.data_path.name} and {other.data_path.name}); give each "
                            "record once")
    if problems:
        raise CaseError(problems)


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0)
    return a == b


def _text(value: object) -> str:
    return f"{value:g}" if isinstance(value, float) else ("true" if value is True else
                                                           "false" if value is False else
                                                           str(value))


def setup_differences(case: Case, other: Case) -> list[tuple[str, str, str]]:
    """The keys where ``case`` and ``other`` describe a different tank, fill or liquid (or
    gravity), as ``(key, value in case, value in other)``: ``("[tank] fill_fraction", "0.8",
    "0.4")``. Empty: their analogs are the same."""
    out = []
    for table, a, b in (("tank", case.tank, other.tank), ("liquid", case.liquid, other.liquid)):
        for f in fields(a):
            va, vb = getattr(a, f.name), getattr(b, f.name)
            if not _same(va, vb):
                out.append((f"[{table}] {f.name}", _text(va), _text(vb)))
    if not _same(case.rig.gravity, other.rig.gravity):
        out.append(("[rig] gravity", _text(case.rig.gravity), _text(other.rig.gravity)))
    return out


def refuse_mixed(cases: Sequence[Case]) -> None:
    """Raise :class:`CaseError` with one line for every case whose tank, fill or liquid
    (:func:`setup_differences`) is not the first case's: the cases of one fit share the
    analog's physical parameters, and those depend on them."""
    problems = []
    first = cases[0] if cases else None
    for case in cases[1:]:
        diff = setup_differences(case, first)
        if diff:
            keys = "; ".join(f"{k} = {a}, but {first.path.name} has {b}" for k, a, b in diff)
            problems.append(f"{case.path.name}: {keys}: one fit shares the analog's masses, "
                            "lengths and damping across its cases, and they depend on the tank, "
                            "its fill and the liquid; fit each setup on its own, or compare "
                            "fills with `slosh campaign` (it groups records by tank, fill and "
                            "liquid)")
    if problems:
        raise CaseError(problems)
