"""Loading the case files of a command: each record once, and what looks wrong said."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from ..data import Case, load_case
from ..data.records import refuse_repeated

__all__ = ["load_cases", "positive_hz"]


def load_cases(paths: Sequence[str], *, prediction: bool = False,
               motion_band_hz: float | None = None) -> tuple[list[Case], list[str]]:
    """The cases of ``paths`` and warnings about them.

    A record given twice is refused (:func:`estimate.data.records.refuse_repeated`);
    ``prediction``: a ``[prediction]`` that contradicts the tank's own modal prediction is
    a warning (:func:`estimate.fitting.initial.prediction_conflicts`); ``motion_band_hz``
    (``--motion-band``, Hz) replaces every case's ``[test] motion_band_hz``.
    """
    cases = [load_case(p) for p in paths]
    if motion_band_hz is not None:
        cases = [replace(c, test=replace(c.test, motion_band_hz=motion_band_hz)) for c in cases]
    refuse_repeated(cases)
    notes: list[str] = []
    if prediction:
        from ..fitting.initial import prediction_conflicts

        for case in cases:
            notes += prediction_conflicts(case)
    return cases, notes


def positive_hz(text: str) -> float:
    """An argparse type: a positive finite frequency in Hz."""
    import argparse
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a frequency in Hz, found {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive frequency in Hz, found {text!r}")
    return value
