"""Loading the case files of a command: each record once, and what looks wrong said."""

from __future__ import annotations

from collections.abc import Sequence

from ..data import Case, load_case
from ..data.records import refuse_repeated

__all__ = ["load_cases"]


def load_cases(paths: Sequence[str], *, prediction: bool = False) -> tuple[list[Case], list[str]]:
    """The cases of ``paths`` and warnings about them.

    A record given twice is refused (:func:`estimate.data.records.refuse_repeated`);
    ``prediction``: a ``[prediction]`` that contradicts the tank's own modal prediction is
    a warning (:func:`estimate.fitting.initial.prediction_conflicts`).
    """
    cases = [load_case(p) for p in paths]
    refuse_repeated(cases)
    notes: list[str] = []
    if prediction:
        from ..fitting.initial import prediction_conflicts

        for case in cases:
            notes += prediction_conflicts(case)
    return cases, notes
