"""Multiple shooting with a node every few samples (:mod:`estimate.fitting.condensed`)
is the same discrete model as a node at every sample: the same RK4 steps on the same
grid. Its fit must reach the same optimum, and the number of samples per interval follows
the sample rate."""

from __future__ import annotations

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import make_case, pendulum

from estimate import FitProblem, fit, model_from_spec
from estimate.fitting.condensed import padded_grid
from estimate.fitting.transcription import MultipleShooting, interval_samples


@pytest.mark.parametrize("mode, start", [("estimated", "rest"), ("filtered", "free")])
def test_condensed_fit_reaches_the_node_per_sample_optimum(tmp_path, mode, start):
    """A 4 s, 200 Hz record fitted with a node at every sample and with one every 4
    (the last interval padded): the estimates agree within 1e-3 of their standard errors
    and the standard errors within 0.1 % (IPOPT stops at a relative tolerance of 1e-6;
    a different discrete model would move them by a sizeable fraction of a standard
    error)."""
    case, _ = make_case(tmp_path, "c", ref.Ramped(ref.Sine(0.003, 2.1), 1.0, 0.0),
                        pendulums=[pendulum()], duration=4.0, rate=200.0, seed=7)
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case), input=mode)
    one = fit(problem, transcription=MultipleShooting(samples_per_interval=1),
              initial_state=start, progress=False)
    four = fit(problem, transcription=MultipleShooting(samples_per_interval=4),
               initial_state=start, progress=False)
    assert one.names == four.names and one.converged and four.converged
    ok = np.isfinite(one.stderr) & (one.stderr > 0)
    assert ok.sum() >= 4
    dz = np.abs(four.values[ok] - one.values[ok]) / one.stderr[ok]
    assert dz.max() < 1e-3, dict(zip(np.asarray(one.names)[ok], dz))
    assert np.allclose(four.stderr[ok], one.stderr[ok], rtol=1e-3)


@pytest.mark.parametrize("rate, n, expected", [(500.0, 30001, 10), (100.0, 3001, 2),
                                               (50.0, 3001, 1), (2000.0, 60001, 16),
                                               (500.0, 9, 4), (500.0, 4, 1)])
def test_samples_per_interval_follow_the_sample_rate(rate, n, expected):
    """20 ms intervals (at most 16 samples, at least two intervals per record)."""
    assert interval_samples(np.arange(n) / rate) == expected


def test_padded_grid_ends_with_zero_length_steps():
    t = np.arange(11) * 0.01  # 10 steps in intervals of 4: 12 steps, the last 2 of h = 0
    m, tk, hk = padded_grid(t, 4)
    assert m == 3 and tk.size == hk.size == 12
    assert np.allclose(hk[:10], 0.01) and np.all(hk[10:] == 0.0)
    assert np.allclose(tk[:10], t[:-1]) and np.all(tk[10:] == t[-1])


def test_condensed_carriage_inputs_are_the_spline_without_its_stage_matrix(tmp_path,
                                                                           monkeypatch):
    """With an estimated carriage motion the condensed shooting makes the stage and
    sample inputs from each interval's window of coefficients: the carriage motion it
    reports at the samples is SciPy's B-spline of the fitted coefficients (displacement,
    velocity, acceleration to 1e-9 of their ranges: round-off of a sum of six products),
    and the sparse CasADi stage matrix (1.6 million entries on a 30,001-sample record)
    was never made."""
    case, _ = make_case(tmp_path, "c", ref.Ramped(ref.Sine(0.003, 2.1), 1.0, 0.0),
                        pendulums=[pendulum()], duration=4.0, rate=200.0, seed=7)
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case), input="estimated")
    carriage = problem.carriage[0]
    made = []
    convert = type(carriage).casadi_matrix
    monkeypatch.setattr(type(carriage), "casadi_matrix",
                        lambda self, *a: made.append(a[-1]) or convert(self, *a))
    res = fit(problem, transcription=MultipleShooting(samples_per_interval=4),
              progress=False)
    t = np.asarray(case.time, float)
    spline = carriage.values(res.carriage_coefficients[0], t)
    got = np.asarray(res.carriage[0])
    assert got.shape == spline.shape == (3, t.size)
    span = np.ptp(spline, axis=1, keepdims=True)
    assert np.max(np.abs(got - spline) / span) < 1e-9
    assert "stage" not in made and "displacement" in made


