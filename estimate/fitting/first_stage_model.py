"""The first stage's linear model (:mod:`estimate.fitting.identification`): a record
low-passed and decimated, the design ``[a(t - lag), b(t - lag), 1]`` with the linear
mode's bob acceleration ``b``, the masses by linear least squares at given frequency,
damping and lags (variable projection), the exact Jacobian of the projected residual, and
the lag profile that starts each search."""

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
#: The frequency profile (:func:`_frequency_profile`): relative step of its log-spaced
#: frequencies and the damping ratios it tries.
PROFILE_STEP = 0.0125
PROFILE_ZETAS = (0.005, 0.03)


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
    #: The acceleration at the lagged times and its derivative by the lag, by lag: the
    #: searches evaluate one lag for several frequencies and damping ratios
    shifted: dict = field(default_factory=dict, repr=False, compare=False)

    def acceleration_at(self, lag: float) -> tuple[np.ndarray, np.ndarray]:
        """The acceleration at ``time - lag`` [m/s^2] (held at its end values outside) and
        its derivative by ``lag`` [m/s^3] (zero where held)."""
        out = self.shifted.get(lag)
        if out is None:
            if len(self.shifted) > 128:
                self.shifted.clear()
            t = self.time
            s = t - lag
            inside = (s > t[0]) & (s < t[-1])
            s = np.clip(s, t[0], t[-1])
            a = np.asarray(self.acceleration(s), float)
            da = np.where(inside, -np.asarray(self.acceleration(s, 1), float), 0.0)
            out = self.shifted[lag] = (a, da)
        return out


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
        X = _design(rec, omega, zeta, float(x[2 + i]))[0]
        after = int(np.argmax(np.abs(X[:, 0])))
        thetas.append(X[after:, 1][rec.keep[after:]] / gravity)
    theta = np.concatenate(thetas)
    return math.sqrt(2 * float(np.mean(theta**2))) if theta.size else math.nan


def _coefficients(omega, zeta, dt: float):
    """The linear mode's discrete filter ``B/A = (2 zeta omega s + omega^2) / (s^2 + 2 zeta
    omega s + omega^2)`` by the bilinear transform ``s = K (1 - 1/z) / (1 + 1/z)`` prewarped
    at ``omega`` (``K = omega / tan(omega dt / 2)``: the resonance lands exactly):
    numerator, denominator, and their derivatives by log omega and by log zeta (three
    coefficients each, along the first axis: ``omega`` and ``zeta`` may be arrays)."""
    half = omega * dt / 2
    if np.ndim(half) == 0:  # a search's evaluation: Python floats are faster
        warp = min(float(half), 1.5)  # near Nyquist the warp is held
        K = omega / math.tan(warp)
        dK = K - omega * warp / math.sin(warp) ** 2 if half < 1.5 else K  # by log omega
    else:
        warp = np.minimum(half, 1.5)
        K = omega / np.tan(warp)
        dK = np.where(half < 1.5, K - omega * warp / np.sin(warp) ** 2, K)
    c, w2 = 2 * zeta * omega, omega**2

    def polys(dK, dc, dw2):
        num = np.array([c * K + w2, 2 * w2, w2 - c * K])
        den = np.array([K * K + c * K + w2, 2 * (w2 - K * K), K * K - c * K + w2])
        dcK = dc * K + c * dK
        dnum = np.array([dcK + dw2, 2 * dw2, dw2 - dcK])
        dden = np.array([2 * K * dK + dcK + dw2, 2 * (dw2 - 2 * K * dK), 2 * K * dK - dcK + dw2])
        return num, den, dnum, dden

    num, den, d_num_omega, d_den_omega = polys(dK, c, 2 * w2)
    _, _, d_num_zeta, d_den_zeta = polys(0 * K, c, 0 * w2)
    return num, den, (d_num_omega, d_den_omega), (d_num_zeta, d_den_zeta)


def _design(rec: _Record, omega: float, zeta: float, lag: float, derivatives: bool = False):
    """Columns ``[a(t - lag), b(t - lag), 1]`` of one record (``b`` of the linear mode) and,
    with ``derivatives``, those of ``b`` by log omega and log zeta and of ``[a, b]`` by the
    lag (``None`` without). ``b = y + a(0)``, ``y = (N/D) (a - a(0))`` from rest, so
    ``dy = (dN u - dD y) / D``: exact, one filter each."""
    from scipy.signal import lfilter

    t = rec.time
    a, da = rec.acceleration_at(lag)
    num, den, d_omega, d_zeta = _coefficients(omega, zeta, float(t[1] - t[0]))
    u = a - a[0]
    y = lfilter(num, den, u)
    X = np.column_stack([a, y + a[0], np.ones_like(a)])
    if not derivatives:
        return X, None
    by = [lfilter(dn, den, u) - lfilter(dd, den, y) for dn, dd in (d_omega, d_zeta)]
    b_lag = lfilter(num, den, da - da[0]) + da[0]
    return X, (by[0], by[1], np.column_stack([da, b_lag]))


