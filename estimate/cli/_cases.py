"""Loading the case files of a command: each record once, and what looks wrong said."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the parser of every command imports this module: load nothing yet
    from ..data import Case

__all__ = ["add_strict", "load_cases"]


def add_strict(parser) -> None:
    """The ``--strict`` option of a command that reads case files."""
    parser.add_argument("--strict", action="store_true",
                        help="refuse case files with unknown keys or tables (default: a warning "
                             "naming the key and the nearest known name)")


def load_cases(paths: Sequence[str], *, prediction: bool = False, strict: bool = False
               ) -> tuple[list["Case"], list[str]]:
    """The cases of ``paths`` and warnings about them (``strict``: unknown keys are errors,
    :func:`estimate.data.load_case`).

    A record given twice is refused (:func:`estimate.data.records.refuse_repeated`);
    ``prediction``: a ``[prediction]`` that contradicts the tank's own modal prediction is
    a warning (:func:`estimate.fitting.initial.prediction_conflicts`).
    """
    from ..data import load_case
    from ..data.records import refuse_repeated

    cases = [load_case(p, strict=strict) for p in paths]
    refuse_repeated(cases)
    notes: list[str] = []
    if prediction:
        from ..fitting.initial import prediction_conflicts

        for case in cases:
            notes += prediction_conflicts(case)
    return cases, notes
