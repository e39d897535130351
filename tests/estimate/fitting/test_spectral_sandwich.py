"""The robust covariance's spectral floor: a nuisance that absorbs the noise in the band where
the parameter's information lives (as an estimated carriage motion does) must not make the
robust standard error optimistic. Reference: the exact variance of the linear estimator
under the known noise covariance."""

import functools

import numpy as np
import scipy.sparse as sps
from scipy.linalg import toeplitz

from estimate.fitting.covariance import ReducedKKT
from estimate.fitting.spectral_sandwich import spectral_middle


@functools.lru_cache(maxsize=1)
def _coloured_covariance(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Covariance of unit white noise plus a 1/f noise whose density in the band
    (0.02-0.06 cycles per sample) is 10-30 times the white's, as a transducer's 1/f noise
    is in the slosh band over its filtered white noise; and its Cholesky factor."""
    m = 16 * n
    f = np.abs(np.fft.fftfreq(m))
    density = 0.6 / np.maximum(f, 1.0 / m)
    gamma = np.fft.ifft(density).real[:n]
    cov = toeplitz(gamma) + np.eye(n)
    return cov, np.linalg.cholesky(cov)


def _errors_in_variables(seed: int):
    """A linear errors-in-variables problem like a fit with an estimated carriage motion:
    ``force = theta a(t) + B c + n`` with ``a`` (a decaying transient and a sinusoid) inside
    the band of the nuisance basis ``B`` (sinusoids at every other frequency of the band,
    as a spline spans a band without spanning every signal in it), and a ``displacement``
    channel ``0.25 B c + white`` that alone pins ``c``. The force rows are weighed as if
    their noise were white, but it is :func:`_coloured_covariance`: strong in the band, so
    the nuisance absorbs most of it there. Returns (the spectral sandwich's standard error, the
    Gauss-Newton standard error, the exact standard deviation) of ``theta``."""
    n = 2048
    t = np.arange(n)
    freqs = np.arange(40, 120, 2) / n  # the band: 0.02-0.06 cycles per sample
    B = np.hstack([np.cos(2 * np.pi * np.outer(t, freqs)), np.sin(2 * np.pi * np.outer(t, freqs))])
    a = (np.cos(2 * np.pi * 60.5 / n * t) * np.exp(-t / 600)
         + 0.5 * np.sin(2 * np.pi * 90.5 / n * t))
    J = np.block([[a[:, None], B], [np.zeros((n, 1)), 0.25 * B]])
    Sigma_f, factor = _coloured_covariance(n)
    rng = np.random.default_rng(seed)
    nf = factor @ rng.normal(size=n)
    nd = rng.normal(size=n)
    y = np.r_[nf, nd]  # truth theta = 0, c = 0: the data are the noise
    sol, *_ = np.linalg.lstsq(J, y, rcond=None)
    e = J @ sol - y
    # the exact variance of theta-hat = h^T y over the noise
    h = np.linalg.pinv(J)[0]
    exact = np.sqrt(h[:n] @ Sigma_f @ h[:n] + h[n:] @ h[n:])
    kkt = ReducedKKT(sps.csc_matrix(J), sps.csc_matrix((0, J.shape[1])), 1)
    X = kkt.inverse_information
    middle = spectral_middle(kkt.effective_jacobian(), e, [np.r_[t, np.full(n, -1)]],
                             lambda w: kkt.Je @ kkt.step(w))
    sigma2 = float(e @ e) / (e.size - J.shape[1])
    return float(np.sqrt(X @ middle @ X)[0, 0]), float(np.sqrt(sigma2 * X[0, 0])), exact


def test_the_spectral_middle_gives_the_exact_variance():
    """Over eight noise draws the spectral sandwich's standard error is within -10 % / +20 %
    of the exact one (measured 0.96-1.04 while building this test: one record's spectrum,
    and its 1/f fit across the absorbed band). Without the white-noise probes' correction
    the absorbed band reads as a quiet one (0.82-0.90 on five draws); the Gauss-Newton
    error, which takes the noise as white, is 0.57-0.97."""
    for seed in range(8):
        spectral, gn, exact = _errors_in_variables(seed)
        assert 0.9 * exact <= spectral <= 1.2 * exact, (seed, spectral / exact, gn / exact)
