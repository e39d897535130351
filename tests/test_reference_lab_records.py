"""The lab-record generator against hand calculations: the integrated accelerometer, the
free decay's swing and the window's cut."""

import math

import numpy as np
import pytest
import reference_lab_records as lab


def test_integrated_displacement_drifts_as_its_bias_says():
    """Without noise the double integral of a bias b is b t^2 / 2 (trapezoid rule: exact
    for a constant); the second difference of the trapezoid rule applied twice is the
    acceleration averaged as ``(a[i-1] + 2 a[i] + a[i+1]) / 4``, exactly."""
    t = np.arange(1001) / 100.0
    acc = np.sin(2 * np.pi * 1.5 * t)
    x = lab.integrated_displacement(t, acc, rng=np.random.default_rng(0), bias=0.0, noise=0.0)
    second = np.diff(x, 2) / 0.01**2
    assert second == pytest.approx((acc[:-2] + 2 * acc[1:-1] + acc[2:]) / 4, abs=1e-8)
    drift = lab.integrated_displacement(t, 0 * t, rng=np.random.default_rng(0), bias=0.02,
                                        noise=0.0)
    assert drift == pytest.approx(0.01 * t**2, abs=1e-12)


def test_free_decay_starts_swinging_with_the_carriage_at_rest():
    rec = lab.free_decay(lab.SMALL, duration=2.0, theta0=0.3)
    sim = rec["sim"]
    assert sim["theta"][0][0] == pytest.approx(0.3)
    assert np.all(sim["displacement_clean"] == 0.0)
    # the force is the swing's: m L thetadd cos(theta) at rest in the swing = -m g sin cos
    p = lab.SMALL
    assert sim["force_true"][0] == pytest.approx(-p.mass * lab.G * math.sin(0.3) * math.cos(0.3),
                                                  rel=1e-9)


def test_running_window_is_cut_from_the_running_test():
    rec = lab.running_window(lab.SMALL, start=10.0, window=2.0)
    assert rec["time"][0] == pytest.approx(10.0) and rec["time"][-1] == pytest.approx(12.0)
    assert abs(rec["theta0"]) > 0.02  # the liquid swings at the first sample
    assert rec["drive_hz"] == pytest.approx(0.95 * lab.SMALL.frequency)
