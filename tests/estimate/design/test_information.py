"""The information a record would add: CasADi forward sensitivities through the RK4
simulation against the independent reference simulator (SciPy DOP853 of hand-written
equations, differentiated by central differences here in the test), and the algebra that
adds a record's information to the fit's covariance."""

from __future__ import annotations

import numpy as np
import pytest
import reference_models as ref
from design_helpers import DRY, FIXED, LIMITS, G
from scipy.interpolate import make_interp_spline

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import derive
from estimate.design import SteadySine
from estimate.design.drives import fit_to_limits
from estimate.design.information import (
    Prediction,
    motion_inputs,
    prior_information,
    sensitivities,
    swing_angles,
)

NAMES = ("fixed.mass", "p1.mass", "p1.length", "p1.damping", "p1.stiffness")
TRUTH = {"fixed.mass": FIXED, "p1.mass": 1.3, "p1.length": 0.0553, "p1.damping": 2e-3,
         "p1.stiffness": 0.1}


@pytest.fixture(scope="module")
def setup():
    model = (LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1")
             + HingeDamper("p1"))
    dm = derive(model)
    drive = fit_to_limits(SteadySine(LIMITS, 6.0, frequency=2.2), 100.0)
    t = np.arange(601) / 100.0
    half = np.linspace(0, 6, 1201)
    inputs = motion_inputs(drive.motion(half))
    values = {"rig.dry_mass": DRY, "rig.gravity": G, **TRUTH}
    rec = sensitivities(dm, NAMES, ("force_x",), 600)(values, inputs, t)
    # the reference is driven by a quintic spline through the drive at 5 kHz (SciPy; its
    # acceleration is exact to ~1e-7 of the peak): the same input for every run
    fine = np.linspace(0, 6, 30001)
    spline = make_interp_spline(fine, drive.motion(fine)[0], k=5)

    def motion(tt):
        return spline(tt), spline(tt, 1), spline(tt, 2)

    return dm, motion, t, rec


def _reference(motion, t, **params):
    p = ref.Pendulum(params["p1.mass"], params["p1.length"], params["p1.stiffness"],
                     params["p1.damping"])
    return ref.simulate_lateral(t, motion, pendulums=[p], fixed_mass=params["fixed.mass"],
                                dry_mass=DRY, gravity=G)


def test_outputs_and_swing_match_the_reference(setup):
    """RK4 at 100 Hz against DOP853 at rtol 1e-10: 1e-4 of the force's range (the RK4
    error at 2.2 Hz, (w h)^4 / 120 per step accumulated over 13 periods)."""
    dm, drive, t, rec = setup
    sim = _reference(drive, t, **TRUTH)
    F = sim["force_true"]
    assert np.abs(rec.outputs[0] - F).max() < 1e-4 * np.abs(F).max()
    swing = swing_angles(dm, rec.states)["p1"]
    assert np.abs(swing - np.abs(sim["theta"][0])).max() < 1e-4 * np.abs(sim["theta"]).max()


@pytest.mark.parametrize("name", NAMES)
def test_sensitivities_match_differences_of_the_reference(setup, name):
    """dF/dp from CasADi against central differences of the reference force (step 1e-4
    of the value: truncation ~1e-8 relative, the reference's own error ~1e-9): 1e-3 of the
    largest sensitivity, which is what RK4's error allows."""
    _, drive, t, rec = setup
    h = 1e-4 * TRUTH[name]
    up = _reference(drive, t, **{**TRUTH, name: TRUTH[name] + h})["force_true"]
    down = _reference(drive, t, **{**TRUTH, name: TRUTH[name] - h})["force_true"]
    fd = (up - down) / (2 * h)
    J = rec.jacobian[0, :, NAMES.index(name)]
    assert np.abs(J - fd).max() < 1e-3 * np.abs(fd).max(), name


def test_information_of_white_noise(setup):
    """J^T J / sigma^2, channel by channel (hand-written sum)."""
    _, _, _, rec = setup
    J = rec.jacobian[0]
    assert np.allclose(rec.information([0.02]), J.T @ J / 0.02**2)


def _covariance(rng, n=5):
    """A fit-like covariance: two well-determined masses strongly correlated and a nearly
    undetermined direction (relative standard deviation 1e3)."""
    A = rng.normal(size=(n, n))
    Q, _ = np.linalg.qr(A)
    sd = np.array([1e-2, 3e-2, 1e-1, 2e-2, 1e3])
    return Q @ np.diag(sd**2) @ Q.T


def test_prior_round_trip_and_update():
    """The prior (inverse of the fit's covariance) alone reproduces the covariance; with a
    record's information it gives (C^-1 + F)^-1, checked with NumPy's inverse where that
    is well conditioned."""
    rng = np.random.default_rng(4)
    names = ["a", "b", "c", "d", "e"]
    values = np.array([1.5, 1.3, 0.05, 2e-3, 0.1])
    C = _covariance(rng) * np.outer(values, values)
    prior, se = prior_information(names, names, C)
    before = Prediction.of(names, values, prior, None, ["a", "b"], se)
    assert np.allclose(before.covariance, C, rtol=1e-6, atol=1e-12 * np.abs(C).max())
    J = rng.normal(size=(400, 5)) / values
    F = J.T @ J
    after = Prediction.of(names, values, prior, F, ["a", "b"], se)
    direct = np.linalg.inv(np.linalg.inv(C) + F)
    assert np.allclose(after.covariance, direct, rtol=1e-6)
    assert after.criterion("D") < before.criterion("D")
    assert after.criterion("A") < before.criterion("A")
    assert after.relative_halfwidth("a") == pytest.approx(
        1.959963984540054 * np.sqrt(direct[0, 0]) / 1.5)


def test_a_parameter_at_a_bound_has_no_prior_information():
    names = ["a", "b", "c"]
    C = np.diag([1e-4, 4e-4])
    prior, se = prior_information(names, ["a", "c"], C)
    assert np.all(prior[1] == 0) and np.all(prior[:, 1] == 0)
    assert np.isnan(se[1]) and se[0] == pytest.approx(1e-2)
