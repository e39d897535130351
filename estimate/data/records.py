"""Which cases hold the same record: a record given twice would count its evidence twice
(and shrink the standard errors by sqrt(2))."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

from .case import Case, CaseError

__all__ = ["record_digest", "refuse_repeated"]


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
