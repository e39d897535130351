"""Zero-phase low-pass filtering with model-extended ends (see :mod:`estimate.data.signals`)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._common import _as_uniform, _sine_costs, _sine_design, _sine_fit
from .spectra import dominant_frequency

__all__ = ["MAX_PAD_RECORDS", "lowpass"]

#: Longest end padding of :func:`lowpass` and the derivative filters, in records.
MAX_PAD_RECORDS = 2


def _end_model(t_win: NDArray[np.float64], x_win: NDArray[np.float64], t_new: NDArray[np.float64],
               fs: float) -> NDArray[np.float64]:
    """Fit line + sinusoid (with 2nd, 3rd harmonics) to one end window; evaluate at t_new."""
    from scipy import optimize
    t0 = t_win[-1] if t_new[0] > t_win[-1] else t_win[0]
    tw, tn = t_win - t0, t_new - t0
    span = float(t_win[-1] - t_win[0])
    f_lo, f_hi = 1.0 / span, min(0.2 * fs, 25.0)
    if not f_lo < f_hi:  # a window shorter than a period of any drive: a line it is
        return np.polyval(np.polyfit(tw, x_win, 1), tn)
    grid = np.geomspace(f_lo, f_hi, 160)

    def harmonics(f: float) -> int:
        return max(1, min(3, int(0.45 * fs / f)))

    # Search the fundamental with one sinusoid: with harmonics in the model, f/2 and f/3 would
    # fit a pure sine exactly as well and the search could lock onto a sub-harmonic.
    costs = _sine_costs(tw, x_win, grid)
    i = int(np.argmin(costs))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = optimize.minimize_scalar(lambda f: _sine_fit(tw, x_win, f)[0],
                                   bounds=(a, b), method="bounded")
    f = float(res.x) if res.fun <= costs[i] else float(grid[i])
    h = harmonics(f)
    _, coef = _sine_fit(tw, x_win, f, h)
    return _sine_design(tn, [k * f for k in range(1, h + 1)]) @ coef


def _extend(t: NDArray[np.float64], x: NDArray[np.float64], step: float, pad_seconds: float
            ) -> tuple[NDArray[np.float64], int]:
    """Extend both ends by a fitted model (see the module docstring); return (x_ext, n_pad).

    The padding is ``pad_seconds`` but at most :data:`MAX_PAD_RECORDS` times the record, so
    its memory is bounded in samples whatever the sampling rate (a 1e-12 s step would
    otherwise ask for 1e12 samples per second of padding); a filter whose response outlasts
    twice the record cannot make use of more.
    """
    n = t.size
    fs = 1.0 / step
    n_pad = min(int(np.ceil(pad_seconds * fs)), MAX_PAD_RECORDS * n)
    n_win = min(n, max(int(round(1.0 * fs)), 16))
    # two periods of the record's dominant frequency when that is longer than 1 s
    try:
        f_dom = dominant_frequency(t, x, min_frequency=2.0 / (t[-1] - t[0]), refine=False)
        n_win = min(n, max(n_win, int(round(2.0 * fs / f_dom))))
    except ValueError:
        pass
    k = np.arange(1, n_pad + 1)
    left = _end_model(t[:n_win], x[:n_win], t[0] - k[::-1] * step, fs)
    right = _end_model(t[-n_win:], x[-n_win:], t[-1] + k * step, fs)
    return np.concatenate([left, x, right]), n_pad




def lowpass(time: ArrayLike, values: ArrayLike, *, cutoff_hz: float = 10.0, order: int = 4,
            ends: Literal["extend", "odd"] = "extend") -> NDArray[np.float64]:
    """Zero-phase Butterworth low-pass filter.

    The filter runs forwards and backwards (``sosfiltfilt``), so the result has no phase lag and
    the magnitude response is ``1 / (1 + (f / cutoff_hz)^(2 order))`` (the square of the
    single-pass Butterworth response: -6 dB at ``cutoff_hz``).

    Parameters
    ----------
    time : array_like
        Uniformly spaced sample times [s].
    values : array_like
        The signal (any unit).
    cutoff_hz : float, default 10.0
        Cutoff frequency [Hz] (the classical filtered-input workflow uses 10 Hz at 100 Hz sampling).
    order : int, default 4
        Butterworth order of one pass.
    ends : {"extend", "odd"}, default "extend"
        ``"extend"`` pads each end with a fitted line + sinusoid model (see the module
        docstring); ``"odd"`` is ``sosfiltfilt``'s own odd reflection.

    Returns
    -------
    numpy.ndarray
        Filtered signal, same unit and length.

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.signals import lowpass
    >>> t = np.arange(3001) * 0.01
    >>> y = np.sin(2 * np.pi * 1.855 * t) + 0.1 * np.sin(2 * np.pi * 30 * t)
    >>> err = lowpass(t, y) - np.sin(2 * np.pi * 1.855 * t)
    >>> bool(np.max(np.abs(err[100:-100])) < 1e-5), bool(np.max(np.abs(err)) < 0.02)
    (True, True)
    """
    from scipy import signal
    t, y, step = _as_uniform(time, values, "values")
    fs = 1.0 / step
    if not 0.0 < cutoff_hz < 0.5 * fs:
        raise ValueError(f"expected 0 < `cutoff_hz` < Nyquist frequency {0.5 * fs:g} Hz, "
                         f"found {cutoff_hz!r}")
    if order < 1:
        raise ValueError(f"expected `order` >= 1, found {order!r}")
    sos = signal.butter(order, cutoff_hz, btype="low", output="sos", fs=fs)
    if ends == "odd":
        return signal.sosfiltfilt(sos, y)
    if ends != "extend":
        raise ValueError(f'expected `ends` "extend" or "odd", found {ends!r}')
    ext, n_pad = _extend(t, y, step, _pad_seconds(cutoff_hz, order))
    return signal.sosfiltfilt(sos, ext, padtype=None)[n_pad:n_pad + t.size]


def _pad_seconds(cutoff_hz: float, order: int) -> float:
    # The Butterworth impulse response has decayed to ~1e-4 after about `order` periods of the
    # cutoff frequency; 1 s keeps at least a second of model beyond each end.
    return max(1.0, 1.5 * order / cutoff_hz)
