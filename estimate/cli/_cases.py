"""Loading the case files of a command: each record once, and what looks wrong said."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the parser of every command imports this module: load nothing yet
    from ..data import Case

__all__ = ["add_force", "add_strict", "assignments", "load_cases", "positive_hz"]


def add_strict(parser) -> None:
    """The ``--strict`` option of a command that reads case files."""
    parser.add_argument("--strict", action="store_true",
                        help="refuse case files with unknown keys or tables (default: a warning "
                             "naming the key and the nearest known name)")


def add_force(parser) -> None:
    """The ``--force`` option of a command that takes a fit result
    (:func:`estimate.fitting.record.fit_notes`)."""
    parser.add_argument("--force", action="store_true",
                        help="use a fit result that did not converge (`converged: false`), with "
                             "a warning; refused without it")


def load_cases(paths: Sequence[str], *, prediction: bool = False, strict: bool = False,
               motion_band_hz: float | None = None, shared: bool = False,
               decimate: int | None = None, slosh_band: bool = False
               ) -> tuple[list["Case"], list[str]]:
    """The cases of ``paths`` and warnings about them (``strict``: unknown keys are errors,
    :func:`estimate.data.load_case`).

    A record given twice is refused (:func:`estimate.data.records.refuse_repeated`);
    ``prediction``: a ``[prediction]`` that contradicts the tank's own modal prediction is
    a warning (:func:`estimate.fitting.initial.prediction_conflicts`); ``motion_band_hz``
    (``--motion-band``, Hz) replaces every case's ``[test] motion_band_hz``; ``shared``:
    the cases are fitted with shared parameters, so records of different tanks, fills or
    liquids are refused (:func:`estimate.data.records.refuse_mixed`); ``decimate``
    (``--decimate``) decimates every case's record as ``[test] decimate`` would
    (:func:`estimate.data.decimation.decimate_case`); without it, ``slosh_band``
    decimates a long record sampled far above the slosh band to about 100 Hz
    (:func:`estimate.data.decimation.slosh_band_decimated`: ``slosh fit``'s default).
    """
    from ..data import load_case
    from ..data.decimation import READ_ALLOWANCE
    from ..data.records import refuse_mixed, refuse_repeated

    # the budget counts the samples the command keeps
    allowance = decimate or (READ_ALLOWANCE if slosh_band else 1)
    cases = [load_case(p, strict=strict, allowance=allowance) for p in paths]
    if motion_band_hz is not None:
        cases = [replace(c, test=replace(c.test, motion_band_hz=motion_band_hz)) for c in cases]
    if decimate is not None:
        from ..data.decimation import decimate_case

        cases = [decimate_case(c, decimate, "--decimate") for c in cases]
    elif slosh_band:
        from ..data.decimation import slosh_band_decimated

        cases = [slosh_band_decimated(c) for c in cases]
    refuse_repeated(cases)
    if shared:
        refuse_mixed(cases)
    notes: list[str] = []
    if prediction:
        from ..fitting.initial import prediction_conflicts

        for case in cases:
            notes += prediction_conflicts(case)
    return cases, notes


def decimation_factor(text: str) -> int:
    """An argparse type: an integer >= 1 (``--decimate``)."""
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, found {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, found {text!r}")
    return value


def add_decimate(parser) -> None:
    """The ``--decimate K`` option of the commands that fit."""
    parser.add_argument("--decimate", type=decimation_factor, default=None, metavar="K",
                        help="fit every K-th sample of each record after a zero-phase "
                             "anti-alias low-pass, as the case key [test] decimate = K does "
                             "(a record sampled far above the slosh band fits in a fraction "
                             "of the time and memory; the new rate must be >= 40 Hz). "
                             "Default: a record of 10,000 samples or more at 200 Hz or more "
                             "is fitted (diagnose: searched) at about 100 Hz; 1 keeps "
                             "every sample")


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


def assignments(items: Sequence[str]) -> dict[str, float]:
    """Values of ``--set NAME=VALUE`` options by name.

    Raises
    ------
    InputError
        Naming every item that is not ``NAME=NUMBER``.
    """
    from analogs.errors import InputError

    out, problems = {}, []
    for item in items:
        name, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out[name.strip()] = float(value)
        except ValueError:
            problems.append(f"`--set {item}`: expected NAME=NUMBER")
    if problems:
        raise InputError("; ".join(problems))
    return out
