"""The independent 3-D motion reference (tests/reference_motion.py) against hand limits:
its kinematics, a static tilt, a rigid tank translated, the transducer's point and axes,
the energy balance of an undamped pendulum under a 3-D motion, and its noise."""

import math

import numpy as np
import pytest
from reference_motion import (
    CHANNELS,
    FixedMass,
    Motion,
    Move,
    Noise,
    RampedSine,
    SphericalPendulum,
    Transducer,
    energy,
    rotation,
    simulate_motion,
)
from scipy.integrate import cumulative_simpson

G = 9.80665
#: Closed forms evaluated in double precision against the same numbers: round-off only.
EXACT = 1e-12
#: Central differences with a 1e-5 s step: truncation ~h^2 |f'''| ~ 1e-8 of the rates here.
DIFFERENCE = 1e-6
#: The energy balance integrates the power with Simpson's rule on a 1 kHz grid (error
#: ~dt^4 |P''''| ~ 1e-9 J) against states from DOP853 at rtol 1e-11; the energies swing by
#: ~0.8 J (measured error 5e-9 J), so 1e-7 J is a margin of 20 and far below a wrong term
#: (a missing Coriolis or Euler term changes the balance by 1e-3 J or more).
ENERGY_BALANCE = 1e-7

THREE_D = Motion(x=RampedSine(0.01, 1.7, ramp=0.6, start=0.1), y=RampedSine(0.006, 2.3, 0.4, 0.5, 0.2),
                 z=RampedSine(0.004, 1.1, ramp=0.5, start=0.0),
                 roll=RampedSine(0.05, 0.9, 0.3, 0.5, 0.0), pitch=RampedSine(0.09, 1.3, 0.0, 0.7, 0.1),
                 yaw=(RampedSine(0.2, 0.7, 1.0, 0.5, 0.0), Move(0.3, 1.0, 0.2)))


def _const(value):
    return lambda t: (np.full_like(np.asarray(t, float), value), 0 * np.asarray(t, float),
                      0 * np.asarray(t, float))


def test_angular_velocity_and_acceleration_are_the_attitude_derivatives():
    t = np.linspace(0.05, 2.95, 30)  # off the ramps' ends, where the third derivative jumps
    h = 1e-5
    R, omega, alpha, a_o, g = THREE_D.kinematics(t)
    Rp, wp, *_ = THREE_D.kinematics(t + h)
    Rm, wm, *_ = THREE_D.kinematics(t - h)
    for i in range(t.size):
        W = R[i].T @ (Rp[i] - Rm[i]) / (2 * h)  # skew(omega) in tank components
        assert np.allclose([W[2, 1], W[0, 2], W[1, 0]], omega[i], atol=DIFFERENCE)
        assert np.allclose(W, -W.T, atol=DIFFERENCE)
    assert np.allclose((wp - wm) / (2 * h), alpha, atol=DIFFERENCE)
    # R is Rz Ry Rx, and gravity and the lab acceleration are seen in tank axes
    ph, th, ps = (THREE_D.axis(a, t)[0] for a in ("roll", "pitch", "yaw"))
    a_lab = np.stack([THREE_D.axis(a, t)[2] for a in "xyz"], axis=1)
    for i in range(t.size):
        Ri = rotation(ph[i], th[i], ps[i])
        assert np.allclose(R[i], Ri, atol=EXACT)
        assert np.allclose(a_o[i], Ri.T @ a_lab[i], atol=EXACT)
        assert np.allclose(g[i], Ri.T @ [0.0, 0.0, -G], atol=EXACT)
        # the integrator's one-time path gives the same numbers
        for one, many in zip(THREE_D.at(float(t[i])), (omega[i], alpha[i], a_o[i], g[i])):
            assert np.allclose(one, many, atol=EXACT)