def _stacked(recs, x, derivatives: bool = False):
    """The stacked design (shared M, m; an offset per record) and force, kept samples; with
    ``derivatives`` also the design's derivatives by ``x`` (log omega, log zeta, the lags),
    one matrix each (else ``None``)."""
    omega, zeta = math.exp(x[0]), math.exp(x[1])
    n = len(recs)
    if n == 1 and recs[0].keep.all():  # the usual case, without the copies
        X, d = _design(recs[0], omega, zeta, float(x[2]), derivatives)
        if d is None:
            return X, recs[0].force, None
        dX = [np.zeros_like(X) for _ in range(3)]
        dX[0][:, 1], dX[1][:, 1], dX[2][:, :2] = d
        return X, recs[0].force, dX
    blocks, forces, parts = [], [], []
    for i, rec in enumerate(recs):
        X, d = _design(rec, omega, zeta, float(x[2 + i]), derivatives)
        keep = rec.keep
        X = X[keep]
        offset = np.zeros((X.shape[0], n))
        offset[:, i] = 1.0
        blocks.append(np.hstack([X[:, :2], offset]))
        forces.append(rec.force[keep])
        parts.append(None if d is None else (d[0][keep], d[1][keep], d[2][keep]))
    Xs, F = np.vstack(blocks), np.concatenate(forces)
    if not derivatives:
        return Xs, F, None
    rows = np.cumsum([0] + [b.shape[0] for b in blocks])
    dX = [np.zeros_like(Xs) for _ in range(2 + n)]
    for i, (by_omega, by_zeta, by_lag) in enumerate(parts):
        sl = slice(rows[i], rows[i + 1])
        dX[0][sl, 1] = by_omega
        dX[1][sl, 1] = by_zeta
        dX[2 + i][sl, :2] = by_lag
    return Xs, F, dX


