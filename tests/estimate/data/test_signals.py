"""Tests of `estimate.data.signals` against analytic references.

Reference records: 30 s at 100 Hz (3001 samples), like the seed's tests. The displacement noise
(2e-5 m) and drive (1.855 Hz, 7.5 mm) match the estimation notes' calibration case.

Tolerances and why
------------------
* Acceleration: with white displacement noise of standard deviation s at rate fs, a zero-phase
  low-pass of cutoff fc leaves acceleration noise of about
  sqrt((2 pi)^4 (2 s^2 / fs) fc^5 / 5) = 1.6e-3 m/s^2 at fc = 4 Hz, 0.16% of the 1.02 m/s^2
  amplitude. RMS error is required below 0.5% of the amplitude (3x margin for the filter's
  finite roll-off and the noise draw); the worst error in the first and last 0.5 s below 2%
  (the notes report 0.44 m/s^2 = 43% for plain `sosfiltfilt`, which the test confirms).
* Phase: the fitted phase of the acceleration must equal the analytic one within 1e-3 rad
  (0.09 ms at 1.855 Hz, 1% of one 10 ms sample): a causal filter would lag by many ms.
* Frequency: refined peaks within 1e-4 relative (the requirement is 0.1%; a least-squares
  sinusoid fit over 30 s with 1% noise is good to ~1e-5).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from estimate.data.signals import (
    DriveCheck,
    check_drive_frequency,
    displacement_derivatives,
    dominant_frequency,
    find_spectral_peaks,
    lowpass,
    welch_spectrum,
)

FS = 100.0
T = np.arange(3001) / FS
F_DRIVE = 1.855
W = 2 * np.pi * F_DRIVE
AMP = 0.0075
PHASE = 0.7
NOISE = 2e-5

ACC_RMS_RTOL = 5e-3
ACC_END_RTOL = 2e-2
PHASE_TOL = 1e-3
FREQ_RTOL = 1e-4


def _noisy_sine(seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = AMP * np.sin(W * T + PHASE)
    acc = -(W**2) * x
    noisy = x + np.random.default_rng(seed).normal(0.0, NOISE, T.size)
    return noisy, x, acc


def _phase_at(t: np.ndarray, y: np.ndarray, f: float) -> float:
    a = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
    (s, c, _), *_ = np.linalg.lstsq(a, y, rcond=None)
    return float(np.arctan2(c, s))


def _ends(e: np.ndarray, seconds: float = 0.5) -> np.ndarray:
    n = int(seconds * FS)
    return np.r_[e[:n], e[-n:]]


# ---------------------------------------------------------------------------------------------
# derivatives


@pytest.mark.parametrize("method", ["butterworth", "savgol"])
@pytest.mark.parametrize("seed", [1, 2])
def test_acceleration_of_noisy_sine(method: str, seed: int) -> None:
    noisy, x, acc = _noisy_sine(seed)
    xs, xd, xdd = displacement_derivatives(T, noisy, method=method)
    amp_acc = W**2 * AMP
    err = xdd - acc
    assert np.sqrt(np.mean(err**2)) < ACC_RMS_RTOL * amp_acc
    assert np.max(np.abs(_ends(err))) < ACC_END_RTOL * amp_acc
    vel = W * AMP * np.cos(W * T + PHASE)
    assert np.sqrt(np.mean((xd - vel) ** 2)) < ACC_RMS_RTOL * W * AMP
    assert np.sqrt(np.mean((xs - x) ** 2)) < NOISE  # smoothing reduces the noise
    # zero phase lag
    assert abs(_phase_at(T, xdd, F_DRIVE) - _phase_at(T, acc, F_DRIVE)) < PHASE_TOL


def test_plain_filtfilt_has_the_end_error_we_avoid() -> None:
    """The estimation notes' failure: odd padding + differentiation wrecks the ends."""
    noisy, _, acc = _noisy_sine()
    sos = signal.butter(4, 5.0, output="sos", fs=FS)
    naive = np.gradient(np.gradient(signal.sosfiltfilt(sos, noisy), T), T)
    _, _, xdd = displacement_derivatives(T, noisy, cutoff_hz=5.0)
    naive_end = np.max(np.abs(_ends(naive - acc)))
    ours_end = np.max(np.abs(_ends(xdd - acc)))
    assert naive_end > 0.1 * W**2 * AMP
    assert ours_end < naive_end / 20


