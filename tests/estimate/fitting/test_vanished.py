"""A model with a mode the record does not show (:mod:`estimate.fitting.vanished`): the fit
stops when its cost stalls with the mode's mass gone, and is refitted with its other
parameters held.

Before: a ``fixed,p1,p2`` fit of a one-mode record ran all 300 IPOPT iterations and ended
"not converged" (17-39 s on 3,001 samples, 466 s on 30,001).

The same fit's other failure: ``p2`` driven far below its frequency is a second fixed mass,
takes the fixed mass's share (0.5-1.5 kg for its mode's 0.048 kg) and wanders in frequency
until IPOPT runs out of iterations or diverges (seeds 2, 3, 4, 8, 13 of the record below:
fixed mass 0.0001-0.99 kg for 1.5). Such a fit is refitted from its start with that
pendulum's other parameters held (its damper at 0, as a vanished one's): the five then
converge with the fixed mass within 0.5 % of the truth."""

import warnings

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import G, make_case, pendulum

from estimate import FitProblem, fit, model_from_spec
from estimate.data.case import Prediction
from estimate.fitting.vanished import STALL_ITERATIONS, held_refit, stall_stop


@pytest.fixture(scope="module")
def one_mode(tmp_path_factory):
    """A 6 s, 500 Hz record of the 8-inch sphere at 60 % fill (one pendulum, no second
    mode) from the reference simulator: a 1 mm sweep over 0.6-1.6 f1 faded in over 1.5 s
    from rest, force noise 1.3 % of its RMS, displacement noise 20 um (the 6 s row of
    ``benchmarks/bench_length.py``)."""
    p = pendulum(1.30, 0.0553, 0.01)
    f1 = ref.natural_frequency(p, G) / (2 * np.pi)
    drive = ref.Ramped(ref.LinearSweep(0.001, 0.6 * f1, 1.6 * f1, 6.0), 1.5, 0.0)
    case, _ = make_case(tmp_path_factory.mktemp("one_mode"), "one_mode", drive, pendulums=[p],
                        fixed_mass=1.5, dry_mass=1.2, noise=0.013, displacement_noise=2e-5,
                        duration=6.0, rate=500.0, seed=4,
                        prediction=Prediction(1.338, 0.057, 1.456, 0.007))
    return case, {"fixed.mass": 1.5, "p1.mass": 1.30, "p1.length": 0.0553}


