"""Shared helpers: input checks and least-squares sinusoid fits."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

_UNIFORM_RTOL = 1e-3          # same tolerance as the case loader (estimate.data.case.TIME_STEP_RTOL)
_MIN_SAMPLES = 16
_AUTO_CUTOFF_MIN_HZ = 4.0     # the estimation notes: 4-6 Hz cutoffs gave < 1% fixed-mass error
_AUTO_CUTOFF_FACTOR = 1.6     # order-8 Butterworth, |H|^2 at f/fc = 1/1.6: 1 - 5e-4
_DERIV_ORDER = 8
_SAVGOL_RTOL = 1e-3           # allowed 2nd-derivative gain error of the S-G filter at the signal
_SIGNIFICANT = 1e-2           # acceleration amplitude relative to the dominant component
_FLOOR_RATIO = 100.0          # a significant peak's PSD over the median PSD (noise floor)


def _as_uniform(time: ArrayLike, values: ArrayLike, name: str = "signal"
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    t = np.asarray(time, dtype=float)
    y = np.asarray(values, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"expected 1-D `time` and `{name}` of equal length, found shapes "
                         f"{t.shape} and {y.shape}")
    if t.size < _MIN_SAMPLES:
        raise ValueError(f"expected at least {_MIN_SAMPLES} samples, found {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError(f"expected finite `time` and `{name}`, found NaN or inf; load data "
                         "through `estimate.data.load_case`, which reports the rows")
    dt = np.diff(t)
    step = float(np.median(dt))
    if not step > 0 or np.any(np.abs(dt - step) > _UNIFORM_RTOL * step):
        raise ValueError("expected uniformly sampled, strictly increasing `time` (every step "
                         f"within {_UNIFORM_RTOL:g} of the median step), found steps from "
                         f"{dt.min():.6g} s to {dt.max():.6g} s")
    return t, y, step


def _sine_design(t: NDArray[np.float64], freqs: list[float]) -> NDArray[np.float64]:
    cols = [np.ones_like(t), t]
    for f in freqs:
        w = 2.0 * np.pi * f
        cols += [np.cos(w * t), np.sin(w * t)]
    return np.column_stack(cols)


def _sine_fit(t: NDArray[np.float64], y: NDArray[np.float64], f: float, harmonics: int = 1
              ) -> tuple[float, NDArray[np.float64]]:
    """Least-squares fit of offset + trend + sinusoids at f, 2f, ...; (residual SS, coeffs)."""
    a = _sine_design(t, [k * f for k in range(1, harmonics + 1)])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    r = y - a @ coef
    return float(r @ r), coef


def _sine_costs(t: NDArray[np.float64], y: NDArray[np.float64], freqs: NDArray[np.float64]
                ) -> NDArray[np.float64]:
    """Residual sum of squares of offset + trend + one sinusoid, for every frequency at once
    (batched normal equations from sums over the samples, columns normalised; ``t`` should
    be centred on the window for conditioning)."""
    w = 2.0 * np.pi * np.asarray(freqs, float)[:, None] * t[None, :]
    C, S = np.cos(w), np.sin(w)
    n, G = t.size, w.shape[0]
    cc = np.einsum("gn,gn->g", C, C)
    M = np.empty((G, 4, 4))
    M[:, 0, 0], M[:, 1, 1] = n, t @ t
    M[:, 0, 1] = M[:, 1, 0] = t.sum()
    M[:, 0, 2] = M[:, 2, 0] = C.sum(axis=1)
    M[:, 0, 3] = M[:, 3, 0] = S.sum(axis=1)
    M[:, 1, 2] = M[:, 2, 1] = C @ t
    M[:, 1, 3] = M[:, 3, 1] = S @ t
    M[:, 2, 3] = M[:, 3, 2] = np.einsum("gn,gn->g", C, S)
    M[:, 2, 2], M[:, 3, 3] = cc, n - cc
    b = np.column_stack([np.full(G, y.sum()), np.full(G, t @ y), C @ y, S @ y])
    d = np.sqrt(np.maximum(np.einsum("gkk->gk", M), 1e-300))
    Mn = M / (d[:, :, None] * d[:, None, :])
    bn = b / d
    coef = np.linalg.solve(Mn + 1e-12 * np.eye(4), bn[..., None])[..., 0]
    return np.maximum(y @ y - np.einsum("gk,gk->g", bn, coef), 0.0)


def _refine_frequency(t: NDArray[np.float64], y: NDArray[np.float64], f0: float,
                      half_width: float, harmonics: int = 1) -> float:
    """Frequency minimising the sinusoid-fit residual within f0 +/- half_width [Hz].

    The residual has side lobes spaced 1/T apart (T the record length), so a grid finer than
    1/T locates the main lobe before a bounded scalar minimisation polishes it.
    """
    from scipy import optimize
    tc = t - t.mean()
    span = float(t[-1] - t[0])
    lo, hi = max(f0 - half_width, 1e-6), f0 + half_width
    grid = np.arange(lo, hi + 1e-12, 1.0 / (4.0 * span))
    if grid.size < 3:
        grid = np.linspace(lo, hi, 3)
    costs = (_sine_costs(tc, y, grid) if harmonics == 1
             else [_sine_fit(tc, y, f, harmonics)[0] for f in grid])
    i = int(np.argmin(costs))
    step = grid[1] - grid[0]
    a, b = max(grid[i] - step, lo), min(grid[i] + step, hi)
    res = optimize.minimize_scalar(lambda f: _sine_fit(tc, y, f, harmonics)[0],
                                   bounds=(a, b), method="bounded",
                                   options={"xatol": 1e-7 * max(f0, 1e-3)})
    return float(res.x) if res.fun <= costs[i] else float(grid[i])
