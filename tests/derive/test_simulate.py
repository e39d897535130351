"""Simulated behaviour against conserved quantities, analytic limits and SciPy."""

import math

import numpy as np
import pytest
import tolerances as tol
from scipy.integrate import solve_ivp

from analogs import (
    FixedMass,
    HingeDamper,
    HingeSpring,
    LateralRig,
    Pendulum,
    Rotor,
    SphericalPendulum,
    SuspendedMass,
)
from derive import RK4, Adaptive, NoExcitation, Sampled, Sine, c_compiler, derive, simulate

G = 9.80665
TIGHT = Adaptive(rtol=1e-12, atol=1e-14)


def _energy(sim):
    return sim.output("kinetic_energy") + sim.output("potential_energy")


def _relative_drift(sim):
    e = _energy(sim)
    return np.max(np.abs(e - e[0])) / abs(e[0])


def test_undamped_two_pendulums_conserve_energy_in_a_fixed_tank():
    model = (LateralRig() + FixedMass("fixed", mass=1.5, height=0.1)
             + Pendulum("p1", mass=1.3, length=0.057, hinge_height=0.10) + HingeSpring("p1", stiffness=0.02)
             + Pendulum("p2", mass=0.05, length=0.018, hinge_height=0.10))
    t = np.linspace(0.0, 30.0, 3001)
    sim = simulate(model, {"rig.dry_mass": 1.2}, t, NoExcitation(), integrator=TIGHT,
                   x0={"p1.theta": 0.4, "p2.theta": -0.2}, outputs=("kinetic_energy", "potential_energy"))
    assert np.ptp(sim.state("p1.theta")) > 0.5  # it really swings
    assert _relative_drift(sim) < tol.ENERGY_DRIFT


def test_small_amplitude_free_decay_frequency_matches_analytic():
    m, L, k = 1.338, 0.057, 0.05
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
    params = {"rig.dry_mass": 1.2, "fixed.mass": 1.456, "p1.mass": m, "p1.length": L,
              "p1.stiffness": k, "p1.damping": 1e-5}
    t = np.linspace(0.0, 30.0, 30001)
    sim = simulate(model, params, t, integrator=Adaptive(), x0={"p1.theta": 1e-3})
    th = sim.state("p1.theta")
    i = np.nonzero((th[:-1] < 0) & (th[1:] >= 0))[0]
    crossings = t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])
    f_sim = (len(crossings) - 1) / (crossings[-1] - crossings[0])
    f_hand = math.sqrt(G / L + k / (m * L**2)) / (2 * math.pi)
    # light damping lowers the frequency by ~zeta^2/2 ~ 1e-8: negligible here
    assert abs(f_sim / f_hand - 1) < tol.FREE_DECAY_FREQUENCY


def _hand_two_pendulums(t, A, f, pend, m_rigid):
    """SciPy DOP853 of hand-written equations of two pendulums on a sine-driven carriage."""
    w = 2 * math.pi * f

    def xdd(tt):
        return -A * w * w * math.sin(w * tt)

    def rhs(tt, y):
        a = xdd(tt)
        out = []
        for j, (m, L, k, c) in enumerate(pend):
            th, thd = y[2 * j], y[2 * j + 1]
            thdd = -(m * L * a * math.cos(th) + m * G * L * math.sin(th) + k * th + c * thd) / (m * L**2)
            out += [thd, thdd]
        return out

    sol = solve_ivp(rhs, (t[0], t[-1]), np.zeros(2 * len(pend)), method="DOP853",
                    t_eval=t, rtol=1e-10, atol=1e-13)
    a = -A * w * w * np.sin(w * t)
    force = m_rigid * a
    for j, (m, L, k, c) in enumerate(pend):
        th, thd = sol.y[2 * j], sol.y[2 * j + 1]
        thdd = -(m * L * a * np.cos(th) + m * G * L * np.sin(th) + k * th + c * thd) / (m * L**2)
        force = force + m * (a + L * thdd * np.cos(th) - L * thd**2 * np.sin(th))
    return force


def test_two_pendulum_forced_response_matches_scipy_reference():
    pend = [(1.338, 0.057, 0.01, 2e-4), (0.048, 0.018, 0.0, 1e-5)]
    model = LateralRig() + FixedMass("fixed")
    params = {"rig.dry_mass": 1.2, "fixed.mass": 1.456}
    for j, (m, L, k, c) in enumerate(pend, start=1):
        name = f"p{j}"
        model = model + Pendulum(name) + HingeSpring(name) + HingeDamper(name)
        params |= {f"{name}.mass": m, f"{name}.length": L, f"{name}.stiffness": k, f"{name}.damping": c}
    t = np.linspace(0.0, 10.0, 1001)
    sim = simulate(model, params, t, Sine(0.005, 2.0), integrator=TIGHT)
    ref = _hand_two_pendulums(t, 0.005, 2.0, pend, 1.2 + 1.456)
    rel_rms = np.sqrt(np.mean((sim.output("force_x") - ref) ** 2) / np.mean(ref**2))
    assert rel_rms < tol.FORCED_RESPONSE_RMS