def test_static_tilt_gives_the_weights_torque():
    """Pitched by theta and held, the pendulum hanging plumb (a = theta in the tank): the
    force is the weight in tank axes and the pitch torque about O is -g sin(theta) times the
    first moments of the fixed mass and of the pendulum's mass at its hinge (the bob's
    weight acts along a line through the hinge)."""
    theta = 0.3
    pend = SphericalPendulum(1.3, 0.055, 0.12, damping=0.002)
    fixed = FixedMass(1.5, 0.08, inertia=0.004, axial_inertia=0.006)
    t = np.linspace(0.0, 2.0, 201)
    z_p = -0.04
    out = simulate_motion(t, Motion(pitch=_const(theta)), pendulum=pend, fixed=fixed,
                          dry_mass=1.2, x0=(theta, 0.0, 0.0, 0.0),
                          transducer=Transducer((0.0, 0.0, z_p)))
    assert np.max(np.abs(out["states"][:, :2] - [theta, 0.0])) < 1e-9  # it stays plumb
    M = 1.2 + 1.5 + 1.3
    c = out["clean"]
    assert np.allclose(c["force_x"], -M * G * math.sin(theta), rtol=1e-9)
    assert np.allclose(c["force_z"], M * G * math.cos(theta), rtol=1e-9)
    moment = 1.5 * 0.08 + 1.3 * 0.12
    # about P below O: the lateral force's arm adds -z_p F_x
    expected = -G * math.sin(theta) * moment - z_p * (-M * G * math.sin(theta))
    assert np.allclose(c["torque_y"], expected, rtol=1e-9)
    for ch in ("force_y", "torque_x", "torque_z"):
        assert np.max(np.abs(c[ch])) < 1e-9


def test_rigid_tank_translated_in_x_gives_mass_times_acceleration():
    fixed = FixedMass(1.5, 0.08, inertia=0.004)
    t = np.linspace(0.0, 3.0, 301)
    motion = Motion(x=RampedSine(0.01, 2.0))
    out = simulate_motion(t, motion, fixed=fixed, dry_mass=1.2)
    a = motion.axis("x", t)[2]
    c = out["clean"]
    assert np.allclose(c["force_x"], 2.7 * a, atol=EXACT)
    assert np.allclose(c["force_z"], 2.7 * G, atol=EXACT)
    assert np.allclose(c["torque_y"], 1.5 * 0.08 * a, atol=EXACT)  # m h a about O


def test_slow_translation_moves_the_pendulum_with_the_tank():
    """Driven at a tenth of its frequency the pendulum follows the tank (quasi-static): the
    force is the total mass times the acceleration to the pendulum's (f/f1)^2 ~ 1 %."""
    pend = SphericalPendulum(1.3, 0.055, 0.12, damping=0.02)
    f1 = pend.frequency_hz()
    t = np.linspace(0.0, 20.0, 2001)
    motion = Motion(x=RampedSine(0.02, 0.1 * f1, ramp=4.0))
    out = simulate_motion(t, motion, pendulum=pend, fixed=FixedMass(1.5, 0.08), dry_mass=1.2)
    a = motion.axis("x", t)[2]
    late = t > 8.0
    slope = np.polyfit(a[late], out["clean"]["force_x"][late], 1)[0]
    assert slope == pytest.approx(4.0 * (1 + 1.3 / 4.0 * 0.01), rel=2e-3)


def test_transducer_point_and_axes():
    pend = SphericalPendulum(1.3, 0.055, 0.12, damping=0.002)
    t = np.linspace(0.0, 2.0, 101)
    kw = dict(pendulum=pend, fixed=FixedMass(1.5, 0.08), dry_mass=1.2)
    base = simulate_motion(t, THREE_D, **kw)
    turned = simulate_motion(t, THREE_D, transducer=Transducer(yaw=math.pi), **kw)
    for ch, sign in zip(CHANNELS, (-1, -1, 1, -1, -1, 1)):
        assert np.allclose(turned["clean"][ch], sign * base["clean"][ch], atol=1e-12)
    r_p = np.array([0.01, -0.02, -0.05])
    moved = simulate_motion(t, THREE_D, transducer=Transducer(tuple(r_p)), **kw)
    F = np.stack([base["clean"][c] for c in CHANNELS[:3]], axis=1)
    M = np.stack([base["clean"][c] for c in CHANNELS[3:]], axis=1)
    shifted = M - np.cross(r_p, F)
    for k, ch in enumerate(CHANNELS[3:]):
        assert np.allclose(moved["clean"][ch], shifted[:, k], atol=1e-12)


