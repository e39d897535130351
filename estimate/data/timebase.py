"""A uniform time base for records whose timestamps are not uniform: ``[test] resample_hz``.

Acquisition systems write two kinds of irregular timestamps:

* **receive times of a clocked stream.** A transducer samples on its own clock and the
  logging computer stamps each sample when it arrives, late by a varying latency: the
  samples are uniform, the stamps jitter (by milliseconds on a network or USB link). The
  sample's index is then the better clock. Interpolating the values at the jittered stamps
  would put each value up to a jitter away from where it was taken (1 ms of a 0.9 m/s
  transport move is 0.9 mm, a hundred times an encoder's noise), so these samples are
  placed on the least-squares line through their stamps (index -> time) and their values
  are kept as recorded. The test: the stamps' deviation from that line, averaged over
  every run of :data:`SLIP_WINDOW` samples, stays within a quarter step (a dropped or
  repeated sample shifts every later stamp by a step; one within the last dozen samples
  escapes the test and moves those few samples by one step).
* **samples taken at irregular times** (a polled logger, a file merged from streams): the
  stamps are the sampling times. Every channel is then interpolated at the uniform grid
  by the same not-a-knot cubic spline (:class:`scipy.interpolate.CubicSpline`), so the
  displacement and the force keep their relative timing; the grid does not reach beyond
  the first and last stamps. A grid coarser than the record's mean step would alias the
  noise above its Nyquist frequency: it is refused (decimate with an anti-alias filter
  first).

A clocked stream whose rate differs from ``resample_hz`` by more than
:data:`RATE_TOLERANCE` (relative) is placed on its line, then interpolated at
``resample_hz``. What was done is returned as a note, which the fit report prints.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["RATE_TOLERANCE", "SLIP_WINDOW", "UniformRecord", "uniform_record"]

#: Samples over which the stamps' deviation from their line is averaged to find slips.
SLIP_WINDOW = 50
#: A clock within this relative difference of ``resample_hz`` keeps its own rate (sampling
#: clocks are not exact; interpolating by 0.1 % would only smear the samples).
RATE_TOLERANCE = 0.01


@dataclass(frozen=True)
class UniformRecord:
    """A record on a uniform time base.

    Attributes
    ----------
    time : numpy.ndarray
        Uniform sample times [s].
    columns : dict of str to numpy.ndarray
        The channels on ``time``, in their units.
    note : str
        What was done, for the fit report.
    """

    time: NDArray[np.float64]
    columns: dict[str, NDArray[np.float64]]
    note: str


def _clock_line(t: NDArray[np.float64], step: float) -> tuple[NDArray[np.float64], float] | None:
    """The least-squares line through the stamps ``t`` against their index and the largest
    stamp deviation from it [s], when the stamps are receive times of a uniform clock
    (module docstring); else None."""
    n = t.size
    i = np.arange(n, dtype=float)
    slope, intercept = np.polyfit(i, t, 1)
    line = intercept + slope * i
    dev = t - line
    window = min(SLIP_WINDOW, n)
    smooth = np.convolve(dev, np.full(window, 1.0 / window), mode="valid")
    if np.max(np.abs(smooth)) > 0.25 * slope:
        return None
    return line, float(np.max(np.abs(dev)))


def uniform_record(name: str, time: NDArray[np.float64],
                   columns: Mapping[str, NDArray[np.float64]], rate_hz: float,
                   problems: list[str], *, max_samples: int) -> UniformRecord | None:
    """Bring a record with strictly increasing stamps ``time`` [s] onto a uniform time
    base near ``rate_hz`` [Hz] (module docstring); append a problem (naming the data file
    ``name`` and ``[test] resample_hz``) and return None when that cannot be done soundly.

    ``columns`` are the other channels (any units); ``max_samples`` bounds the samples of
    an interpolated record (the memory budget of a fit).
    """
    from scipy.interpolate import CubicSpline
    t = np.asarray(time, float)
    step = 1.0 / rate_hz
    n = t.size
    mean_step = (t[-1] - t[0]) / (n - 1)
    cols = {k: np.asarray(v, float) for k, v in columns.items()}
    clocked = _clock_line(t, mean_step)
    if clocked is not None:
        line, worst = clocked
        clock_hz = 1.0 / float(line[1] - line[0])
        dev = t - line
        what = (f"timestamps jitter by up to {1e3 * worst:.3g} ms (RMS "
                f"{1e3 * float(np.sqrt(np.mean(dev**2))):.3g} ms) about a uniform clock at "
                f"{clock_hz:.6g} Hz: taken as receive times of uniformly taken samples, "
                "which were placed on the least-squares line through the timestamps, their "
                "values kept")
        if worst <= 1e-6 * mean_step + 1e-12:
            what = f"timestamps uniform at {clock_hz:.6g} Hz"
        if abs(clock_hz - rate_hz) <= RATE_TOLERANCE * rate_hz:
            tail = "" if worst > 1e-6 * mean_step + 1e-12 else "; nothing to do"
            return UniformRecord(line, cols, f"{name}: [test] resample_hz = {rate_hz:g}: "
                                 f"{what}{tail}")
        base, source = line, what
    else:
        base, source = t, (f"timestamps irregular (steps {1e3 * float(np.min(np.diff(t))):.3g} "
                           f"to {1e3 * float(np.max(np.diff(t))):.3g} ms, mean "
                           f"{1e3 * mean_step:.3g} ms): taken as the sampling times")
    if step > mean_step * (1 + RATE_TOLERANCE):
        problems.append(f"{name}: [test] resample_hz: expected a rate at or above the record's "
                        f"mean rate {1 / mean_step:.6g} Hz, found {rate_hz:g} Hz; a coarser grid "
                        "would alias the noise above its Nyquist frequency: decimate the record "
                        "with an anti-alias filter first, or give resample_hz = "
                        f"{1 / mean_step:.6g}")
        return None
    m = int(np.floor((base[-1] - base[0]) / step + 1e-9)) + 1
    if m > max_samples:
        problems.append(f"{name}: [test] resample_hz: {rate_hz:g} Hz makes {m} samples, above "
                        f"the {max_samples} a fit can hold in memory; give a lower rate")
        return None
    grid = base[0] + step * np.arange(m)
    out = {k: CubicSpline(base, v)(grid) for k, v in cols.items()}
    note = (f"{name}: [test] resample_hz = {rate_hz:g}: {source}; every channel interpolated "
            f"at a uniform {rate_hz:g} Hz grid by one not-a-knot cubic spline each ({n} -> "
            f"{m} samples)")
    return UniformRecord(grid, out, note)