def test_rk4_converges_to_the_adaptive_solution_at_fourth_order():
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")
    params = {"rig.dry_mass": 1.2, "fixed.mass": 1.456, "p1.mass": 1.338, "p1.length": 0.057,
              "p1.damping": 1e-4}
    exc = Sine(0.005, 1.855)
    ref = simulate(model, params, np.linspace(0, 5, 501), exc, integrator=TIGHT).output("force_x")
    errs = []
    for s in (1, 2):
        sim = simulate(model, params, np.linspace(0, 5, 501), exc, integrator=RK4(substeps=s))
        errs.append(np.max(np.abs(sim.output("force_x") - ref)))
    assert errs[0] / errs[1] > 12  # 2^4 = 16 for a fourth-order method


def test_spherical_pendulum_started_in_a_plane_is_the_planar_pendulum():
    t = np.linspace(0.0, 5.0, 501)
    base = LateralRig() + FixedMass("fixed")
    vals = {"rig.dry_mass": 1.0, "fixed.mass": 1.0, "p1.mass": 0.7, "p1.length": 0.08}
    planar = simulate(base + Pendulum("p1") + HingeDamper("p1", damping=1e-3), vals, t,
                      Sine(0.004, 1.7), integrator=TIGHT)
    sph = simulate(base + SphericalPendulum("p1") + HingeDamper("p1", damping=1e-3), vals, t,
                   Sine(0.004, 1.7), integrator=TIGHT)
    assert np.max(np.abs(sph.state("p1.alpha") - planar.state("p1.theta"))) < 1e-9
    assert np.max(np.abs(sph.state("p1.beta"))) < 1e-12
    assert np.max(np.abs(sph.output("force_x") - planar.output("force_x"))) < 1e-8


def test_spherical_pendulum_conserves_energy_and_vertical_angular_momentum():
    m, L = 0.7, 0.08
    model = LateralRig() + SphericalPendulum("p1", mass=m, length=L, hinge_height=0.1)
    t = np.linspace(0.0, 10.0, 1001)
    sim = simulate(model, {"rig.dry_mass": 0.0}, t, NoExcitation(), integrator=TIGHT,
                   x0={"p1.alpha": 0.5, "p1.beta": 0.1, "p1.beta_dot": 2.0},
                   outputs=("kinetic_energy", "potential_energy"))
    assert _relative_drift(sim) < tol.ENERGY_DRIFT
    a, b = sim.state("p1.alpha"), sim.state("p1.beta")
    ad, bd = sim.state("p1.alpha_dot"), sim.state("p1.beta_dot")
    # bob relative to the hinge: L (sin a cos b, sin b, -cos a cos b); L_z = m (x yd - y xd)
    x, y = L * np.sin(a) * np.cos(b), L * np.sin(b)
    xd = L * (np.cos(a) * np.cos(b) * ad - np.sin(a) * np.sin(b) * bd)
    yd = L * np.cos(b) * bd
    hz = m * (x * yd - y * xd)
    assert np.ptp(hz) / abs(hz[0]) < 1e-8


def test_rotor_keeps_its_angular_momentum_and_damping_decays_it_exponentially():
    J, c = 2e-3, 4e-3
    t = np.linspace(0.0, 3.0, 301)
    free = simulate(LateralRig() + Rotor("r1", inertia=J), {"rig.dry_mass": 0.0}, t,
                    integrator=TIGHT, x0={"r1.psi_dot": 5.0})
    assert np.ptp(free.state("r1.psi_dot")) < 1e-10
    damped = simulate(LateralRig() + Rotor("r1", inertia=J, damping=c), {"rig.dry_mass": 0.0}, t,
                      integrator=TIGHT, x0={"r1.psi_dot": 5.0})
    assert np.allclose(damped.state("r1.psi_dot"), 5.0 * np.exp(-c / J * t), rtol=1e-8, atol=0)
    # the transducer holds the tank against the rotor's drag: it supplies the rate of change
    # of the assembly's angular momentum, torque_z = J psi_ddot = -c psi_dot
    assert np.allclose(damped.output("torque_z"), -c * damped.state("r1.psi_dot"), rtol=1e-7, atol=1e-12)


def test_suspended_mass_oscillates_at_sqrt_k_over_m_and_conserves_energy():
    m, k = 0.3, 120.0
    model = LateralRig() + SuspendedMass("s1", axes="xy", mass=m, height=0.05, stiffness_x=k,
                                         stiffness_y=2 * k)
    t = np.linspace(0.0, 4.0, 4001)
    sim = simulate(model, {"rig.dry_mass": 0.0}, t, integrator=TIGHT,
                   x0={"s1.s_x": 0.01, "s1.s_y": 0.02}, outputs=("kinetic_energy", "potential_energy"))
    assert np.allclose(sim.state("s1.s_x"), 0.01 * np.cos(math.sqrt(k / m) * t), atol=1e-10)
    assert np.allclose(sim.state("s1.s_y"), 0.02 * np.cos(math.sqrt(2 * k / m) * t), atol=1e-10)
    assert _relative_drift(sim) < tol.ENERGY_DRIFT