def test_energy_balance_of_an_undamped_pendulum_under_3d_motion():
    """With no damping, the energy of the tank assembly in the lab changes by the work of
    the transducer's force and torque (the only loads besides gravity)."""
    pend = SphericalPendulum(1.3, 0.055, 0.12, damping=0.0, stiffness=0.01)
    fixed = FixedMass(1.5, 0.08, inertia=0.004, axial_inertia=0.006)
    t = np.linspace(0.0, 2.0, 2001)
    out = simulate_motion(t, THREE_D, pendulum=pend, fixed=fixed, dry_mass=1.2,
                          x0=(0.1, -0.05, 0.0, 0.3), rtol=1e-11, atol=1e-13)
    X = out["states"]
    E, P = energy(t, X, THREE_D, pendulum=pend, fixed=fixed, dry_mass=1.2, power=True)
    spring = 0.5 * 0.01 * (X[:, 0] ** 2 + X[:, 1] ** 2)
    work = cumulative_simpson(P, x=t, initial=0.0)
    assert np.ptp(E) > 0.1  # not vacuous: the motion does work
    assert np.max(np.abs((E + spring - E[0] - spring[0]) - work)) < ENERGY_BALANCE
    # the damper would take energy out: the balance is sensitive to it
    damped = SphericalPendulum(1.3, 0.055, 0.12, damping=0.002, stiffness=0.01)
    out2 = simulate_motion(t, THREE_D, pendulum=damped, fixed=fixed, dry_mass=1.2,
                           x0=(0.1, -0.05, 0.0, 0.3), rtol=1e-11, atol=1e-13)
    X2 = out2["states"]
    E2, P2 = energy(t, X2, THREE_D, pendulum=damped, fixed=fixed, dry_mass=1.2, power=True)
    spring2 = 0.5 * 0.01 * (X2[:, 0] ** 2 + X2[:, 1] ** 2)
    dissipated = cumulative_simpson(0.002 * (X2[:, 2] ** 2 + X2[:, 3] ** 2), x=t, initial=0.0)
    balance = (E2 + spring2 - E2[0] - spring2[0]) - cumulative_simpson(P2, x=t, initial=0.0)
    assert np.max(np.abs(balance + dissipated)) < ENERGY_BALANCE
    assert np.max(np.abs(balance)) > 1e3 * ENERGY_BALANCE


def test_noise_is_seeded_per_channel_and_of_the_stated_size():
    pend = SphericalPendulum(1.3, 0.055, 0.12, damping=0.002)
    t = np.linspace(0.0, 2.0, 2001)
    kw = dict(pendulum=pend, fixed=FixedMass(1.5, 0.08), dry_mass=1.2,
              noise=Noise(force=0.02, torque=0.02, tone=None, drift=0.0), seed=3)
    a = simulate_motion(t, THREE_D, **kw)
    b = simulate_motion(t, THREE_D, **kw)
    rms_f = max(np.std(a["clean"][c]) for c in CHANNELS[:3])
    for ch in CHANNELS:
        assert np.array_equal(a[ch], b[ch])
    ratio = np.std(a["force_y"] - a["clean"]["force_y"]) / rms_f
    assert 0.017 < ratio < 0.023  # the quiet channel is as noisy as the driven ones
    assert set(a["motion"]) == {"x", "y", "z", "roll", "pitch", "yaw"}