def test_crank_motion_with_harmonic() -> None:
    """A crank's displacement has a 2nd harmonic; its acceleration must be kept too."""
    r, rod, phi0 = 0.01, 0.15, 0.4
    phi = phi0 + W * T
    x = r * np.cos(phi) + np.sqrt(rod**2 - r**2 * np.sin(phi) ** 2) - rod
    # analytic second derivative (constant dphi/dt = W)
    s = np.sqrt(rod**2 - r**2 * np.sin(phi) ** 2)
    g = r**2 * np.sin(phi) * np.cos(phi)
    dg = r**2 * np.cos(2 * phi)
    acc = W**2 * (-r * np.cos(phi) - dg / s - g**2 / s**3)
    noisy = x + np.random.default_rng(5).normal(0.0, NOISE, T.size)
    _, _, xdd = displacement_derivatives(T, noisy)
    scale = W**2 * r
    err = xdd - acc
    assert np.sqrt(np.mean(err**2)) < ACC_RMS_RTOL * scale
    assert np.max(np.abs(_ends(err))) < ACC_END_RTOL * scale


def test_frequency_sweep_displacement() -> None:
    """A 1-3 Hz linear chirp: the end models must follow the local frequency."""
    f0, f1, dur = 1.0, 3.0, T[-1]
    phase = 2 * np.pi * (f0 * T + 0.5 * (f1 - f0) * T**2 / dur)
    x = 0.005 * np.sin(phase)
    fdot = 2 * np.pi * (f1 - f0) / dur
    wt = 2 * np.pi * (f0 + (f1 - f0) * T / dur)
    acc = -0.005 * wt**2 * np.sin(phase) + 0.005 * fdot * np.cos(phase)
    noisy = x + np.random.default_rng(3).normal(0.0, NOISE, T.size)
    _, _, xdd = displacement_derivatives(T, noisy, cutoff_hz=6.0)
    scale = 0.005 * (2 * np.pi * f1) ** 2
    err = xdd - acc
    assert np.sqrt(np.mean(err**2)) < ACC_RMS_RTOL * scale
    assert np.max(np.abs(_ends(err))) < ACC_END_RTOL * scale


def test_derivative_errors() -> None:
    noisy, _, _ = _noisy_sine()
    with pytest.raises(ValueError, match=r'expected `method` "butterworth" or "savgol", found'):
        displacement_derivatives(T, noisy, method="spline")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"expected 0 < `cutoff_hz` < Nyquist frequency 50 Hz"):
        displacement_derivatives(T, noisy, cutoff_hz=80.0)
    with pytest.raises(ValueError, match=r"expected an odd `window`"):
        displacement_derivatives(T, noisy, method="savgol", window=20)
    # a carriage at rest is no error: any cutoff keeps a constant position
    rest = displacement_derivatives(T, np.full_like(T, 0.003))
    assert np.allclose(rest[0], 0.003, atol=1e-12) and np.allclose(rest[1:], 0.0, atol=1e-9)
    bad_t = T.copy()
    bad_t[100:] += 0.01
    with pytest.raises(ValueError, match=r"expected uniformly sampled, strictly increasing `time`"):
        displacement_derivatives(bad_t, noisy)
    with pytest.raises(ValueError, match=r"expected 1-D `time` and `displacement` of equal length"):
        displacement_derivatives(T, noisy[:-1])
    nan = noisy.copy()
    nan[7] = np.nan
    with pytest.raises(ValueError, match=r"expected finite `time` and `displacement`"):
        displacement_derivatives(T, nan)


def test_inputs_not_modified() -> None:
    noisy, _, _ = _noisy_sine()
    copy = noisy.copy()
    displacement_derivatives(T, noisy)
    lowpass(T, noisy)
    np.testing.assert_array_equal(noisy, copy)


# ---------------------------------------------------------------------------------------------
# low-pass


@pytest.mark.parametrize("ends", ["extend", "odd"])
def test_lowpass_zero_phase_and_gain(ends: str) -> None:
    clean = np.sin(W * T + PHASE)
    y = clean + 0.2 * np.sin(2 * np.pi * 30.0 * T) + np.random.default_rng(0).normal(0, 0.01, T.size)
    out = lowpass(T, y, ends=ends)  # default 10 Hz, as the seed
    assert abs(_phase_at(T, out, F_DRIVE) - PHASE) < PHASE_TOL
    # 0.01 white noise keeps sqrt(10/50) of its variance below 10 Hz: std 0.0045
    interior = slice(100, -100)
    assert np.sqrt(np.mean((out - clean)[interior] ** 2)) < 0.006
    assert np.max(np.abs(out - clean)[interior]) < 0.03  # ~6 sigma
    if ends == "extend":
        assert np.max(np.abs(out - clean)) < 0.03


