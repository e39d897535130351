"""The memory budget a record is checked against before anything is allocated for it.

The fit is what needs memory: a multiple-shooting NLP holds states, Jacobian blocks and
IPOPT's factorisation for every sample. Its peak resident memory grows per sample by
(``benchmarks/bench_length.py`` and fits of the same records with larger models):

- 8-11 KiB for the baseline lateral model with an estimated carriage motion (30,001,
  120,001 and 600,001 samples peak at 0.44, 1.0 and 5.5 GB);
- 10 KiB with a stream lag, 13 KiB with two modes, a lag and transducer offsets;
- 40 KiB for the spinning rig's six channels (a rotor and a pendulum).

:data:`FIT_BYTES_PER_SAMPLE` rounds the one-channel figure up, and
:data:`CHANNEL_BYTES_PER_SAMPLE` adds each further channel (:func:`fit_bytes`: 16 KiB per
sample for one channel, 46 KiB for six). A record is read only when its fit with one
channel would fit the budget; :func:`check_fit` checks a fit's cases with their channels
before the fit allocates them. A record needing more than the budget is refused with the
number of samples it holds and by how much to decimate it; slosh modes lie below about
10 Hz, so a few hundred samples per second are plenty.
"""

from __future__ import annotations

import math
import os
import re

from analogs.errors import InputError

__all__ = ["BUDGET_VARIABLE", "CHANNEL_BYTES_PER_SAMPLE", "DEFAULT_BUDGET",
           "FIT_BYTES_PER_SAMPLE", "check_fit", "decimation_hint", "fit_bytes", "max_samples",
           "memory_budget", "size_text"]

#: Environment variable that sets the budget, e.g. ``16G``, ``512M`` or a number of bytes.
BUDGET_VARIABLE = "SLOSH_MEMORY_BUDGET"
#: Budget when :data:`BUDGET_VARIABLE` is not set [bytes]: 4 GiB.
DEFAULT_BUDGET = 4 * 2**30
#: Memory a fit of one measured channel needs per sample [bytes] (module docstring).
FIT_BYTES_PER_SAMPLE = 16 * 2**10
#: ... and per sample of each further measured channel [bytes].
CHANNEL_BYTES_PER_SAMPLE = 6 * 2**10

_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def memory_budget() -> int:
    """The memory budget [bytes]: :data:`BUDGET_VARIABLE` or :data:`DEFAULT_BUDGET`."""
    text = os.environ.get(BUDGET_VARIABLE, "").strip()
    if not text:
        return DEFAULT_BUDGET
    m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*([KMGT]?)(?:i?B)?", text, re.IGNORECASE)
    if not m or float(m.group(1)) <= 0:
        raise InputError(f"{BUDGET_VARIABLE}={text!r}: expected a memory size such as 16G, "
                         "512M or a number of bytes")
    return int(float(m.group(1)) * _UNITS[m.group(2).upper()])


def max_samples() -> int:
    """The most samples a record may hold within the budget."""
    return memory_budget() // FIT_BYTES_PER_SAMPLE


def fit_bytes(samples: int, channels: int = 1) -> int:
    """Memory a fit of ``samples`` samples of ``channels`` measured channels needs [bytes]."""
    return samples * (FIT_BYTES_PER_SAMPLE + max(channels - 1, 0) * CHANNEL_BYTES_PER_SAMPLE)


def check_fit(cases: list[tuple[str, int, int]]) -> None:
    """Raise :class:`~analogs.errors.InputError` when a fit of ``cases`` (name, samples,
    measured channels) needs more memory than the budget, naming each case's need and by
    how much to decimate."""
    need = sum(fit_bytes(n, c) for _, n, c in cases)
    budget = memory_budget()
    if need <= budget:
        return
    factor = math.ceil(need / budget)
    parts = ", ".join(f"{name}: {n} samples x {c} channel{'s' if c > 1 else ''} "
                      f"({size_text(fit_bytes(n, c))})" for name, n, c in cases)
    raise InputError(f"the fit needs about {size_text(need)} ({parts}), over the memory budget "
                     f"of {size_text(budget)} (set {BUDGET_VARIABLE} to change it): decimate by "
                     f"{factor} (a case's `[test] decimate = {factor}` low-passes its record "
                     f"below the new Nyquist frequency and keeps every {factor}{_ordinal(factor)} "
                     "row), cut the records or fit fewer channels")


def size_text(n_bytes: float) -> str:
    """``4294967296`` as ``4 GiB``."""
    for unit in ("TiB", "GiB", "MiB", "KiB"):
        scale = _UNITS[unit[0]]
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def decimation_hint(samples: int, decimate: int = 1) -> str:
    """What to do with a record of ``samples`` samples over the budget (``decimate``: the
    factor it is read for, its ``[test] decimate`` or the command's default decimation)."""
    limit = max_samples()
    factor = math.ceil(samples / limit)
    now = (f" (it was read for a fit of every {decimate}{_ordinal(decimate)} sample)"
           if decimate > 1 else "")
    return (f"a fit needs about {size_text(FIT_BYTES_PER_SAMPLE)} per sample "
            f"({size_text(samples / decimate * FIT_BYTES_PER_SAMPLE)}), over the memory budget "
            f"of {size_text(memory_budget())} (at most {limit} samples; set {BUDGET_VARIABLE} "
            f"to change it): decimate by {factor}: `[test] decimate = {factor}`{now} low-passes "
            f"the record below the new Nyquist frequency and keeps every "
            f"{factor}{_ordinal(factor)} row; or cut the record")


def _ordinal(n: int) -> str:
    return "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
