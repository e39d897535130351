"""The memory budget a record is checked against before anything is allocated for it.

The fit is what needs memory: a multiple-shooting NLP holds states, Jacobian blocks and
IPOPT's factorisation for every sample. Its peak resident memory grows by 9-13 KiB per
sample for the baseline model with an estimated carriage motion
(``benchmarks/bench_length.py``: 30,001, 120,001 and 600,001 samples peak at 0.48, 1.2 and
6.4 GB); :data:`FIT_BYTES_PER_SAMPLE` rounds that up for larger models. A record needing
more than the budget is refused with the number of samples it holds and by how much to
decimate it; slosh modes lie below about 10 Hz, so a few hundred samples per second are
plenty.
"""

from __future__ import annotations

import math
import os
import re

from analogs.errors import InputError

__all__ = ["BUDGET_VARIABLE", "DEFAULT_BUDGET", "FIT_BYTES_PER_SAMPLE", "decimation_hint",
           "max_samples", "memory_budget", "size_text"]

#: Environment variable that sets the budget, e.g. ``16G``, ``512M`` or a number of bytes.
BUDGET_VARIABLE = "SLOSH_MEMORY_BUDGET"
#: Budget when :data:`BUDGET_VARIABLE` is not set [bytes]: 4 GiB.
DEFAULT_BUDGET = 4 * 2**30
#: Memory a fit needs per sample of a record [bytes] (see the module docstring).
FIT_BYTES_PER_SAMPLE = 32 * 2**10

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


def size_text(n_bytes: float) -> str:
    """``4294967296`` as ``4 GiB``."""
    for unit in ("TiB", "GiB", "MiB", "KiB"):
        scale = _UNITS[unit[0]]
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def decimation_hint(samples: int) -> str:
    """What to do with a record of ``samples`` samples over the budget."""
    limit = max_samples()
    factor = math.ceil(samples / limit)
    return (f"a fit needs about {size_text(FIT_BYTES_PER_SAMPLE)} per sample "
            f"({size_text(samples * FIT_BYTES_PER_SAMPLE)}), over the memory budget of "
            f"{size_text(memory_budget())} (at most {limit} samples; set {BUDGET_VARIABLE} to "
            f"change it): decimate by {factor} (low-pass below the new Nyquist frequency, then "
            f"keep every {factor}{_ordinal(factor)} row) or cut the record")


def _ordinal(n: int) -> str:
    return "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
