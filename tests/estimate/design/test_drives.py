"""Drive families: their motion, its derivatives, the frequencies they hold, and the limits.

References are independent of the CasADi expressions: SciPy splines through the sampled
displacement (their derivatives), zero crossings for the frequencies, and the rig's limits
checked on a grid 50 times finer than the drive file's.
"""

from __future__ import annotations

import numpy as np
import pytest
from design_helpers import LIMITS
from scipy.interpolate import make_interp_spline

from estimate.design import AmplitudeSteps, LinearChirp, SteadySine, SteppedSine
from estimate.design.drives import LEAD, fit_to_limits, limit_amplitude

RATE = 100.0
DRIVES = [SteadySine(LIMITS, 30.0, frequency=2.6), SteppedSine(LIMITS, 30.0, first=1.2, second=3.7),
          AmplitudeSteps(LIMITS, 30.0, frequency=0.8), LinearChirp(LIMITS, 30.0, start=5.0, end=1.0)]


@pytest.mark.parametrize("drive", DRIVES, ids=lambda d: d.family)
def test_velocity_and_acceleration_are_the_derivatives(drive):
    """CasADi's derivatives of the displacement against a quintic spline's through 2 kHz
    samples (its error there is ~(2 pi f h)^4 ~ 1e-5 of the amplitude at 5 Hz)."""
    t = np.linspace(0, drive.duration, int(drive.duration * 2000) + 1)
    x, v, a = drive.motion(t)
    spline = make_interp_spline(t, x, k=5)
    inner = slice(50, -50)
    assert np.abs(spline(t, 1) - v)[inner].max() <= 1e-4 * np.abs(v).max()
    assert np.abs(spline(t, 2) - a)[inner].max() <= 1e-3 * np.abs(a).max()


@pytest.mark.parametrize("drive", DRIVES, ids=lambda d: d.family)
def test_drives_start_and_end_at_rest(drive):
    t = np.array([0.0, LEAD, drive.duration])
    m = drive.motion(t)
    assert np.abs(m).max() < 1e-12


@pytest.mark.parametrize("drive", DRIVES, ids=lambda d: d.family)
def test_scaled_to_the_limits_and_not_beyond(drive):
    """After scaling, every peak on a grid 50 times finer than the drive file's is within
    its limit, and the tightest one within 2 % of it (the design keeps a 1 % margin)."""
    d = fit_to_limits(drive, RATE)
    t = np.linspace(0, d.duration, int(d.duration * RATE * 50) + 1)
    x, v, a = np.abs(d.motion(t)).max(axis=1)
    ratios = (x / (LIMITS.stroke / 2), v / LIMITS.velocity, a / LIMITS.acceleration)
    assert max(ratios) <= 1.0 + 1e-9
    assert max(ratios) >= 0.98


def test_limit_amplitude():
    """The largest sine amplitude: stroke-limited at low frequency, then speed, then
    acceleration (hand-derived for 100 mm, 0.3 m/s, 2 m/s^2)."""
    assert limit_amplitude(0.3, LIMITS) == pytest.approx(0.05)
    assert limit_amplitude(1.0, LIMITS) == pytest.approx(0.3 / (2 * np.pi))
    assert limit_amplitude(3.0, LIMITS) == pytest.approx(2.0 / (2 * np.pi * 3) ** 2)


def _crossings(x, t):
    """Times where ``x`` changes sign strictly (linear interpolation between samples)."""
    idx = np.nonzero(x[1:] * x[:-1] < 0)[0]
    return t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])


def test_stepped_sine_holds_its_two_frequencies():
    d = SteppedSine(LIMITS, 30.0, first=1.2, second=3.7)
    t = np.linspace(0, 30, 300001)
    x = d.motion(t)[0]
    z = _crossings(x, t)
    half = LEAD + (30 - LEAD) / 2
    for lo, hi, f in ((LEAD + 3, half - 1, 1.2), (half + 1, 27, 3.7)):
        zz = z[(z > lo) & (z < hi)]
        assert 1 / (2 * np.mean(np.diff(zz))) == pytest.approx(f, rel=1e-4)


def test_chirp_sweeps_linearly():
    """Half-periods of a linear chirp: the instantaneous frequency from zero crossings
    follows start + rate (t - lead) to 0.1 %."""
    d = LinearChirp(LIMITS, 30.0, start=1.0, end=5.0)
    t = np.linspace(0, 30, 300001)
    z = _crossings(d.motion(t)[0], t)
    mid = 0.5 * (z[1:] + z[:-1])
    f = 1 / (2 * np.diff(z))
    keep = (mid > 4) & (mid < 26)
    rate = (5.0 - 1.0) / (30 - LEAD)
    assert np.abs(f[keep] - (1.0 + rate * (mid[keep] - LEAD))).max() < 1e-3 * 5
