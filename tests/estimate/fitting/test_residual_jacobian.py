"""The residual Jacobian assembled from per-sample blocks equals CasADi's automatic
differentiation of the residual expression, for every variant the fit builds: estimated and
filtered input, a fixed and a free start, two pendulums, a measurement model with its own
parameters, two cases at once and weighted samples (a sensor delay zeroes the last ones);
each with a shooting node at every sample and with one every 3 samples (the states in
between simulated with forward sensitivities, the last interval padded: 300 samples)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import make_case, pendulum

from estimate import FitProblem, model_from_spec
from estimate.fitting.assembly import assemble_nlp as _setup
from estimate.fitting.measurement import RigFriction, SensorDelay, SensorOffset
from estimate.fitting.transcription import MultipleShooting


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    folder = tmp_path_factory.mktemp("jac")
    # 3 s records: enough to exercise every index; longer ones only cost time
    return [make_case(folder, name, ref.Ramped(ref.Sine(amp, hz), 1.0, 0.0),
                      pendulums=[pendulum()], duration=3.0, seed=seed, tone=ref.Tone(0.05, 25.0))[0]
            for name, amp, hz, seed in (("a", 0.003, 1.9, 1), ("b", 0.002, 2.5, 2))]


VARIANTS = {
    "estimated rest": (1, "fixed,p1", "estimated", (), "rest"),
    "estimated free": (1, "fixed,p1", "estimated", (), "free"),
    "filtered rest": (1, "fixed,p1", "filtered", (), "rest"),
    "two pendulums": (1, "fixed,p1,p2", "estimated", (), "rest"),
    "offset and drift": (1, "fixed,p1", "estimated", (SensorOffset(),), "rest"),
    "rig friction": (1, "fixed,p1", "estimated", (RigFriction(),), "rest"),
    "delay weights": (1, "fixed,p1", "estimated", (SensorDelay(0.05),), "free"),
    "two cases": (2, "fixed,p1", "estimated", (), "rest"),
}


@pytest.mark.parametrize("per_interval", [1, 3])
@pytest.mark.parametrize("variant", VARIANTS)
def test_assembled_residual_jacobian_equals_automatic_differentiation(cases, variant,
                                                                      per_interval):
    ncases, spec, mode, measurement, start = VARIANTS[variant]
    chosen = cases[:ncases]
    problem = FitProblem.build(chosen if ncases > 1 else chosen[0],
                               model_from_spec(spec, chosen[0]), input=mode,
                               measurement=list(measurement))
    nlp, terms = _setup(problem, MultipleShooting(samples_per_interval=per_interval),
                        "squared", [start] * ncases, True, False, None)
    condensed = [t.block.state_jacobian is not None for t in terms]
    assert all(condensed) == (per_interval > 1)
    assert all(t.jacobian is not None for t in terms)  # the assembled path is the one tested
    f = ca.Function("f", [nlp.w], [nlp.jac_r, ca.jacobian(nlp.r, nlp.w)])
    w = nlp.w0 * (1 + 0.05 * np.random.default_rng(3).standard_normal(nlp.w0.size))
    w[: len(problem.estimated)] += 0.1  # no estimate at 0 (a friction's: its terms vanish)
    assembled, automatic = (np.asarray(m.full()) for m in f(w))
    # the same derivatives by two routes: equal to rounding (relative 1e-12 of the largest)
    assert np.max(np.abs(assembled - automatic)) <= 1e-12 * np.max(np.abs(automatic))


@pytest.mark.parametrize("steady, offsets, per_interval",
                         [(False, False, 1), (True, False, 1), (False, True, 1),
                          (True, True, 4)])
def test_six_channel_residual_jacobian_equals_automatic_differentiation(tmp_path, steady,
                                                                        offsets, per_interval):
    """The spinning rig: six channels of different units (scaled per channel), a pendulum
    and a rotor, from rest or from the steady relative equilibrium, with or without every
    channel's offset and drift estimated."""
    import reference_spinning as rs
    from synthetic_cases import make_spinning_case

    rig = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06,
                 nutation_frequency=-0.5, dry_mass=2.0, nutation_ramp=1.0, nutation_start=0.5)
    case, _ = make_spinning_case(
        tmp_path, "S", rig, pendulum=rs.SphericalPendulum(1.25, 0.062, 0.035, damping=5e-4),
        rotor=rs.Rotor(0.01, 0.04, axis="y"), fixed_mass=1.5, fixed_height=0.05, noise=0.01,
        duration=2.0, steady=steady, tank_radius=0.1016)
    from estimate.fitting.measurement import ChannelOffsets

    problem = FitProblem.build(case, model_from_spec("fixed,p1,r1", case),
                               measurement=(ChannelOffsets(),) if offsets else ())
    kind = "steady" if steady else "rest"
    nlp, terms = _setup(problem, MultipleShooting(samples_per_interval=per_interval),
                        "squared", [kind], True, False, None)
    assert len(problem.channels(0)) == 6 and terms[0].jacobian is not None
    assert (terms[0].block.state_jacobian is not None) == (per_interval > 1)
    f = ca.Function("f", [nlp.w], [nlp.jac_r, ca.jacobian(nlp.r, nlp.w)])
    w = nlp.w0 * (1 + 0.05 * np.random.default_rng(4).standard_normal(nlp.w0.size))
    assembled, automatic = (np.asarray(m.full()) for m in f(w))
    assert np.max(np.abs(assembled - automatic)) <= 1e-12 * np.max(np.abs(automatic))


