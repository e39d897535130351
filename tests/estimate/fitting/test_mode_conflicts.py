"""A fitted pendulum far heavier than the tank's mode of its number is reported, with the
estimates it moves with; one near its prediction is not."""

import math

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import rig_record

from estimate import FitProblem, model_from_spec
from estimate.fitting.initial import predicted_values
from estimate.fitting.mode_conflicts import mode_conflicts


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    case, _, _ = rig_record(tmp_path_factory.mktemp("modes"), "m",
                            lambda f1: ref.Sine(0.0025, 0.9 * f1), seed=3)
    return FitProblem.build(case, model_from_spec("fixed,p1,p2", case))


def _state(problem, p2_factor: float, corr: float):
    """Values at the predictions but ``p2.mass`` at ``p2_factor`` times its own; standard
    errors 2 % of the values; the fixed mass and ``p2.mass`` correlated by ``corr``."""
    pred = predicted_values(problem.experiments[0].case, problem.model)
    names = [e.name for e in problem.estimated]
    theta = np.array([pred.get(e.parameter, e.initial) for e in problem.estimated], float)
    k = names.index("p2.mass")
    theta[k] *= p2_factor
    se = np.maximum(0.02 * np.abs(theta), 1e-9)
    C = np.eye(theta.size)
    C[k, names.index("fixed.mass")] = C[names.index("fixed.mass"), k] = corr
    return theta, se, C * np.outer(se, se), pred, k


def test_a_pendulum_ten_times_its_mode_is_reported_with_what_it_moves_with(problem):
    theta, se, cov, pred, _ = _state(problem, 10.0, -0.95)
    out = mode_conflicts(problem, theta, se, cov, {"p2.frequency_hz": 5.1})
    assert len(out) == 1, out
    f2 = math.sqrt(problem.experiments[0].case.rig.gravity / pred["p2.length"]) / (2 * math.pi)
    assert "`p2` ended as a 5.1 Hz pendulum" in out[0]
    assert f"10 x the tank's mode 2 ({pred['p2.mass']:.3g} kg at {f2:.3g} Hz)" in out[0]
    assert "`fixed.mass` (correlation -0.95)" in out[0]


def test_a_pendulum_near_its_mode_or_undetermined_is_not(problem):
    theta, se, cov, _, k = _state(problem, 1.5, -0.95)  # near its prediction
    assert mode_conflicts(problem, theta, se, cov, {}) == []
    theta, se, cov, _, k = _state(problem, 4.0, -0.95)  # 4x, within two errors of 3x
    se[k] = theta[k] / 3
    assert mode_conflicts(problem, theta, se, cov, {}) == []
