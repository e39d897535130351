"""Samples of a record's measured force channels that do not measure the force, found so
that the fit leaves them out (weight 0):

* **clipped** samples (:func:`clipping`): a transducer or an acquisition channel that
  saturates reads its full-scale value, exactly, for as long as the true force stays beyond
  it. Those samples say only that the force was at least that large; fitted as
  measurements, they pull the analog towards a flat-topped force (a 6 N clip of the bundled
  A1 record, a third of its samples: slosh mass 16 % low, its 95 % interval excluding the
  truth, "converged").
* **spikes** (:func:`spikes`): one or two samples far off both their neighbours (an
  electrical glitch, a dropped bit). Two of 60-80 N in A1 (its noise 0.07 N) ended its
  fit on the liquid-mass bound with a residual 7 times the noise.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .case import Case

__all__ = ["MIN_CLIPPED_FRACTION", "MIN_CLIPPED_RUN", "SPIKE_FACTOR", "BadSamples",
           "Flagged", "bad_samples", "clipping", "runs", "spikes"]

#: A channel is clipped at an extreme value when at least this share of its samples (and
#: at least :data:`_MIN_CLIPPED_SAMPLES`) read exactly that value...
MIN_CLIPPED_FRACTION = 0.005
_MIN_CLIPPED_SAMPLES = 5
#: ... and some of them in a run of this many consecutive samples: a noisy, quantised
#: channel reaches its largest step at a few isolated samples, a saturated one stays there.
MIN_CLIPPED_RUN = 3
#: A spike stands off the medians of the three samples before it and of the three after it,
#: on the same side, by this many robust standard deviations (1.4826 times the median
#: absolute value) of the record's departures from the mean of those two medians: noise
#: and the force's curvature (a slosh force sampled at 10 or more samples per period
#: departs from its neighbours' medians by less than a tenth of its amplitude).
SPIKE_FACTOR = 10.0
#: Longest run of samples taken for one spike (a longer excursion is a feature of the force).
_SPIKE_RUN = 2
_SIDE = 3


class BadSamples(UserWarning):
    """Samples of a measured channel are not measurements (clipped, spikes): left out."""


@dataclass(frozen=True)
class Flagged:
    """Samples of one channel that are left out: ``mask`` (True where flagged), why
    (``"clipped"`` or ``"spikes"``) and what the message shows."""

    channel: str
    kind: str
    mask: NDArray[np.bool_]
    detail: str

    def summary(self) -> str:
        """What was found: ``"967 samples (32 %) read exactly -6 and +6, ...: clipped
        (...)"``."""
        n, count = self.mask.size, int(self.mask.sum())
        what = ("clipped (the transducer or the acquisition saturated)" if self.kind == "clipped"
                else "spikes (far off both their neighbours: glitches, not force)")
        return f"{count} sample{'s' * (count != 1)} ({100 * count / n:.2g} %) {self.detail}: {what}"

    def describe(self, name: str) -> str:
        """One line for the fit's notes and warnings (``name``: the case's id)."""
        return f"{name}: column `{self.channel}`: {self.summary()}; left out of the fit"


def runs(mask: NDArray[np.bool_]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Starts and (exclusive) ends of the runs of True in ``mask``."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def clipping(channel: str, values: NDArray[np.float64], *, min_runs: int = 1
             ) -> Flagged | None:
    """The clipped samples of one channel (see :data:`MIN_CLIPPED_FRACTION` and
    :data:`MIN_CLIPPED_RUN`), or None. ``min_runs``: fewest separate runs of
    :data:`MIN_CLIPPED_RUN` or more at a level (a carriage displacement holds its end
    position once, legitimately; clipped, it flattens every peak).

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> f = 8 * np.sin(2 * np.pi * t)
    >>> c = clipping("force", np.clip(f, -6, 6))
    >>> c.detail, int(c.mask.sum()) > 200
    ('read exactly -6 and +6, in runs of up to 23', True)
    >>> clipping("force", f) is None
    True
    """
    x = np.asarray(values, float)
    n = x.size
    if n == 0 or not np.ptp(x) > 0:
        return None
    need = max(_MIN_CLIPPED_SAMPLES, MIN_CLIPPED_FRACTION * n)
    mask = np.zeros(n, bool)
    levels, longest = [], 0
    for level in (float(x.min()), float(x.max())):
        at = x == level
        starts, ends = runs(at)
        run = int((ends - starts).max()) if starts.size else 0
        long_runs = int(np.sum(ends - starts >= MIN_CLIPPED_RUN))
        if at.sum() >= need and run >= MIN_CLIPPED_RUN and long_runs >= min_runs:
            mask |= at
            levels.append(level)
            longest = max(longest, run)
    if not levels:
        return None
    shown = " and ".join(f"{v:+.4g}" for v in levels)
    return Flagged(channel, "clipped", mask, f"read exactly {shown}, in runs of up to {longest}")