def _problem(case, spec="fixed,p1,p2", **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return FitProblem.build(case, model_from_spec(spec, case), **kw)


def test_the_stall_rule(one_mode):
    """On made-up iterations: a cost flat within one residual variance stops the fit when
    p2's mass is under 1 % of its start (from iteration 15); not when the mass is 2 % of
    it, nor when an estimate wanders by three times its scale with every mass kept (a
    weak-spring record's correct model walks its length-spring ridge so before it
    converges), nor when the cost still falls by two variances per iteration."""
    problem = _problem(one_mode[0], lag="none")
    names = list(problem.names)
    theta0 = problem.initial.copy()
    stop = stall_stop(problem, 6000)
    flat = [6000.0 + 0.01 * (k % 3) for k in range(200)]  # one variance: 1.0

    def first_stop(costs, thetas):
        return next((k for k in range(1, len(costs) + 1) if stop(costs[:k], thetas[k - 1])), None)

    vanished = theta0.copy()
    vanished[names.index("p2.mass")] *= 0.005
    assert first_stop(flat, [vanished] * 200) == STALL_ITERATIONS + 1
    kept = theta0.copy()
    kept[names.index("p2.mass")] *= 0.02  # small, not vanished
    assert first_stop(flat, [kept] * 200) is None
    scale = problem.estimated[names.index("p1.stiffness")].scale
    wander = [theta0 + np.eye(len(names))[names.index("p1.stiffness")] * 3 * scale * (k % 2)
              for k in range(200)]
    assert first_stop(flat, wander) is None
    falling = [6000.0 - 2.0 * k for k in range(200)]
    assert first_stop(falling, [vanished] * 200) is None


def _one_mode_record(folder, seed: int):
    p = pendulum(1.30, 0.0553, 0.01)
    f1 = ref.natural_frequency(p, G) / (2 * np.pi)
    drive = ref.Ramped(ref.LinearSweep(0.001, 0.6 * f1, 1.6 * f1, 6.0), 1.5, 0.0)
    case, _ = make_case(folder, "one_mode", drive, pendulums=[p], fixed_mass=1.5, dry_mass=1.2,
                        noise=0.013, displacement_noise=2e-5, duration=6.0, rate=500.0,
                        seed=seed, prediction=Prediction(1.338, 0.057, 1.456, 0.007))
    return case


@pytest.mark.slow  # 13 fits, 1-35 s each
def test_a_mode_the_record_lacks_ends_held_and_the_intervals_hold_the_truth(tmp_path):
    """``fixed,p1,p2`` on 13 draws of the one-mode record (seeds 1-13): p2's mass vanishes
    (the fit stops and is refitted with its other parameters held), or takes the fixed
    mass's share (refitted from the start with them held), or stays near its mode's mass.
    Every fixed-mass interval holds the truth (measured: 13 of 13), at least 9 fits converge
    (measured: 9; before the heavy-mass refit 4, the five heavy ones ending 0.0001-0.99 kg),
    and every refit holds p2's length at its start and its damper at 0."""
    converged, held = 0, 0
    for seed in range(1, 14):
        case = _one_mode_record(tmp_path / str(seed), seed)
        problem = _problem(case, lag="none")
        starts = {e.name: e.initial for e in problem.estimated}
        res = fit(problem, progress=False)
        converged += res.converged
        lo, hi = res.interval("fixed.mass")
        assert lo <= 1.5 <= hi, (seed, res.status, lo, hi)
        if "p2.length" not in res.names:
            held += 1
            assert res.problem.fixed[0]["p2.length"] == pytest.approx(starts["p2.length"])
            assert res.problem.fixed[0]["p2.damping"] == 0.0
            assert res.converged, (seed, res.status)
    assert converged >= 9 and held >= 5, (converged, held)


@pytest.mark.slow  # the first solve diverges (196 iterations, 20 s) before the refit
def test_a_vanished_mode_is_refitted_with_its_parameters_held(one_mode):
    """``fixed,p1,p2`` on the one-mode record: p2's mass ends far from its mode's (here
    0.51 kg, the first solve diverging), and the fit is refitted with p2's length and spring
    held at their starts and its damper at 0. p2's mass stays estimated, on its bound, with
    a one-sided limit under 2 % of the first mode's; the intervals of the fixed mass, the
    first mode's mass and length hold the truth."""
    case, truth = one_mode
    problem = _problem(case, lag="none")
    starts = {e.name: e.initial for e in problem.estimated}
    res = fit(problem, progress=False)
    assert res.converged, (res.status, res.iterations)
    assert "p2.mass" in res.names
    for name in ("p2.length", "p2.damping", "p2.stiffness"):
        assert name not in res.names
    held = res.problem.fixed[0]
    assert held["p2.length"] == pytest.approx(starts["p2.length"])
    assert held["p2.damping"] == 0.0
    note = next(n for n in res.problem.notes if "does not determine" in n)
    assert "p2.mass" in note and "p2.length" in note
    assert res.at_bound[res.names.index("p2.mass")] == "lower"
    assert res.one_sided_limit("p2.mass") < 0.02 * truth["p1.mass"]
    for name in ("fixed.mass", "p1.mass", "p1.length"):
        lo, hi = res.interval(name)
        assert lo <= truth[name] <= hi, (name, lo, hi, truth[name])


def test_held_refit_needs_a_vanished_mass(one_mode):
    """Nothing to hold when every mass is above 1 % of its start; the note names the
    vanished mode, the values held (its damper at 0) and the stalled fit's status."""
    problem = _problem(one_mode[0], lag="none")
    theta = problem.initial.copy()
    assert held_refit(problem, theta, "Stalled", 20) is None
    theta[problem.names.index("p2.mass")] = 1e-6
    held, note = held_refit(problem, theta, "Stalled", 20)
    assert "p2.mass" in held.names and "p2.length" not in held.names
    assert "p2.mass went to 1e-06" in note and "Stalled after 20 iterations" in note
    assert held.fixed[0]["p2.damping"] == 0.0
    assert "p1.length" in held.names and "p2.mass" in held.names


def test_a_mass_far_above_its_mode_is_refitted_from_the_start_with_its_mode_held(one_mode):
    """p2 at 0.9 kg (19 x its tank mode's 0.048 kg) after a fit that did not converge: held
    like a vanished one (length and spring at their starts, damper at 0), and every estimate
    restarted where the fit began; the note says how heavy it went and the status. At 2 x
    its mode (under ``PREDICTION_FACTOR``) nothing is held."""
    from estimate.fitting.initial import PREDICTION_FACTOR

    problem = _problem(one_mode[0], lag="none")
    theta = problem.initial.copy()
    k = problem.names.index("p2.mass")
    predicted = problem.estimated[k].initial
    theta[k] = 2.0 * predicted
    assert 2.0 < PREDICTION_FACTOR and held_refit(problem, theta, "Invalid_Number_Detected",
                                                  196) is None
    theta[k] = 0.9
    theta[problem.names.index("fixed.mass")] = 0.5
    held, note = held_refit(problem, theta, "Invalid_Number_Detected", 196)
    assert "p2.length" not in held.names and "p2.stiffness" not in held.names
    assert held.fixed[0]["p2.damping"] == 0.0
    assert held.fixed[0]["p2.length"] == pytest.approx(problem.estimated[
        problem.names.index("p2.length")].initial)
    start = dict(zip(held.names, held.initial))
    assert start["fixed.mass"] == pytest.approx(problem.initial[problem.names.index("fixed.mass")])
    assert start["p2.mass"] == pytest.approx(predicted)
    assert "p2.mass went to 0.9 kg" in note and "Invalid_Number_Detected after 196" in note