def _solve_linear(X: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares coefficients of ``F ~ X beta`` and the inverse Gram matrix
    ``(X^T X)^-1``: from the normal equations of the column-scaled design, by the
    pseudo-inverse when they are near singular (the design has a few columns)."""
    scale = np.sqrt(np.einsum("ij,ij->j", X, X))
    scale[scale == 0] = 1.0
    G = (X.T @ X) / np.outer(scale, scale)
    try:
        d = np.diag(np.linalg.cholesky(G))
        inverse = np.linalg.inv(G) if d.min() >= 1e-6 * d.max() else np.linalg.pinv(G)
    except np.linalg.LinAlgError:
        inverse = np.linalg.pinv(G)
    inverse /= np.outer(scale, scale)
    return inverse @ (X.T @ F), inverse


def _projected(recs, x) -> tuple[np.ndarray, np.ndarray]:
    """Residual of the linear least-squares fit at the nonlinear parameters ``x`` (log
    omega, log zeta, lags), and the linear coefficients ``(M, m, offsets...)``."""
    X, F, _ = _stacked(recs, x)
    beta, _ = _solve_linear(X, F)
    return F - X @ beta, beta


def _projected_jacobian(recs, x) -> np.ndarray:
    """The exact Jacobian of :func:`_projected`'s residual by ``x`` (:class:`_Projection`)."""
    return _Projection(recs, x, range(len(x))).jacobian(x)


class _Projection:
    """:func:`_projected`'s residual and :func:`_projected_jacobian` for a search over the
    ``free`` entries of ``x`` (the others held at ``x``'s), the Jacobian computed with the
    residual and kept for the call at the same point that follows (SciPy's
    ``least_squares`` asks for both at every accepted step). The Jacobian is Golub and
    Pereyra's, exact: ``dr/dx_k = -(I - X X^+) dX_k beta - X (X^T X)^-1 dX_k^T r``."""

    def __init__(self, recs, x, free):
        self.recs, self.x, self.free = recs, np.array(x, float), list(free)
        self._at, self._jacobian = None, None

    def _full(self, y):
        x = self.x.copy()
        x[self.free] = y
        return x

    def residual(self, y) -> np.ndarray:
        x = self._full(y)
        X, F, dX = _stacked(self.recs, x, derivatives=True)
        dX = [dX[k] for k in self.free]
        beta, inverse = _solve_linear(X, F)
        r = F - X @ beta
        V = np.column_stack([D @ beta for D in dX])
        W = np.column_stack([D.T @ r for D in dX])
        self._at = np.array(y, float)
        self._jacobian = -(V - X @ (inverse @ (X.T @ V))) - X @ (inverse @ W)
        return r

    def jacobian(self, y) -> np.ndarray:
        if self._at is None or not np.array_equal(self._at, y):
            self.residual(y)
        return self._jacobian


def _beta_covariance(recs, x, s2: float) -> np.ndarray:
    X, _, _ = _stacked(recs, x)
    return s2 * np.linalg.pinv(X.T @ X)


def _physical(recs, x) -> bool:
    """Positive rigid and slosh masses and lags off the edges of :data:`LAG_RANGE`."""
    _, beta = _projected(recs, x)
    inside = all(LAG_RANGE[0] + LAG_GRID_STEP < t < LAG_RANGE[1] - LAG_GRID_STEP for t in x[2:])
    return bool(beta[0] > 0 and beta[1] > 0 and inside)


def _batch_costs(A: np.ndarray, B: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Per row ``k`` of ``A`` and ``B`` (or ``A`` one row for all), the residual sum of
    squares of the least-squares fit ``F ~ M A[k] + m B[k] + c``, infinite where ``M`` or
    ``m`` is not positive: the normal equations of the column-scaled design, every row at
    once."""
    A = np.broadcast_to(A, B.shape)
    sa, sb = A.sum(1), B.sum(1)
    ab = np.einsum("ij,ij->i", A, B)
    G = np.stack([np.stack([np.einsum("ij,ij->i", A, A), ab, sa], -1),
                  np.stack([ab, np.einsum("ij,ij->i", B, B), sb], -1),
                  np.stack([sa, sb, np.full_like(sa, F.size)], -1)], 1)
    h = np.stack([A @ F, B @ F, np.full_like(sa, F.sum())], -1)
    scale = np.sqrt(np.einsum("kii->ki", G))
    scale[scale == 0] = 1.0
    Gn = G / (scale[:, :, None] * scale[:, None, :])
    coef = np.einsum("kij,kj->ki", np.linalg.pinv(Gn), h / scale) / scale
    cost = float(F @ F) - np.einsum("ki,ki->k", coef, h)  # r.r at the optimum
    return np.where((coef[:, 0] > 0) & (coef[:, 1] > 0), cost, np.inf)


def _lag_profile(recs, x0: np.ndarray) -> np.ndarray:
    """Per record, the lag on a grid over :data:`LAG_RANGE` where the projected objective
    (the others at ``x0``) is lowest among lags with positive masses (``x0``'s lag when
    none has): a drive near one frequency also fits half a period off with the masses'
    signs flipped. Every lag of the grid at once: one filter over the stacked shifted
    accelerations."""
    from scipy.signal import lfilter

    grid = np.arange(LAG_RANGE[0], LAG_RANGE[1] + 0.5 * LAG_GRID_STEP, LAG_GRID_STEP)
    omega, zeta = math.exp(x0[0]), math.exp(x0[1])
    lags = np.array(x0[2:], float)
    for i, rec in enumerate(recs):
        t, keep = rec.time, rec.keep
        A = np.asarray(rec.acceleration(np.clip(t[None, :] - grid[:, None], t[0], t[-1])),
                       float)
        num, den, _, _ = _coefficients(omega, zeta, float(t[1] - t[0]))
        B = lfilter(num, den, A - A[:, :1], axis=1) + A[:, :1]
        cost = _batch_costs(A[:, keep], B[:, keep], rec.force[keep])
        if np.isfinite(cost).any():
            lags[i] = grid[int(np.argmin(cost))]
    return lags


def _frequency_profile(recs, low_hz: float, high_hz: float) -> float | None:
    """The frequency [Hz] on a log grid over ``[low_hz, high_hz]`` (steps of
    :data:`PROFILE_STEP`, damping ratios :data:`PROFILE_ZETAS`, lags zero) where the
    records' summed projected objective (each record its own masses) is lowest among points
    with positive masses in every record; ``None`` when no point has them. A start that
    does not depend on the prediction or the force spectrum: a large swing makes the
    linear objective bumpy, and a search from either may end in a minimum with a negative
    slosh mass."""
    from scipy.signal import lfilter

    if not high_hz > low_hz > 0:
        return None
    freqs = np.exp(np.arange(math.log(low_hz), math.log(high_hz), PROFILE_STEP))
    f, z = (g.ravel() for g in np.meshgrid(freqs, PROFILE_ZETAS))
    total = np.zeros(f.size)
    for rec in recs:
        t, keep = rec.time, rec.keep
        a = rec.acceleration_at(0.0)[0]
        num, den, _, _ = _coefficients(2 * math.pi * f, z, float(t[1] - t[0]))
        B = np.empty((f.size, a.size))
        for k in range(f.size):
            B[k] = lfilter(num[:, k], den[:, k], a - a[0])
        total += _batch_costs(a[keep], B[:, keep] + a[0], rec.force[keep])
    if not np.isfinite(total).any():
        return None
    return float(f[int(np.argmin(total))])
