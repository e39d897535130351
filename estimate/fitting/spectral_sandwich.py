"""The middle of the parameters' sandwich covariance from the noise spectra of the measured
channels, read where the fit's nuisance variables did not absorb the noise.

A fit whose carriage motion is estimated (hundreds of spline coefficients) explains part of
the force noise by motion inside the band the spline spans: there the residuals hold a small
fraction of the noise (a 60 s, 500 Hz record from a transducer with coloured noise: 1e-3 to
1e-1 of it between 1.7 and 5.4 Hz). That band is where the slosh parameters' information
lives, so any middle read from the residuals (lag-0 or Newey-West) understates the spread of
the estimates: on 41 such records driven by a sine, the masses' 95 % intervals covered the
truth 32-33 times (z-scores' spread 1.48). The noise is still in the estimates, which move
with it as ``X J^T n`` (``J`` the residuals' sensitivity with the nuisance re-estimated,
``X`` the inverse information); their variance needs the noise spectrum ``S(f)``:
``Omega = sum_k J_k^H S_k J_k / N`` over the discrete Fourier transform of ``J``'s rows.

``S`` is read from the residuals' spectrum divided by the fit's own transfer of white noise:
unit white noise put through the Gauss-Newton step (one solve with the factorised KKT
matrix each, :data:`PROBES` of them) leaves ``g(f)`` of its spectrum; where
``g >= G_MIN`` the residual spectrum over ``g`` estimates ``S``. A smooth noise model is
fitted to those estimates (white, or white plus a power law when the data demand it: a
transducer's 1/f noise) and carries ``S`` across the band where the fit absorbed most.
Channels are taken as independent of each other (their cross-spectra are left to the
Newey-West middle of :func:`estimate.fitting.covariance.robust_covariance`).
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, signal
from scipy.ndimage import median_filter

__all__ = ["G_MIN", "spectral_middle"]

#: The share of white noise the fit must leave in the residuals at a frequency for the
#: residual spectrum there to be read as the noise's.
G_MIN = 0.5
#: White-noise probes put through the fit's Gauss-Newton step.
PROBES = 4
#: The noise model is fitted up to this many times the frequency below which the
#: parameters' sensitivities hold 99 % of their energy (and over at least MIN_BINS bins).
TOP_FACTOR = 4.0
MIN_BINS = 16
#: The F statistic (2 and many degrees of freedom, 0.1 %) a coloured noise model must
#: exceed over a white one.
COLOUR_F = 7.0


def spectral_middle(J: np.ndarray, e: np.ndarray, samples: list[np.ndarray], step,
                    bands: list[float] | None = None) -> np.ndarray:
    """``Omega`` (parameters x parameters, scaled) of the residuals' sensitivity ``J``
    (residuals x parameters, nuisance re-estimated) from the noise spectra of each case's
    channels. ``samples`` as for :func:`estimate.fitting.covariance.robust_covariance`
    (per case, each residual row's sample index; -1 for the displacement's rows, which form
    one channel in sample order); ``step(w)`` the change ``J_e dw`` of residuals ``w`` by
    the Gauss-Newton step ``dw`` of all variables from them
    (:meth:`estimate.fitting.covariance.ReducedKKT.step`). ``bands``, per case, the
    highest frequency (cycles per sample; default 0.5, Nyquist) at which its records hold
    the noise as it came: a decimated record's anti-alias filter takes the noise away above
    :data:`estimate.data.decimation.FLAT`, and a noise model fitted there would read that
    fall as coloured noise rising towards the slosh band (a 6 s record decimated by 2 to 5:
    the masses' intervals 2.4-6.8 times the Gauss-Newton ones)."""
    p = J.shape[1]
    rng = np.random.default_rng(0)
    live = np.any(J != 0, axis=1) | (e != 0)
    probes = []
    for _ in range(PROBES):
        w = np.where(live, rng.normal(size=e.size), 0.0)
        probes.append(w + step(w))
    omega = np.zeros((p, p))
    start = 0
    for i, idx in enumerate(samples):
        idx = np.asarray(idx, int)
        rows = np.arange(start, start + idx.size)
        start += idx.size
        band = 0.5 if bands is None else float(bands[i])
        for ch_rows in _channels(idx):
            r = rows[ch_rows]
            omega += _channel_middle(J[r], e[r], [q[r] for q in probes], live[r], band)
    return 0.5 * (omega + omega.T)


def _channels(idx: np.ndarray) -> list[np.ndarray]:
    """Row positions (within a case) of each channel, in sample order: the measured
    channels' rows repeat the sample indices 0..n-1 once per channel; the displacement's
    (-1) are one channel."""
    out = []
    meas = np.flatnonzero(idx >= 0)
    if meas.size:
        n = int(idx[meas].max()) + 1
        for c in range(meas.size // n):
            block = meas[c * n:(c + 1) * n]
            out.append(block[np.argsort(idx[block], kind="stable")])
    disp = np.flatnonzero(idx < 0)
    if disp.size:
        out.append(disp)
    return out


def _channel_middle(J: np.ndarray, e: np.ndarray, probes: list[np.ndarray], live: np.ndarray,
                    band: float = 0.5) -> np.ndarray:
    """One channel's ``sum_k J_k^H S_k J_k / N`` (see the module), its noise read at most up
    to ``band`` (cycles per sample)."""
    N, p = J.shape
    if N < 64 or not live.any():
        return np.zeros((p, p))
    nper = int(max(64, min(2048, N // 8)))
    f, P = _psd(np.vstack([e, *probes]), nper)
    Pe = P[0]
    # unit white noise on the live rows has the density mean(live): g is the share left
    g = P[1:].mean(axis=0) / float(np.mean(live))
    Jh = np.fft.fft(J, axis=0)
    fk = np.fft.fftfreq(N)
    top = min(band, max(TOP_FACTOR * _energy_edge(Jh, fk), MIN_BINS / nper))
    use = (g >= G_MIN) & (f > 0) & (f <= top)
    if np.count_nonzero(use) < MIN_BINS:
        use = (g >= G_MIN) & (f > 0) & (f <= band)
    if np.count_nonzero(use) < 4:
        return np.zeros((p, p))
    segments = max((N - nper) // (nper // 2) + 1, 1)
    model = _noise_model(f[use], Pe[use] / g[use], top, 2.0 * segments)
    Sk = model(np.maximum(np.abs(fk), float(f[use].min())))
    return ((Jh.conj().T * Sk) @ Jh).real / N


def _energy_edge(Jh: np.ndarray, fk: np.ndarray) -> float:
    """The frequency (cycles per sample) below which 99 % of every column's energy lies."""
    energy = np.abs(Jh) ** 2
    total = energy.sum(axis=0)
    energy = energy[:, total > 0] / total[total > 0]
    if energy.size == 0:
        return 0.5
    order = np.argsort(np.abs(fk))
    share = np.cumsum(energy[order].sum(axis=1)) / energy.shape[1]
    return float(np.abs(fk)[order][min(np.searchsorted(share, 0.99), fk.size - 1)])


def _noise_model(f: np.ndarray, S: np.ndarray, top: float, dof: float):
    """A smooth density fitted to the estimates ``S`` at ``f`` (cycles per sample) in the
    log domain: white (a constant) unless white plus a power law ``a + b (f / top)^-alpha``
    (``alpha`` in [0, 2.5]: 1/f-like, drifting) fits significantly better (an F-test on the
    log residuals at 0.1 %, a few estimates cannot make a short record's noise coloured).
    Lines (estimates 4 robust deviations above a running median) are left out. The log of a
    Welch estimate with ``dof`` degrees of freedom is low by about ``1 / dof`` on average,
    which is put back."""
    y = np.log(np.maximum(S, 1e-300))
    med = median_filter(y, size=min(7, y.size // 2 * 2 - 1), mode="nearest")
    keep = y - med < 4 * (1.4826 * np.median(np.abs(y - med)) + 1e-12)
    lx, y = np.log(f[keep] / top), y[keep]
    white = float(np.mean(y))

    def flat(ff):
        return np.full(np.shape(ff), np.exp(white + 1.0 / dof))

    ssr_white = float(np.sum((y - white) ** 2))
    n = y.size
    # no slope in log-log at 5 %: white, without the power law's fit
    slope = np.polyfit(lx, y, 1, full=True)[1]
    ssr_slope = float(slope[0]) if slope.size else ssr_white
    if n <= 6 or (ssr_white - ssr_slope) < 3.84 * ssr_slope / (n - 2):
        return flat

    def log_model(q, logx):
        return np.logaddexp(q[0], q[1] - q[2] * logx)

    def jacobian(q):
        m = log_model(q, lx)
        coloured = np.exp(q[1] - q[2] * lx - m)
        return np.column_stack([np.exp(q[0] - m), coloured, -lx * coloured])

    fitted = optimize.least_squares(lambda q: log_model(q, lx) - y, [white, white - 3.0, 1.0],
                                    jac=jacobian,
                                    bounds=([-np.inf, -np.inf, 0.0], [np.inf, np.inf, 2.5]))
    ssr_power = float(2 * fitted.cost)
    coloured = (ssr_white - ssr_power) / 2 > COLOUR_F * ssr_power / (n - 3)
    if not coloured:
        return flat
    q = fitted.x
    return lambda ff: np.exp(log_model(q, np.log(ff / top)) + 1.0 / dof)


def _psd(x: np.ndarray, nper: int) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided Welch spectral density (per sample: its mean over the frequencies is the
    variance) of ``x`` (each row of it) at ascending frequencies (cycles per sample)."""
    f, P = signal.welch(x, fs=1.0, nperseg=nper, return_onesided=False, detrend="constant",
                        axis=-1)
    o = np.argsort(f)
    return f[o], P[..., o]
