"""Light checks of the independent reference simulator `tests/reference_models.py`."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks

sys.path.insert(0, str(Path(__file__).parent))

from reference_models import (
    AmplitudeSteps,
    Crank,
    Friction,
    LinearSweep,
    Pendulum,
    Ramped,
    Sine,
    SteppedSweep,
    Tone,
    drive_at,
    hinge_damping,
    natural_frequency,
    simulate_lateral,
)

G = 9.80665


def _zero_crossing_frequency(t: np.ndarray, y: np.ndarray) -> float:
    """Mean frequency from linearly interpolated upward zero crossings [Hz]."""
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return (tc.size - 1) / (tc[-1] - tc[0])


@pytest.mark.parametrize("stiffness", [0.0, 0.05])
def test_free_decay_frequency(stiffness: float) -> None:
    p = Pendulum(mass=1.338, length=0.057, stiffness=stiffness)
    t = np.arange(0.0, 20.0, 0.001)  # 1 ms sampling: interpolation error << 0.1%
    out = simulate_lateral(t, Sine(0.0, 1.0), pendulums=[p], initial_theta=[1e-3])
    expected = np.sqrt(G / p.length + p.stiffness / (p.mass * p.length**2)) / (2 * np.pi)
    assert natural_frequency(p) / (2 * np.pi) == pytest.approx(expected, rel=1e-14)
    # amplitude 1e-3 rad shifts the frequency by theta0^2/16 ~ 6e-8: far below 0.1%
    assert _zero_crossing_frequency(t, out["theta"][0]) == pytest.approx(expected, rel=1e-3)


def test_damped_decay_rate_matches_damping_ratio() -> None:
    zeta = 0.02
    c = hinge_damping(1.338, 0.057, zeta)
    p = Pendulum(1.338, 0.057, damping=c)
    t = np.arange(0.0, 10.0, 0.001)
    th = simulate_lateral(t, Sine(0.0, 1.0), pendulums=[p], initial_theta=[1e-3])["theta"][0]
    pk, _ = find_peaks(th)
    delta = np.log(th[pk[0]] / th[pk[10]]) / 10  # logarithmic decrement per period
    assert delta / np.sqrt(4 * np.pi**2 + delta**2) == pytest.approx(zeta, rel=1e-3)


@pytest.mark.parametrize("excitation", [Sine(0.005, 1.855, 0.3), Crank(0.01, 0.15, 1.855, 0.04, 0.7)])
def test_rigid_tank_force_is_total_mass_times_acceleration(excitation) -> None:
    t = np.arange(0.0, 5.0, 0.01)
    out = simulate_lateral(t, excitation, fixed_mass=2.794, dry_mass=1.2)
    np.testing.assert_allclose(out["force"], (2.794 + 1.2) * out["acceleration"], rtol=1e-14,
                               atol=1e-14)
    assert out["theta"].shape == (0, t.size)


def test_sensor_delay_shifts_force() -> None:
    t = np.arange(0.0, 5.0, 0.01)
    exc = Sine(0.005, 1.855)
    out = simulate_lateral(t, exc, fixed_mass=1.0, dry_mass=1.0, sensor_delay=0.03)
    np.testing.assert_allclose(out["force"], 2.0 * exc(t - 0.03)[2], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(out["force_true"], 2.0 * exc(t)[2], rtol=1e-13, atol=1e-13)


def test_noise_tone_and_friction() -> None:
    t = np.arange(0.0, 30.0, 0.01)
    exc = Sine(0.005, 1.855)
    clean = simulate_lateral(t, exc, fixed_mass=1.0, dry_mass=1.0)
    out = simulate_lateral(t, exc, fixed_mass=1.0, dry_mass=1.0, noise=0.015, seed=3,
                           tone=Tone(0.1, 29.0), friction=Friction(0.2, 1.5))
    xd = clean["velocity"]
    mech = clean["force"] + 0.2 * np.sign(xd) + 1.5 * xd
    np.testing.assert_allclose(out["force_clean"] - 0.1 * np.sin(2 * np.pi * 29.0 * t), mech,
                               atol=1e-12)
    resid = out["force"] - out["force_clean"]
    assert np.std(resid) == pytest.approx(0.015 * np.sqrt(np.mean(mech**2)), rel=0.05)


@pytest.mark.parametrize(
    "excitation",
    [
        Crank(0.01, 0.15, 1.855, d_omega=0.04, phi0=0.7),
        LinearSweep(0.005, 1.0, 5.0, 30.0),
        SteppedSweep(0.005, (1.0, 2.0, 3.0, 4.0, 5.0), dwell=6.0, ramp=0.5),
        AmplitudeSteps((0.002, 0.004, 0.008), 2.0, dwell=10.0, ramp=0.5),
    ],
)
def test_excitation_derivatives_are_consistent(excitation) -> None:
    """Analytic derivatives against central differences (step 1e-5 s: error ~1e-9 relative)."""
    # offset grid: the linear sweep's acceleration has a slope jump exactly at 0 and 30 s
    t = np.linspace(-1.0, 31.0, 4001) + 1.234e-4
    h = 1e-5
    x, xd, xdd = excitation(t)
    xp, xdp, _ = excitation(t + h)
    xm, xdm, _ = excitation(t - h)
    scale_v = np.max(np.abs(xd))
    scale_a = np.max(np.abs(xdd))
    np.testing.assert_allclose((xp - xm) / (2 * h), xd, atol=1e-6 * scale_v)
    np.testing.assert_allclose((xdp - xdm) / (2 * h), xdd, atol=1e-5 * scale_a)


@pytest.mark.parametrize(
    "excitation",
    [
        Sine(0.005, 1.855, 0.3),
        LinearSweep(0.002, 1.0, 4.0, 30.0, 0.2),
        SteppedSweep(0.005, (1.0, 2.0, 3.0, 4.0, 5.0), dwell=6.0, ramp=0.5),
        AmplitudeSteps((0.002, 0.004, 0.008), 2.0, dwell=10.0, ramp=0.5),
        Ramped(AmplitudeSteps((0.002, 0.004), 2.0, dwell=10.0, ramp=0.5), 1.5, start=0.7),
        Ramped(LinearSweep(0.002, 1.0, 4.0, 30.0), 2.0),
    ],
)
def test_the_integrators_float_form_of_each_drive_is_its_array_form(excitation) -> None:
    """``drive_at`` (the right-hand side's float formulas) against the array forms, before,
    inside and after every ramp and step, to 1e-12 of each signal's peak (rounding: the
    same formulas, ``math`` for NumPy)."""
    at = drive_at(excitation)
    assert at is not None
    t = np.sort(np.r_[np.random.default_rng(1).uniform(-1.0, 31.0, 3000), 0.0, 0.7, 2.2, 30.0])
    arrays = excitation(t)
    floats = np.array([at(float(ti)) for ti in t]).T
    for a, f in zip(arrays, floats):
        np.testing.assert_allclose(f, a, rtol=0, atol=1e-12 * np.max(np.abs(a)))
    assert drive_at(Crank(0.01, 0.15, 1.855)) is None  # the array form, one element a call


def test_a_servo_following_a_transport_move_has_its_float_form() -> None:
    """``ServoFollow.at`` (lag, ripple while moving) against its array form, as above."""
    from reference_rig_records import ServoFollow, TransportMove

    servo = ServoFollow(TransportMove(0.3, 2.5, start=1.0), lag=0.015, ripple=2e-5)
    t = np.linspace(0.0, 5.0, 2001) + 1e-4
    arrays = servo(t)
    floats = np.array([drive_at(servo)(float(ti)) for ti in t]).T
    for a, f in zip(arrays, floats):
        np.testing.assert_allclose(f, a, rtol=0, atol=1e-12 * np.max(np.abs(a)))


def test_stiff_hinge_limit_is_rigid() -> None:
    """A very stiff, well-damped hinge makes the bob ride rigidly with the tank."""
    t = np.arange(0.0, 2.0, 0.01)
    exc = Sine(0.005, 1.855)
    k = 1e3  # natural frequency ~76 Hz, 41x the drive: quasi-static error (1/41)^2 ~ 6e-4
    stiff = Pendulum(1.338, 0.057, stiffness=k,
                     damping=hinge_damping(1.338, 0.057, 0.5, stiffness=k))
    out = simulate_lateral(t, exc, pendulums=[stiff], fixed_mass=1.456, dry_mass=1.2)
    total = 1.2 + 1.456 + 1.338
    np.testing.assert_allclose(out["force"][100:], total * out["acceleration"][100:],
                               atol=2e-3 * total * np.max(np.abs(out["acceleration"])))


def test_bad_arguments() -> None:
    t = np.arange(0.0, 1.0, 0.01)
    with pytest.raises(ValueError, match="sensor_delay"):
        simulate_lateral(t, Sine(0.005, 2.0), sensor_delay=-0.01)
    with pytest.raises(ValueError, match="initial angles"):
        simulate_lateral(t, Sine(0.005, 2.0), pendulums=[Pendulum(1.0, 0.05)],
                         initial_theta=[0.1, 0.2])
