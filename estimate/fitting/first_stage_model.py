"""The first stage's linear model (:mod:`estimate.fitting.identification`): a record
low-passed and decimated, the design ``[a(t - lag), b(t - lag), 1]`` with the linear
mode's bob acceleration ``b``, the masses by linear least squares at given frequency,
damping and lags (variable projection), and the lag profile that starts each search."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: Lags searched [s]: the force stream up to 50 ms ahead of or 150 ms behind the motion.
LAG_RANGE = (-0.05, 0.15)
#: Step of the lag profile that starts each search [s].
LAG_GRID_STEP = 0.005

#: Both the acceleration and the force are low-passed (zero phase, the same filter, so the
#: linear relation holds) at this multiple of the highest starting frequency, at least
#: LOWPASS_MIN_HZ: an acceleration differentiated from a noisy displacement otherwise
#: carries noise that biases the masses low (errors in the regressor) and the lag.
LOWPASS_FACTOR = 3.0
LOWPASS_MIN_HZ = 6.0
#: Then decimated to about this many samples per period of the cutoff.
SAMPLES_PER_CUTOFF = 5.0


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class _Record:
    """One record for the first stage: decimated times [s], the (low-passed) acceleration
    as a function of time (m/s^2, callable on arrays), the low-passed force [N] at those
    times and the samples used (weights > 0)."""

    time: np.ndarray
    acceleration: object
    force: np.ndarray
    keep: np.ndarray
    #: The acceleration at the lagged times, by lag: the searches evaluate one lag for
    #: several frequencies and damping ratios (their finite differences)
    shifted: dict = field(default_factory=dict, repr=False, compare=False)

    def acceleration_at(self, lag: float) -> np.ndarray:
        """The acceleration at ``time - lag`` (held at its end values outside) [m/s^2]."""
        a = self.shifted.get(lag)
        if a is None:
            if len(self.shifted) > 128:
                self.shifted.clear()
            t = self.time
            a = np.asarray(self.acceleration(np.clip(t - lag, t[0], t[-1])), float)
            self.shifted[lag] = a
        return a


def _prepared(t, a, F, w, cutoff: float) -> _Record:
    """A record low-passed at ``cutoff`` (Hz) and decimated (see :data:`LOWPASS_FACTOR`)."""
    from scipy.interpolate import CubicSpline

    from ..data.signals import lowpass

    t = np.asarray(t, float)
    fs = 1.0 / float(np.median(np.diff(t)))
    acc = np.asarray(a(t), float)
    force = np.asarray(F, float)
    if cutoff < 0.4 * fs:
        acc, force = lowpass(t, acc, cutoff_hz=cutoff), lowpass(t, force, cutoff_hz=cutoff)
    step = max(int(fs / (SAMPLES_PER_CUTOFF * cutoff)), 1)
    keep = np.ones(t.size, bool) if w is None else np.asarray(w) > 0
    return _Record(t[::step], CubicSpline(t, acc), force[::step], keep[::step])


def _swing(recs, x, gravity: float) -> float:
    """The linear mode's swing amplitude [rad] after the strongest acceleration: the bob's
    displacement over the pendulum length is ``-b / g`` (``b`` the bob acceleration, the
    damping term aside); the amplitude is sqrt(2) times its RMS."""
    omega, zeta = math.exp(x[0]), math.exp(x[1])
    thetas = []
    for i, rec in enumerate(recs):
        X = _design(rec, omega, zeta, float(x[2 + i]))
        after = int(np.argmax(np.abs(X[:, 0])))
        thetas.append(X[after:, 1][rec.keep[after:]] / gravity)
    theta = np.concatenate(thetas)
    return math.sqrt(2 * float(np.mean(theta**2))) if theta.size else math.nan


def _bob_acceleration(a: np.ndarray, dt: float, omega: float, zeta: float) -> np.ndarray:
    """The linear mode's bob acceleration for the acceleration samples ``a`` (m/s^2), from
    rest: ``B/A = (2 zeta omega s + omega^2) / (s^2 + 2 zeta omega s + omega^2)``,
    discretised by the bilinear transform ``s = K (1 - 1/z) / (1 + 1/z)`` prewarped at
    ``omega`` (``K = omega / tan(omega dt / 2)``: the resonance lands exactly), filtered
    over the record by ``scipy.signal.lfilter``."""
    from scipy.signal import lfilter

    K = omega / math.tan(min(omega * dt / 2, 1.5))
    c, w2 = 2 * zeta * omega, omega**2
    num = [c * K + w2, 2 * w2, w2 - c * K]
    den = [K * K + c * K + w2, 2 * (w2 - K * K), K * K - c * K + w2]
    return lfilter(num, den, a - a[0]) + a[0]


def _design(rec: _Record, omega: float, zeta: float, lag: float) -> np.ndarray:
    """Columns ``[a(t - lag), b(t - lag), 1]`` of one record (``b`` of the linear mode)."""
    t = rec.time
    a = rec.acceleration_at(lag)
    b = _bob_acceleration(a, float(t[1] - t[0]), omega, zeta)
    return np.column_stack([a, b, np.ones_like(a)])


def _stacked(recs, x) -> tuple[np.ndarray, np.ndarray]:
    """The stacked design (shared M, m; an offset per record) and force, kept samples."""
    omega, zeta = math.exp(x[0]), math.exp(x[1])
    blocks, forces = [], []
    n = len(recs)
    for i, rec in enumerate(recs):
        X = _design(rec, omega, zeta, float(x[2 + i]))[rec.keep]
        offset = np.zeros((X.shape[0], n))
        offset[:, i] = 1.0
        blocks.append(np.hstack([X[:, :2], offset]))
        forces.append(rec.force[rec.keep])
    return np.vstack(blocks), np.concatenate(forces)


def _projected(recs, x) -> tuple[np.ndarray, np.ndarray]:
    """Residual of the linear least-squares fit at the nonlinear parameters ``x`` (log
    omega, log zeta, lags), and the linear coefficients ``(M, m, offsets...)``."""
    X, F = _stacked(recs, x)
    beta, *_ = np.linalg.lstsq(X, F, rcond=None)
    return F - X @ beta, beta


def _beta_covariance(recs, x, s2: float) -> np.ndarray:
    X, _ = _stacked(recs, x)
    return s2 * np.linalg.pinv(X.T @ X)


def _physical(recs, x) -> bool:
    """Positive rigid and slosh masses and lags off the edges of :data:`LAG_RANGE`."""
    _, beta = _projected(recs, x)
    inside = all(LAG_RANGE[0] + LAG_GRID_STEP < t < LAG_RANGE[1] - LAG_GRID_STEP for t in x[2:])
    return bool(beta[0] > 0 and beta[1] > 0 and inside)


def _lag_profile(recs, x0: np.ndarray) -> np.ndarray:
    """Per record, the lag on a grid over :data:`LAG_RANGE` where the projected objective
    (the others at ``x0``) is lowest among lags with positive masses: a drive near one
    frequency also fits half a period off with the masses' signs flipped."""
    grid = np.arange(LAG_RANGE[0], LAG_RANGE[1] + 0.5 * LAG_GRID_STEP, LAG_GRID_STEP)
    x = x0.copy()
    for i in range(len(recs)):
        costs = []
        for tau in grid:
            x[2 + i] = tau
            r, beta = _projected(recs[i:i + 1], np.r_[x[:2], tau])
            costs.append(float(r @ r) if beta[0] > 0 and beta[1] > 0 else math.inf)
        if np.isfinite(costs).any():
            x[2 + i] = grid[int(np.argmin(costs))]
    return x[2:]