def spikes(channel: str, values: NDArray[np.float64],
           time: NDArray[np.float64] | None = None) -> Flagged | None:
    """Isolated spikes of one channel (runs of at most two samples standing off both
    sides' medians, :data:`SPIKE_FACTOR`), or None.

    Examples
    --------
    >>> t = np.arange(3001) * 0.01
    >>> f = 6 * np.sin(2 * np.pi * 2.1 * t) + 0.07 * np.random.default_rng(1).standard_normal(t.size)
    >>> spikes("force", f) is None
    True
    >>> f[1200] += 5.0
    >>> spikes("force", f, t).detail
    'stand off both neighbours by up to 4.8 N (at 12 s)'
    """
    x = np.asarray(values, float)
    n = x.size
    if n < 4 * _SIDE:
        return None
    windows = np.lib.stride_tricks.sliding_window_view(x, _SIDE)
    med = np.median(windows, axis=1)  # med[k]: median of x[k : k + SIDE]
    before = np.full(n, np.nan)
    after = np.full(n, np.nan)
    before[_SIDE:] = med[: n - _SIDE]
    after[: n - _SIDE] = med[1:]
    up, down = x - before, x - after
    valid = np.isfinite(up) & np.isfinite(down)
    # the scale: the departure from the mean of both sides' medians, of noise and the
    # force's curvature; a spike departs from both sides on the same side (a step from one)
    scale = 1.4826 * float(np.median(np.abs(x - 0.5 * (before + after))[valid]))
    if not scale > 0:
        return None
    off = np.where(np.sign(up) == np.sign(down), np.sign(up) * np.minimum(abs(up), abs(down)),
                   0.0)
    mask = np.zeros(n, bool)
    mask[valid] = np.abs(off[valid]) > SPIKE_FACTOR * scale
    # a two-sample spike: each sample sees the other among its neighbours, so its partner
    # may fall below the bar; take the partner when it stands off the outer sides as well
    for i in np.flatnonzero(mask):
        for j in (i - 1, i + 1):
            if 0 <= j < n and not mask[j]:
                lo, hi = min(i, j), max(i, j)
                outer = np.r_[x[max(lo - _SIDE, 0):lo], x[hi + 1:hi + 1 + _SIDE]]
                if outer.size and abs(x[j] - np.median(outer)) > SPIKE_FACTOR * scale and \
                        np.sign(x[j] - np.median(outer)) == np.sign(off[i]):
                    mask[j] = True
    starts, ends = runs(mask)
    for s, e in zip(starts, ends):
        if e - s > _SPIKE_RUN:
            mask[s:e] = False
    if not mask.any():
        return None
    k = int(np.argmax(np.where(mask, np.abs(off), -np.inf)))
    where = f" (at {time[k]:.4g} s)" if time is not None else ""
    return Flagged(channel, "spikes", mask,
                   f"stand off both neighbours by up to {abs(off[k]):.3g} N{where}")


#: What :func:`bad_samples` found in live cases: ``id(case) -> (weak reference, result)``
#: (every problem built of a case asks; a diagnosis builds dozens).
_FOUND: dict[int, tuple[weakref.ref, tuple]] = {}


def bad_samples(case: Case) -> tuple[NDArray[np.bool_] | None, list[Flagged]]:
    """The samples of ``case`` flagged in any measured force channel (True; None when none
    is) and each flagged channel's :class:`Flagged` (clipped first, then spikes among the
    samples that are not clipped), found once per case (a case is immutable)."""
    key = id(case)
    entry = _FOUND.get(key)
    if entry is None or entry[0]() is not case:
        entry = (weakref.ref(case, lambda _: _FOUND.pop(key, None)), _find(case))
        _FOUND[key] = entry
    mask, found = entry[1]
    return mask, list(found)


def _find(case: Case) -> tuple[NDArray[np.bool_] | None, tuple[Flagged, ...]]:
    channels = {}
    if case.force is not None:
        channels["force"] = case.force
    if case.motion is not None:
        channels.update(case.channels)
    found = []
    for name, v in channels.items():
        if v is None:
            continue
        clip = clipping(name, v)
        if clip is not None:
            found.append(clip)
        spike = spikes(name, v, case.time)
        if spike is not None and clip is not None:
            mask = spike.mask & ~clip.mask
            spike = Flagged(name, "spikes", mask, spike.detail) if mask.any() else None
        if spike is not None:
            found.append(spike)
    if not found:
        return None, ()
    mask = np.zeros(case.time.size, bool)
    for f in found:
        mask |= f.mask
    return mask, tuple(found)
