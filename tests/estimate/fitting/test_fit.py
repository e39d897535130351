"""Estimation against synthetic data from the independent reference simulator."""

import math

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import G, make_case, pendulum

from analogs import InputError
from estimate import Collocation, FitProblem, fit, model_from_spec

#: Identifiable parameters within 2 % (issue acceptance) on 1 %-noise data.
RECOVERY = 0.02


@pytest.fixture(scope="module")
def sine_case(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fit")
    truth = pendulum(1.30, 0.0553, 0.01)
    case, _ = make_case(folder, "S1", ref.Sine(0.004, 1.9), pendulums=[truth], fixed_mass=1.50,
                        noise=0.01, seed=1)
    return case, truth


def test_identifiable_parameters_recovered_within_two_percent(sine_case):
    case, truth = sine_case
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case)))
    assert res.converged
    assert res.value("fixed.mass") == pytest.approx(1.50, rel=RECOVERY)
    assert res.value("p1.mass") == pytest.approx(truth.mass, rel=RECOVERY)
    assert res.value("p1.length") == pytest.approx(truth.length, rel=RECOVERY)
    assert res.value("p1.damping") == pytest.approx(truth.damping, rel=RECOVERY)
    f_true = ref.natural_frequency(truth, G) / (2 * math.pi)
    assert res.derived["p1.frequency_hz"][0] == pytest.approx(f_true, rel=RECOVERY / 10)
    assert res.derived["p1.damping_ratio"][0] == pytest.approx(0.01, rel=RECOVERY)
    assert not res.identifiability.groups
    # the fit plot: force panel, residual, spectra, trajectories over the IPOPT iterations
    from estimate.fitting.plots import plot_fit

    fig = plot_fit(res)
    assert len(fig.axes) == 4
    measured_line, simulated_line = fig.axes[0].get_lines()
    assert np.allclose(simulated_line.get_ydata(), res.simulated(0))
    assert [ln.get_label() for ln in fig.axes[3].get_lines()][:len(res.names)] == list(res.names)


def test_length_and_spring_confound_is_reported_with_the_frequency(sine_case):
    case, truth = sine_case
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)))
    groups = [set(g) for g in res.identifiability.groups]
    assert {"p1.length", "p1.stiffness"} in groups
    text = " ".join(res.confounded())
    assert "p1.frequency_hz" in text
    # the identifiable combination is still recovered
    f_true = ref.natural_frequency(truth, G) / (2 * math.pi)
    assert res.derived["p1.frequency_hz"][0] == pytest.approx(f_true, rel=2e-3)
    assert res.value("fixed.mass") == pytest.approx(1.50, rel=RECOVERY)


def test_collocation_and_multiple_shooting_agree(sine_case):
    case, _ = sine_case
    prob = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case))
    ms = fit(prob)
    co = fit(prob, transcription=Collocation(degree=3))
    # both are converged answers to the same data; RK4 at 10 ms vs Radau-3: < 0.1 %
    assert np.allclose(co.values, ms.values, rtol=1e-3)


def test_seed_absolute_value_cost_recovers_the_masses(sine_case):
    case, truth = sine_case
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case),
                               input="filtered"), cost="abs")
    assert res.converged
    assert res.value("fixed.mass") == pytest.approx(1.50, rel=0.05)
    assert res.value("p1.mass") == pytest.approx(truth.mass, rel=0.05)


def test_two_cases_share_physical_parameters(tmp_path):
    truth = pendulum(1.30, 0.0553, 0.01)
    a, _ = make_case(tmp_path, "M1", ref.Sine(0.004, 1.8), pendulums=[truth], fixed_mass=1.5,
                     seed=2, duration=15.0)
    b, _ = make_case(tmp_path, "M2", ref.Sine(0.003, 2.4), pendulums=[truth], fixed_mass=1.5,
                     seed=3, duration=15.0)
    res = fit(FitProblem.build([a, b], model_from_spec("fixed,p1:nospring", a)))
    assert res.converged and res.n_samples == a.time.size + b.time.size
    assert res.value("p1.length") == pytest.approx(truth.length, rel=RECOVERY)
    assert res.value("fixed.mass") == pytest.approx(1.5, rel=RECOVERY)


def test_frozen_mass_crank_workflow_succeeds_from_random_starts(tmp_path):
    mass = 2.842  # the frozen 60 % fill of the seed's 8-inch sphere, kg
    crank = ref.Crank(0.01, 0.15, 1.855, d_omega=0.12, phi0=-0.8)
    case, _ = make_case(tmp_path, "F1", crank, fixed_mass=mass, dry_mass=1.2, noise=0.01,
                        duration=20.0, prediction=None)
    model = model_from_spec("fixed", case)
    rng = np.random.default_rng(7)
    ok = 0
    n = 20
    for _ in range(n):
        start = {"fixed.mass": rng.uniform(1.81, 10.0),  # seed's lower bound 4 lb, up to 10 kg
                 "rig.omega_correction": rng.uniform(-0.5, 0.5),
                 "rig.flywheel_angle": rng.uniform(-2.0, 2.0)}
        res = fit(FitProblem.build(case, model, initial=start))
        ok += res.converged and abs(res.value("fixed.mass") / mass - 1) < 0.005
    assert ok >= 0.95 * n


def test_profile_interval_brackets_the_estimate(sine_case):
    from estimate.fitting.profile import profile_interval

    case, truth = sine_case
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case)))
    lo, hi = profile_interval(res, "fixed.mass")
    wlo, whi = res.interval("fixed.mass")
    assert lo < res.value("fixed.mass") < hi
    # near-linear parameter: the profile interval is close to the Wald one
    assert (hi - lo) == pytest.approx(whi - wlo, rel=0.3)