def test_lowpass_errors() -> None:
    with pytest.raises(ValueError, match=r"expected 0 < `cutoff_hz` < Nyquist frequency 50 Hz, "
                                         r"found 60.0"):
        lowpass(T, np.sin(T), cutoff_hz=60.0)
    with pytest.raises(ValueError, match=r'expected `ends` "extend" or "odd", found \'even\''):
        lowpass(T, np.sin(T), ends="even")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"expected at least 16 samples, found 10"):
        lowpass(T[:10], np.sin(T[:10]))


# ---------------------------------------------------------------------------------------------
# spectra


def test_welch_peak_at_known_frequency() -> None:
    y = 3.0 * np.sin(2 * np.pi * 2.0 * T) + np.random.default_rng(0).normal(0, 0.03, T.size)
    spec = welch_spectrum(T, y)
    assert spec.resolution == pytest.approx(FS / 1500)
    assert abs(spec.frequency[np.argmax(spec.psd)] - 2.0) <= spec.resolution
    # Parseval: the PSD integrates to the variance
    assert np.sum(spec.psd) * spec.resolution == pytest.approx(np.var(y), rel=0.05)


def test_peaks_refined_frequency_and_amplitude() -> None:
    rng = np.random.default_rng(4)
    y = (2.0 * np.sin(2 * np.pi * 1.855 * T + 0.3) + 0.3 * np.sin(2 * np.pi * 2.12 * T)
         + 0.1 * np.sin(2 * np.pi * 3.71 * T + 1.0) + rng.normal(0, 0.02, T.size))
    peaks = find_spectral_peaks(T, y)
    assert len(peaks) >= 3
    got = {round(p.frequency, 2): p for p in peaks[:3]}
    for f, a in [(1.855, 2.0), (2.12, 0.3), (3.71, 0.1)]:
        p = min(peaks[:3], key=lambda q: abs(q.frequency - f))
        assert p.frequency == pytest.approx(f, rel=FREQ_RTOL), got
        assert p.amplitude == pytest.approx(a, rel=0.02)
    assert peaks[0].psd >= peaks[1].psd >= peaks[2].psd


def test_dominant_frequency_finds_drive_to_one_in_1e4() -> None:
    for f in (1.66, 1.855, 1.953, 2.343, 2.637):  # the seed's test frequencies
        y = np.sin(2 * np.pi * f * T + 0.5) + np.random.default_rng(0).normal(0, 0.01, T.size)
        assert dominant_frequency(T, y) == pytest.approx(f, rel=FREQ_RTOL)


def test_dominant_frequency_of_constant_signal() -> None:
    with pytest.raises(ValueError, match=r"no spectral peak found between 0.1 Hz to Nyquist"):
        dominant_frequency(T, np.ones_like(T))


# ---------------------------------------------------------------------------------------------
# drive check


def test_drive_check_passes_within_tolerance() -> None:
    force = 4.0 * np.sin(2 * np.pi * 1.87 * T) + np.random.default_rng(0).normal(0, 0.06, T.size)
    check = check_drive_frequency(T, force, 1.855)
    assert isinstance(check, DriveCheck) and check.passed and bool(check)
    assert check.measured_frequency == pytest.approx(1.87, rel=FREQ_RTOL)
    assert check.relative_error == pytest.approx(0.015 / 1.855, rel=1e-2)
    assert check.tolerance == 0.015 and check.drive_frequency == 1.855
    assert "matches the drive frequency 1.8550 Hz: difference 0.81%" in check.message


def test_drive_check_fails_outside_tolerance() -> None:
    force = 4.0 * np.sin(2 * np.pi * 1.90 * T)  # 2.4% above the drive
    check = check_drive_frequency(T, force, 1.855)
    assert not check.passed and not bool(check)
    assert check.relative_error == pytest.approx(0.045 / 1.855, rel=1e-3)
    assert "does NOT match" in check.message and "tolerance 1.50%" in check.message


def test_drive_check_boundary_and_errors() -> None:
    force = np.sin(2 * np.pi * 1.855 * 1.014 * T)
    assert check_drive_frequency(T, force, 1.855).passed
    assert not check_drive_frequency(T, force, 1.855, tolerance=0.01).passed
    with pytest.raises(ValueError, match=r"expected a positive `drive_frequency` in Hz, found 0"):
        check_drive_frequency(T, force, 0)


def test_vectorised_linear_detrend_matches_scipy():
    """The noise analysis's all-segments-at-once linear detrend is SciPy's per segment
    (``signal.detrend(type="linear")``) to rounding."""
    from estimate.data.signals.noise import _linear_detrend

    segments = np.random.default_rng(4).normal(size=(7, 256)) + np.linspace(0, 3, 256)
    assert np.allclose(_linear_detrend(segments), signal.detrend(segments, type="linear"),
                       rtol=0, atol=1e-12)