def test_window_bases_only_for_the_stage_inputs_the_step_depends_on(tmp_path):
    """The lateral rig's pendulum takes the carriage acceleration, not its position or
    velocity: of the step's stage inputs ``[x, xd, xdd]`` at RK4's three stage times only
    the accelerations (rows 2, 5, 8) are used. Checked numerically: the step's result
    does not move when the other rows change, and moves when an acceleration does."""
    from derive import rk4_step
    from estimate.fitting.condensed import used_stage_inputs

    case, _ = make_case(tmp_path, "c", ref.Ramped(ref.Sine(0.003, 2.1), 1.0, 0.0),
                        pendulums=[pendulum()], duration=2.0, rate=200.0, seed=7)
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case))
    dm = problem.experiments[0].derived
    assert used_stage_inputs(dm, 1) == (2, 5, 8)
    step = rk4_step(dm, 1)
    rng = np.random.default_rng(3)
    x = np.array([0.1, -0.3])
    p = dm.parameter_vector(problem.case_values(0, problem.initial))
    U = rng.normal(size=9)
    base = np.asarray(step(x, U, p, 0.0, 0.005)).ravel()
    for i in range(9):
        V = U.copy()
        V[i] += 1.0
        moved = np.abs(np.asarray(step(x, V, p, 0.0, 0.005)).ravel() - base).max()
        assert (moved > 1e-9) == (i in (2, 5, 8)), (i, moved)


def _sine_record(folder, ratio: float, amplitude: float):
    """A 30 s, 100 Hz record from rest of a sine at ``ratio`` times the first mode
    (bench_fit's reference simulator and noise)."""
    truth = pendulum()
    f1 = ref.natural_frequency(truth, 9.80665) / (2 * np.pi)
    case, _ = make_case(folder, "s", ref.Ramped(ref.Sine(amplitude, ratio * f1), 1.5),
                        pendulums=[truth], duration=30.0, rate=100.0, seed=3)
    return case


def test_a_one_mode_fit_is_solved_on_80_ms_nodes_at_the_default_grids_optimum(tmp_path):
    """The default fit of ``fixed,p1`` on a 100 Hz record runs on a node every 8 samples
    (80 ms, :data:`~estimate.fitting.nlp.COARSE_INTERVAL_SECONDS`), converges there and
    reaches the default 20 ms grid's optimum: estimates within 1e-3 of their standard
    errors, standard errors within 0.1 % (the same discrete model: only IPOPT's tolerance
    separates them)."""
    case = _sine_record(tmp_path, 0.9, 0.0025)
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case))
    coarse = fit(problem, progress=False)
    fine = fit(problem, transcription=MultipleShooting(samples_per_interval=2), progress=False)
    assert "samples_per_interval=8" in coarse.transcription, coarse.transcription
    assert "samples_per_interval=2" in fine.transcription
    assert coarse.converged and fine.converged
    assert not any("solved first with a node every" in n for n in coarse.problem.notes)
    ok = np.isfinite(fine.stderr) & (fine.stderr > 0)
    assert ok.sum() >= 4
    dz = np.abs(coarse.values[ok] - fine.values[ok]) / fine.stderr[ok]
    assert dz.max() < 1e-3, dict(zip(np.asarray(fine.names)[ok], dz))
    assert np.allclose(coarse.stderr[ok], fine.stderr[ok], rtol=1e-3)


def test_a_coarse_solve_that_wanders_is_solved_again_on_the_default_grid(tmp_path):
    """A 4 mm sine at 0.4 f1: the pendulum swings almost with the tank, its length and
    hinge spring confounded; on 80 ms nodes IPOPT wanders (300 iterations, measured) and
    on the default grid it converges (26). The fit stops the coarse solve at
    :data:`~estimate.fitting.nlp.COARSE_MAX_ITER` iterations, solves on the default grid
    from the same start, says so, and ends where the default grid alone ends (to 1e-3 of
    a standard error)."""
    from estimate.fitting.nlp import COARSE_MAX_ITER

    case = _sine_record(tmp_path, 0.4, 0.004)
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case))
    res = fit(problem, progress=False)
    fine = fit(problem, transcription=MultipleShooting(samples_per_interval=2), progress=False)
    assert res.converged and fine.converged, (res.status, fine.status)
    assert any("solved first with a node every 80 ms" in n for n in res.problem.notes)
    assert "samples_per_interval=2" in res.transcription
    assert res.iterations == fine.iterations + COARSE_MAX_ITER
    ok = np.isfinite(fine.stderr) & (fine.stderr > 0)
    dz = np.abs(res.values[ok] - fine.values[ok]) / fine.stderr[ok]
    assert dz.max() < 1e-3, dict(zip(np.asarray(fine.names)[ok], dz))


def test_models_with_more_modes_keep_the_default_grid(tmp_path):
    """``fixed,p1,p2`` (four states) is not solved on the coarse grid: a mode the record
    lacks wandered off there (the slow vanished-mode tests failed on 80 ms nodes)."""
    case = _sine_record(tmp_path, 0.9, 0.0025)
    problem = FitProblem.build(case, model_from_spec("fixed,p1,p2", case))
    from estimate.fitting.nlp import Hessian, _coarse

    assert _coarse(problem, MultipleShooting(), Hessian()) is None
    one = FitProblem.build(case, model_from_spec("fixed,p1", case))
    assert _coarse(one, MultipleShooting(), Hessian()).interval_samples(case.time) == 8
    assert _coarse(one, MultipleShooting(samples_per_interval=2), Hessian()) is None
    assert _coarse(one, MultipleShooting(), Hessian("exact")) is None
