"""Checks of the real-rig record generator (tests/reference_rig_records.py) against
independent facts: finite differences of its motions, the sensor filter's DC gain and group
delay, the quantisation grid, and the cylinder's first mode against the project's tank
modal analysis (two independent derivations of the same physics)."""

import math

import numpy as np
import pytest
import reference_models as ref
import reference_rig_records as rr


def _fd_check(motion, t):
    x, xd, xdd = motion(t)
    h = t[1] - t[0]
    # central differences of the analytic x and xd: O(h^2) error, h = 1e-5 s
    assert np.allclose(np.gradient(x, h)[1:-1], xd[1:-1], atol=1e-6 * np.max(np.abs(xd)) + 1e-12)
    assert np.allclose(np.gradient(xd, h)[1:-1], xdd[1:-1], atol=1e-5 * np.max(np.abs(xdd)) + 1e-9)


def test_transport_move_is_rest_to_rest_with_consistent_derivatives():
    move = rr.TransportMove(distance=0.45, duration=0.7, start=0.5)
    x, xd, xdd = move(np.array([0.0, 0.5, 1.2, 3.0]))
    assert x[0] == x[1] == 0 and x[2] == pytest.approx(0.45) and x[3] == pytest.approx(0.45)
    assert np.all(xd[[0, 1, 3]] == 0) and np.all(xdd[[0, 1, 3]] == 0)
    _fd_check(move, np.arange(0.4, 1.3, 1e-5))
    # peak acceleration of the septic profile: 7.513 D / T^2 (s'' max at u = 0.2764)
    assert np.max(np.abs(move(np.linspace(0.5, 1.2, 20001))[2])) == pytest.approx(
        7.5132 * 0.45 / 0.7**2, rel=1e-3)


def test_servo_follow_derivatives_and_lag():
    move = rr.TransportMove(0.3, 0.8, start=0.2)
    servo = rr.ServoFollow(move, lag=0.015, ripple=3e-5, ripple_frequency=21.0)
    _fd_check(servo, np.arange(0.1, 1.2, 1e-5))
    t = np.linspace(0, 2, 2001)
    assert np.allclose(rr.ServoFollow(move, lag=0.015)(t)[0], move(t - 0.015)[0])


def test_force_sensor_gain_delay_quantisation_and_coloured_noise():
    rng = np.random.default_rng(3)
    t = np.arange(0, 20, 0.002)
    f0 = 1.5
    clean = np.sin(2 * np.pi * f0 * t)
    quiet = rr.force_sensor(t, clean, rng=rng, quantum=0.0, white=0, pink=0, lines=(), offset=0)
    # a 2nd-order low-pass at 60 Hz passes 1.5 Hz with gain 1 (to 1e-3) and delays it by
    # 2 zeta / omega_c (phase -atan(2 zeta w wc / (wc^2 - w^2)) ~ -w * 2 zeta / wc)
    tail = t > 2
    A = np.column_stack([np.sin(2 * np.pi * f0 * t[tail]), np.cos(2 * np.pi * f0 * t[tail])])
    (a, b), *_ = np.linalg.lstsq(A, quiet[tail], rcond=None)
    assert math.hypot(a, b) == pytest.approx(1.0, abs=1e-3)
    delay = -math.atan2(b, a) / (2 * np.pi * f0)
    assert delay == pytest.approx(rr.sensor_group_delay(60.0), rel=0.02)
    rec = rr.force_sensor(t, clean, rng=rng, quantum=0.005)
    assert np.allclose(rec / 0.005, np.round(rec / 0.005))
    # the noise above the filter is far below the noise in the slosh band
    from scipy import signal
    f, p = signal.welch(rec - quiet, fs=500, nperseg=1024)
    assert np.median(p[(f > 2) & (f < 10)]) > 30 * np.median(p[f > 150])


def test_receive_times_are_increasing_and_within_the_jitter():
    rng = np.random.default_rng(0)
    t = np.arange(5000) * 0.002
    s = rr.receive_times(t, jitter=1e-3, rng=rng)
    assert np.all(np.diff(s) > 0)
    assert np.max(np.abs(s - t)) <= 1e-3 + 2e-6
    assert np.std(np.diff(s)) > 2e-4  # really jittered


@pytest.mark.parametrize("radius, depth", [(0.05, 0.06), (0.5, 0.9)])
def test_cylinder_first_mode_matches_the_tank_modal_analysis(radius, depth):
    from analogs.tank import Cylinder, Liquid, predict

    mine = rr.cylinder_first_mode(radius, depth)
    pred = predict(Cylinder(radius, length=2 * depth), fill=0.5,
                   liquid=Liquid(density=998.2, viscosity=1e-6), modes=1)
    mode = pred.modes[0]
    # both are the potential-flow solution; the modal analysis is numerical (Ritz): 0.5 %
    assert mine["frequency"] == pytest.approx(mode.frequency_hz, rel=5e-3)
    assert mine["mass"] == pytest.approx(mode.mass, rel=5e-3)
    assert mine["liquid_mass"] == pytest.approx(pred.liquid_mass, rel=1e-6)


def test_a_transport_record_end_to_end_has_the_stated_lag():
    """A whole record: the lag between the true motion and the recorded force is the stream
    delay plus the sensor's group delay (cross-check against the reference simulator)."""
    rng = np.random.default_rng(1)
    t = np.arange(0, 6, 0.002)
    move = rr.TransportMove(0.4, 0.8, start=1.0)
    sim = ref.simulate_lateral(t, move, fixed_mass=2.0, dry_mass=1.0, sensor_delay=0.02)
    rec = rr.force_sensor(t, sim["force_clean"], rng=rng, quantum=0, white=0, pink=0, lines=(),
                          offset=0)
    lag = 0.02 + rr.sensor_group_delay(60.0)
    expected = 3.0 * move(t - lag)[2]
    assert np.max(np.abs(rec - expected)) < 0.02 * np.max(np.abs(expected))