@pytest.mark.parametrize("per_interval", [1, 3])
@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("variant", ["estimated rest", "estimated free", "two cases",
                                     "filtered rest"])
def test_constraint_jacobian_and_fast_constraints_equal_the_interpreted_ones(cases, variant,
                                                                              compiled,
                                                                              per_interval):
    """What IPOPT evaluates: the constraint Jacobian assembled from per-interval blocks
    (bidiagonal state blocks, block-diagonal input blocks times the carriage spline) equals
    CasADi's automatic differentiation of the interpreted constraints, and the constraints
    from the (compiled) step equal the interpreted ones; rounding only (1e-12 relative;
    compiled C may round differently from CasADi's virtual machine)."""
    from derive._compile import c_compiler

    if compiled and c_compiler() is None:
        pytest.skip("no C compiler")
    ncases, spec, mode, measurement, start = VARIANTS[variant]
    chosen = cases[:ncases]
    problem = FitProblem.build(chosen if ncases > 1 else chosen[0],
                               model_from_spec(spec, chosen[0]), input=mode)
    shooting = MultipleShooting(samples_per_interval=per_interval)
    nlp, _ = _setup(problem, shooting, "squared", [start] * ncases, True, compiled, None)
    jac_g = nlp.constraint_jacobian(True)
    assert jac_g is not None
    w = nlp.w0 * (1 + 0.05 * np.random.default_rng(5).standard_normal(nlp.w0.size))
    g_blocks, J_blocks = (np.asarray(m.full()) for m in jac_g(w, []))
    g, g_fast, J = (np.asarray(m.full()) for m in ca.Function(
        "g", [nlp.w], [nlp.g, nlp.g_fast, ca.jacobian(nlp.g, nlp.w)])(w))
    scale = np.max(np.abs(J))
    assert np.max(np.abs(J_blocks - J)) <= 1e-12 * scale
    for other in (g_blocks, g_fast):
        assert np.max(np.abs(other - g)) <= 1e-12 * max(np.max(np.abs(w)), 1.0)
    # the residuals IPOPT evaluates (states from compiled steps when condensed) equal the
    # interpreted, differentiable ones
    plain, _ = _setup(problem, shooting, "squared", [start] * ncases, False, False, None)
    r_fast = np.asarray(ca.Function("r", [nlp.w], [nlp.r])(w).full()).ravel()
    r_plain = np.asarray(ca.Function("r", [plain.w], [plain.r])(w).full()).ravel()
    assert np.max(np.abs(r_fast - r_plain)) <= 1e-10 * max(np.max(np.abs(r_plain)), 1.0)