def test_sampled_excitation_reproduces_the_analytic_one():
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")
    params = {"rig.dry_mass": 1.2, "fixed.mass": 1.456, "p1.mass": 1.338, "p1.length": 0.057,
              "p1.damping": 1e-4}
    t = np.linspace(0.0, 10.0, 1001)
    sine = Sine(0.005, 1.855)
    sampled = Sampled(t, sine.values(t))
    a = simulate(model, params, t, sine).output("force_x")
    b = simulate(model, params, t, sampled).output("force_x")
    # cubic-spline interpolation of the midpoint inputs: error O(h^4 w^4) ~ 1e-5 relative
    assert np.sqrt(np.mean((a - b) ** 2) / np.mean(a**2)) < 1e-4


def test_excitation_size_mismatch_and_bad_grid_are_reported():
    dm = derive(LateralRig(excitation="crank") + FixedMass("fixed"))
    vals = {"rig.dry_mass": 1.0, "fixed.mass": 1.0, "rig.crank_radius": 0.01, "rig.rod_length": 0.15,
            "rig.drive_frequency": 1.8}
    with pytest.raises(ValueError, match="supplies 3 input values but the model takes 0"):
        simulate(dm, vals, np.linspace(0, 1, 11), Sine(0.01, 1.0))
    with pytest.raises(ValueError, match="strictly increasing"):
        simulate(dm, vals, np.array([0.0, 0.0, 1.0]))


@pytest.mark.parametrize("sampled, compiled, chunk", [(False, False, None), (True, False, None),
                                                      (True, True, 64), (False, True, 150)])
def test_simulate_outputs_is_simulate_per_parameter_set(sampled, compiled, chunk, monkeypatch):
    """The batched runs are, set by set and output by output, the RK4 runs of ``simulate``
    (same arithmetic: equal to rounding), compiled or not and in chunks that do not divide
    the run (the runs' states carried from chunk to chunk; the references are made in one
    chunk, before the chunk size is changed, as ``simulate`` shares the chunking); a wrong
    ordering of the mapped columns (runs and samples interleaved) would swap the
    pendulums' responses."""
    from derive import simulate_outputs

    model = LateralRig() + Pendulum("q") + HingeDamper("q")
    t = np.linspace(0.0, 4.0, 401)
    sine = Sine(0.003, 1.7)
    exc = Sampled(t, sine.values(t).reshape(3, t.size)) if sampled else sine
    sets = [{"rig.dry_mass": 0.0, "q.mass": m, "q.length": L, "q.damping": c,
             "q.hinge_height": 0.05}
            for m, L, c in ((1.0, 0.08, 1e-3), (0.4, 0.02, 0.0), (2.0, 0.15, 5e-3))]
    outputs = ("force_x", "torque_y")
    if compiled and c_compiler() is None:
        pytest.skip("no C compiler")
    refs = [simulate(model, p, t, exc, integrator=RK4(2), outputs=outputs).outputs
            for p in sets]
    if chunk is not None:
        import importlib

        monkeypatch.setattr(importlib.import_module("derive.simulate"), "CHUNK_STEPS", chunk)
    got = simulate_outputs(model, sets, t, exc, outputs=outputs, substeps=2, compiled=compiled)
    assert got.shape == (3, t.size, 2)
    for k, ref in enumerate(refs):
        np.testing.assert_allclose(got[k], ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    assert not np.allclose(got[0], got[1])


def test_a_run_longer_than_a_chunk_is_the_same_run_to_the_last_bit(monkeypatch):
    # the fixed-step simulator runs CHUNK_STEPS steps per call, the last chunk padded with
    # zero-length steps: every chunking of a run, and one call for all of it, agree exactly
    import importlib

    ds = importlib.import_module("derive.simulate")  # the module, not the function

    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")
    params = {"rig.dry_mass": 1.2, "fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.057,
              "p1.damping": 1e-3}
    t = np.linspace(0.0, 6.0, 1038)  # 1037 steps: no chunk size below divides it
    w = 2 * np.pi * 2.1
    x = np.vstack([0.004 * np.sin(w * t), 0.004 * w * np.cos(w * t),
                   -0.004 * w**2 * np.sin(w * t)])  # displacement, rate, acceleration
    runs = []
    for chunk in (10**6, 64, 100, 1036):
        monkeypatch.setattr(ds, "CHUNK_STEPS", chunk)
        runs.append(simulate(model, params, t, Sampled(t, x), integrator=RK4()))
    for sim in runs[1:]:
        assert np.array_equal(sim.states, runs[0].states)
        assert np.array_equal(sim.outputs, runs[0].outputs, equal_nan=True)
    assert np.max(np.abs(runs[0].states[:, 0])) > 0.05  # the pendulum does swing