def test_unknown_parameter_names_are_reported(sine_case):
    case, _ = sine_case
    with pytest.raises(KeyError, match="unknown parameter `p1.lenght`"):
        FitProblem.build(case, model_from_spec("fixed,p1", case), initial={"p1.lenght": 0.05})
    with pytest.raises(ValueError, match="unknown component"):
        model_from_spec("fixed,q1", case)


def test_abs_cost_keeps_the_residual_simulated_minus_measured(sine_case):
    """Under the seed's ``sum((|E| - |S|)^2)`` cost the result still reports the force the
    model simulates at the estimates: ``simulated()`` equals an independent RK4 rollout of
    the same model (the fit's one RK4 step per sample) to 1e-9 relative, and the RMS is that
    of ``simulated - measured``. It failed when the transformed residual was stored."""
    from derive import RK4

    case, _ = sine_case
    problem = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case), input="filtered")
    with pytest.raises(InputError, match="input='filtered'"):
        fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case)), cost="abs")
    res = fit(problem, cost="abs")
    assert res.converged
    exp = res.problem.experiments[0]
    rollout = exp.simulate(res.case_values[0], integrator=RK4()).output("force_x")
    scale = np.max(np.abs(rollout))
    assert np.max(np.abs(res.simulated(0) - rollout)) <= 1e-9 * scale
    r = res.simulated(0) - res.measured[0]
    assert res.rms_residual == pytest.approx(float(np.sqrt(np.mean(r**2))), rel=1e-9)


@pytest.mark.parametrize("order", [("A1", "A1_crank"), ("A1_crank", "A1")])
def test_a_measured_and_a_crank_case_fit_together_in_either_order(order):
    """The bundled measured and crank cases share the physical parameters: each case runs on
    its own rig, the crank corrections belong to the crank case only. Before, the first
    order crashed in derive/simulate.py and the second said the excitation supplies 3
    inputs but the model takes 0. Both fits recover the truth within 1 %."""
    import json
    from pathlib import Path

    from estimate import load_case

    examples = Path(__file__).resolve().parents[3] / "examples"
    truth = json.loads((examples / "A1_truth.json").read_text())["parameters"]
    cases = [load_case(examples / f"{name}.toml") for name in order]
    res = fit(FitProblem.build(cases, model_from_spec("fixed,p1:nospring", cases[0])))
    assert res.converged
    assert [n for n in res.names if "omega_correction" in n] == ["A1_crank:rig.omega_correction"]
    for name in ("fixed.mass", "p1.mass", "p1.length"):
        assert res.value(name) == pytest.approx(truth[name], rel=0.01)


def test_fit_plot_shows_what_it_is_for(tmp_path):
    """The fit plot of the bundled example: measured under a thinner simulated line, zooms,
    a residual axis in N scaled without the start-up, a spectrum in N/sqrt(Hz) with the
    noise floor and the drive and fitted frequencies, relative trajectories over integer
    iterations."""
    from pathlib import Path

    from plot_checks import assert_distinguishable, assert_units, assert_ylim_fits, line, marked

    from estimate import load_case
    from estimate.fitting.plots import plot_fit

    case = load_case(Path(__file__).resolve().parents[3] / "examples" / "A1.toml")
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case)), progress=False)
    fig = plot_fit(res, tmp_path / "fit.png")
    assert (tmp_path / "fit.png").stat().st_size > 10_000
    force, resid, spec, traj = fig.axes
    for ax in (force, resid, spec, traj):
        assert_units(ax, x=ax is not force)
    assert force.get_ylabel() == "force_x [N]" and resid.get_ylabel() == "residual [N]"
    assert spec.get_ylabel() == "amplitude density [N/sqrt(Hz)]"
    meas, sim = line(force, "measured"), line(force, "simulated")
    assert_distinguishable(meas, sim)
    assert len(force.child_axes) == 2  # zooms: the start-up and the steady end
    for inset in force.child_axes:  # readable at the saved size
        assert inset.title.get_fontsize() >= 8
        assert all(lb.get_fontsize() >= 7 for lb in inset.get_xticklabels())
    # the model as fitted: without its hinge spring
    assert fig.get_suptitle().startswith("A1: fixed,p1:nospring - RMS residual")
    # the residual axis: set by the residual after the start-up, the start-up peak named
    t, r = case.time, res.residuals[0]
    steady = t > t[0] + 2.0
    assert_ylim_fits(resid, r[steady], 3.0)
    assert resid.get_ylim()[1] < np.max(np.abs(r))  # the start-up spike does not set the scale
    # the spectrum: drive and fitted mode marked, noise floor drawn, data's range only
    # crank at 1.855 Hz nominal plus d_omega = 0.04 rad/s (examples/A1_truth.json)
    assert marked(spec, "drive") == [pytest.approx(1.855 + 0.04 / (2 * math.pi), rel=1e-3)]
    assert marked(spec, "mode p1") == [pytest.approx(res.derived["p1.frequency_hz"][0])]
    assert [ln for ln in spec.get_lines() if ln.get_gid() == "noise floor"]
    densities = np.concatenate([ln.get_ydata() for ln in spec.get_lines()[:2]])
    assert_ylim_fits(spec, densities[densities > 0], 1.5)
    # trajectories: relative change (%) on a linear axis, integer iterations
    assert traj.get_yscale() == "linear" and "[%]" in traj.get_ylabel()
    ticks = [tk for tk in traj.get_xticks() if traj.get_xlim()[0] <= tk <= traj.get_xlim()[1]]
    assert all(float(tk).is_integer() for tk in ticks)
    assert all(ln.get_ydata()[-1] == pytest.approx(0.0, abs=1e-9) for ln in traj.get_lines()[:len(res.names)])
