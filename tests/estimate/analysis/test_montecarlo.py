"""Monte Carlo: draws follow the fit covariance within bounds, each simulated draw equals
``simulate`` with its parameters, and results are identical with the local executor and a
two-worker Dask LocalCluster for the same seed."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import RK4, Sine, derive, simulate
from estimate.analysis.montecarlo import Fit, draw_parameters, monte_carlo, read_fit
from estimate.executor import LocalExecutor

#: Mean and covariance of 40000 draws: standard errors are ~0.5 % of sigma for the mean
#: and ~0.7 % of the variance; 5 % leaves room for every seed.
SAMPLE_MOMENTS = 0.05
#: A Monte Carlo draw runs the same RK4 as simulate, batched: rounding only.
SAME_ARITHMETIC = 1e-12

COV_NAMES = ("fixed.mass", "p1.mass", "p1.length", "p1.damping")
COV = np.array([[1e-4, -5e-5, 0, 0], [-5e-5, 1e-4, 0, 0], [0, 0, 2.5e-7, 0], [0, 0, 0, 2.5e-9]])


def fit_json(path, *, cov=COV, lower_length=0.0456, upper_length=0.0684):
    def entry(value, unit, lower, upper, estimated=True, stderr=0.01):
        return {"value": value, "stderr": stderr if estimated else None, "unit": unit,
                "lower": lower, "upper": upper, "estimated": estimated}

    data = {
        "model": ["fixed", "p1"], "model_spec": "fixed,p1", "case": "A1.toml",
        "parameters": {
            "fixed.mass": entry(1.5, "kg", 1e-9, math.inf),
            "p1.mass": entry(1.3, "kg", 1e-9, math.inf),
            "p1.length": entry(0.05529, "m", lower_length, upper_length),
            "p1.stiffness": entry(0.0, "N m/rad", 0.0, math.inf, estimated=False),
            "p1.damping": entry(0.00106, "N m s/rad", 0.0, math.inf),
            "rig.dry_mass": entry(1.2, "kg", 0.0, math.inf, estimated=False),
            "rig.gravity": entry(9.80665, "m/s^2", 1e-9, math.inf, estimated=False),
        },
        "covariance": {"parameters": list(COV_NAMES), "matrix": np.asarray(cov).tolist()},
        "derived": {}, "cost": 0.0, "rms_residual": 0.0, "iterations": 0, "seconds": 0.0,
        "converged": True, "warnings": [],
    }
    path.write_text(json.dumps(data))  # json writes inf as Infinity, as slosh fit does
    return path


@pytest.fixture()
def fit(tmp_path) -> Fit:
    return read_fit(fit_json(tmp_path / "fit.json"))


def baseline():
    return LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")


def test_draws_follow_covariance(fit):
    draws, acceptance = draw_parameters(fit, 40000, seed=1)
    assert draws.shape == (40000, 4)
    mu = np.array([fit.values[n] for n in COV_NAMES])
    sd = np.sqrt(np.diag(COV))
    assert np.all(np.abs(draws.mean(axis=0) - mu) < SAMPLE_MOMENTS * sd)
    emp = np.cov(draws.T)
    assert np.all(np.abs(emp - COV) < SAMPLE_MOMENTS * np.outer(sd, sd))
    assert acceptance > 0.99


def test_draws_respect_bounds_by_rejection(tmp_path):
    # p1.length bounded one standard deviation above the mean: draws above are redrawn
    fit = read_fit(fit_json(tmp_path / "f.json", upper_length=0.05529 + 5e-4))
    draws, acceptance = draw_parameters(fit, 5000, seed=2)
    assert draws[:, 2].max() <= 0.05529 + 5e-4
    assert 0.8 < acceptance < 0.9  # P(z < 1) = 0.841
    again, _ = draw_parameters(fit, 5000, seed=2)
    np.testing.assert_array_equal(draws, again)


def test_draw_errors(tmp_path):
    bad = read_fit(fit_json(tmp_path / "a.json", cov=-COV))
    with pytest.raises(ValueError, match="not positive semi-definite"):
        draw_parameters(bad, 10)
    # rounding asymmetry (a sandwich covariance's 1e-8) is drawn; a real one is refused
    rounded, skew = COV.copy(), COV.copy()
    rounded[0, 1] *= 1 + 2e-8
    skew[0, 1] *= 1.1
    assert draw_parameters(read_fit(fit_json(tmp_path / "r.json", cov=rounded)), 10)[0].shape \
        == (10, 4)
    with pytest.raises(ValueError, match="must be symmetric and finite"):
        draw_parameters(read_fit(fit_json(tmp_path / "s.json", cov=skew)), 10)
    impossible = read_fit(fit_json(tmp_path / "b.json", lower_length=0.07, upper_length=0.0701))
    with pytest.raises(ValueError, match="inside the parameter bounds"):
        draw_parameters(impossible, 10, max_rounds=3)
    (tmp_path / "c.json").write_text('{"parameters": {"p1.mass": {"value": 1}}, '
                                     '"covariance": {"parameters": ["p1.mass"], "matrix": [[1, 0]]}}')
    with pytest.raises(ValueError, match="covariance.matrix must be 1x1.*model_spec|model_spec.*1x1"):
        read_fit(tmp_path / "c.json")


def _problem():
    t = np.linspace(0, 4, 401)
    return derive(baseline()), t, Sine(0.005, 2.0), {"rig.dry_mass": 1.2, "rig.gravity": 9.80665}


def test_each_draw_equals_simulate(fit):
    dm, t, exc, fixed = _problem()
    res = monte_carlo(dm, t, exc, fit, 5, fixed=fixed, seed=3, batch_size=4)
    assert res.outputs["force_x"].shape == (5, t.size)
    for i in (0, 4):
        values = {**{k: v for k, v in fit.values.items() if k in dm.parameter_names}, **fixed,
                  **dict(zip(COV_NAMES, res.draws[i]))}
        sim = simulate(dm, values, t, exc, integrator=RK4())
        ref = sim.output("force_x")
        assert np.max(np.abs(res.outputs["force_x"][i] - ref)) <= SAME_ARITHMETIC * np.max(np.abs(ref))
        assert res.derived["peak_force_x"][i] == pytest.approx(np.max(np.abs(ref)), rel=1e-12)
        g, L = 9.80665, values["p1.length"]
        assert res.derived["p1.frequency_hz"][i] == pytest.approx(math.sqrt(g / L) / (2 * math.pi))
    env = res.envelopes["force_x"]
    assert np.all(env[2.5] <= env[50.0]) and np.all(env[50.0] <= env[97.5])
    data = res.to_json()
    assert data["samples"] == 5 and set(data["envelopes"]["force_x"]) == {"p2.5", "p5", "p50", "p95", "p97.5"}
    assert "p1.frequency_hz" in res.report()


def test_same_seed_identical_on_local_and_dask_cluster(fit):
    distributed = pytest.importorskip("distributed", reason="needs dask.distributed (extra `dask`)")
    from estimate.executor import DaskExecutor

    dm, t, exc, fixed = _problem()
    local = monte_carlo(dm, t, exc, fit, 40, fixed=fixed, seed=11, batch_size=8,
                        executor=LocalExecutor())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        with DaskExecutor(client=client) as ex:
            assert ex.workers == 2
            remote = monte_carlo(dm, t, exc, fit, 40, fixed=fixed, seed=11, batch_size=8,
                                 executor=ex)
    np.testing.assert_array_equal(local.draws, remote.draws)
    np.testing.assert_array_equal(local.outputs["force_x"], remote.outputs["force_x"])
    other = monte_carlo(dm, t, exc, fit, 40, fixed=fixed, seed=12, batch_size=8)
    assert not np.array_equal(other.draws, local.draws)


def test_unknown_covariance_parameter_is_reported(tmp_path):
    dm, t, exc, fixed = _problem()
    fit = read_fit(fit_json(tmp_path / "f.json"))
    fit2 = Fit(**{**fit.__dict__, "covariance_names": ("p9.mass",) + COV_NAMES[1:],
                  "values": {**fit.values, "p9.mass": 1.0}})
    with pytest.raises(ValueError, match="p9.mass are not parameters of the model"):
        monte_carlo(dm, t, exc, fit2, 4, fixed=fixed)


def test_cli_montecarlo_local(tmp_path, capsys):
    from pathlib import Path

    from estimate.cli import main

    examples = Path(__file__).resolve().parents[3] / "examples"
    fit = fit_json(tmp_path / "fit.json")
    out = tmp_path / "mc"
    status = main(["montecarlo", str(fit), str(examples / "A1.toml"), "--samples", "12",
                   "--seed", "5", "--local", "--batch-size", "8", "--out", str(out)])
    assert status == 0
    data = json.loads((out / "montecarlo.json").read_text())
    assert data["samples"] == 12 and data["seed"] == 5
    assert len(data["envelopes"]["force_x"]["p50"]) == len(data["time"])
    assert (out / "envelope.png").stat().st_size > 10_000
    assert "peak_force_x" in capsys.readouterr().out
    assert main(["montecarlo", str(fit), str(examples / "A1.toml"), "--samples", "12",
                 "--local", "--out", str(out)]) == 2  # exists, no --overwrite


def test_draws_leave_a_held_bound_half_normally_with_the_estimates_that_move_with_it(tmp_path):
    """A spring held at 0 with its move off the bound (``covariance.off_bounds``): it is
    drawn as ``|z| s`` (half-normal: mean ``s sqrt(2/pi)``, variance ``s^2 (1 - 2/pi)``) and
    the length moves with it by ``|z| d``, on top of its covariance. The sample moments of
    40,000 draws against those formulas (SAMPLE_MOMENTS of the standard deviations)."""
    path = fit_json(tmp_path / "fit.json")
    data = json.loads(path.read_text())
    data["parameters"]["p1.stiffness"] |= {"estimated": True, "at_bound": "lower"}
    s, d = 0.02, -4e-4
    data["covariance"]["off_bounds"] = [{"bound": "p1.stiffness",
                                         "move": {"p1.stiffness": s, "p1.length": d}}]
    path.write_text(json.dumps(data))
    fit = read_fit(path)
    assert fit.draw_names == (*COV_NAMES, "p1.stiffness")
    draws, acceptance = draw_parameters(fit, 40000, seed=4)
    k, L = draws[:, 4], draws[:, 2]
    assert k.min() >= 0.0
    assert acceptance > 0.99  # drawn off the bound, not half rejected at it
    h_mean, h_var = math.sqrt(2 / math.pi), 1 - 2 / math.pi
    assert abs(k.mean() - s * h_mean) < SAMPLE_MOMENTS * s
    assert abs(k.std() - s * math.sqrt(h_var)) < SAMPLE_MOMENTS * s
    sd_L = math.sqrt(COV[2, 2] + d**2 * h_var)
    assert abs(L.mean() - (0.05529 + d * h_mean)) < SAMPLE_MOMENTS * sd_L
    assert abs(L.std() - sd_L) < SAMPLE_MOMENTS * sd_L
    assert abs(np.cov(k, L)[0, 1] - s * d * h_var) < SAMPLE_MOMENTS * s * sd_L
    # the others keep their covariance
    emp = np.cov(draws[:, :2].T)
    sd = np.sqrt(np.diag(COV[:2, :2]))
    assert np.all(np.abs(emp - COV[:2, :2]) < SAMPLE_MOMENTS * np.outer(sd, sd))


def test_draws_fill_the_span_to_a_mode_at_its_prediction(tmp_path):
    """A pendulum far heavier than its tank mode (``covariance.to_predicted_modes``): with
    ``p1.mass`` put at the prediction the fixed mass takes what it leaves. Every draw moves
    by ``u`` times that shift, ``u`` 0 or 1 with equal odds (mean 1/2, variance 1/4), on top
    of the covariance: the sample moments of 40,000 draws against those formulas
    (SAMPLE_MOMENTS of the standard deviations), and half the draws at each end."""
    path = fit_json(tmp_path / "fit.json")
    data = json.loads(path.read_text())
    shift = {"p1.mass": -0.9, "fixed.mass": 0.8, "p1.length": 2e-3}
    data["covariance"]["to_predicted_modes"] = [{"mode": "`p1.mass` at its tank mode's 0.4 kg",
                                                 "move": shift}]
    path.write_text(json.dumps(data))
    fit = read_fit(path)
    assert fit.draw_names == COV_NAMES
    draws, acceptance = draw_parameters(fit, 40000, seed=5)
    assert acceptance > 0.99
    mean = np.array([1.5, 1.3, 0.05529, 0.00106]) + 0.5 * np.array(
        [shift.get(n, 0.0) for n in COV_NAMES])
    s = np.array([shift.get(n, 0.0) for n in COV_NAMES])
    cov = COV + np.outer(s, s) / 4
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.abs(draws.mean(axis=0) - mean) < SAMPLE_MOMENTS * sd)
    assert np.all(np.abs(np.cov(draws.T) - cov) < SAMPLE_MOMENTS * np.outer(sd, sd))
    fixed = draws[:, 0]
    assert abs(np.mean(fixed > 1.9) - 0.5) < 0.01  # 1.5 and 2.3 kg, sd 0.01 kg each
    # a record without the key draws exactly as before
    plain = read_fit(fit_json(tmp_path / "plain.json"))
    assert plain.to_modes == ()
    bad = json.loads(path.read_text())
    bad["covariance"]["to_predicted_modes"] = [{"mode": 3, "move": shift}]
    path.write_text(json.dumps(bad))
    with pytest.raises(ValueError, match=r"covariance.to_predicted_modes\[0\]`: expected an object "
                                         r"with a \"mode\" string"):
        read_fit(path)


def test_an_estimate_held_on_a_bound_stays_there_when_another_bound_moves_it_through(tmp_path):
    """Two estimates held at bounds (a spring at 0, a length on its band's upper edge): the
    spring's move off its bound raises the length, which the band stops. The length stays on
    its edge in every draw, instead of every draw being rejected."""
    path = fit_json(tmp_path / "fit.json")
    data = json.loads(path.read_text())
    names = ["fixed.mass", "p1.mass", "p1.damping"]
    keep = [COV_NAMES.index(n) for n in names]
    data["covariance"] = {"parameters": names, "matrix": COV[np.ix_(keep, keep)].tolist(),
                          "off_bounds": [{"bound": "p1.stiffness",
                                          "move": {"p1.stiffness": 0.02, "p1.length": 4e-3}}]}
    data["parameters"]["p1.stiffness"] |= {"estimated": True, "at_bound": "lower"}
    data["parameters"]["p1.length"] |= {"value": 0.0684, "at_bound": "upper"}
    path.write_text(json.dumps(data))
    fit = read_fit(path)
    draws, acceptance = draw_parameters(fit, 2000, seed=3)
    assert acceptance > 0.99
    assert np.all(draws[:, fit.draw_names.index("p1.length")] == 0.0684)


def test_a_fit_record_keeps_the_moves_off_its_held_bounds_and_the_draws_reach_its_intervals(
        tmp_path):
    """The bundled example's fit holds the spring at 0 (its intervals reach off the bound,
    the length's most: the frequency fixes g/L + k/(m L^2)). Its record keeps the move off
    the bound: the spring by its one-sided standard deviation, the others by the reach the
    intervals use. The Monte Carlo draws then cover the length's interval: their 97.5th
    percentile lies at or above its upper end (the half-normal reaches 1.96 standard
    deviations where the one-sided limit is 1.645), and every spring draw is >= 0."""
    from pathlib import Path

    from estimate import FitProblem, fit, load_case, model_from_spec

    case = load_case(Path(__file__).resolve().parents[3] / "examples" / "A1.toml")
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)))
    i = res.names.index("p1.stiffness")
    assert res.at_bound[i] == "lower"
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(res.to_dict()))
    record = read_fit(path)
    (label, move), = record.off_bounds
    assert label == "p1.stiffness"
    assert move["p1.stiffness"] == pytest.approx(res.bound_stderr[i], rel=1e-12)
    for j, name in enumerate(res.names):
        if name in move and name not in ("rig.lag", "p1.stiffness"):  # the others
            assert (max(-move[name], 0), max(move[name], 0)) == pytest.approx(
                tuple(res.bound_reach[j]), rel=1e-12)
    draws, _ = draw_parameters(record, 20000, seed=6)
    names = record.draw_names
    assert draws[:, names.index("p1.stiffness")].min() >= 0.0
    length = draws[:, names.index("p1.length")]
    lo, hi = res.interval("p1.length")
    assert hi - lo > 10 * res.stderr[res.names.index("p1.length")]  # the reach dominates
    assert np.percentile(length, 97.5) >= hi


def test_cli_montecarlo_says_the_draws_hold_an_estimate_at_its_bound(tmp_path, capsys):
    """A fit record whose spring was estimated and ended on 0 (written as `slosh fit` does:
    estimated, at_bound, no covariance) without its move off the bound (an older record):
    the draws cannot move it, and the command says so beside the intervals that do; a
    record without a held estimate, or with its move, gets no such warning."""
    from pathlib import Path

    from estimate.cli import main

    examples = Path(__file__).resolve().parents[3] / "examples"
    fit = fit_json(tmp_path / "fit.json")
    run = ["montecarlo", str(fit), str(examples / "A1.toml"), "--samples", "4", "--local"]
    assert main([*run, "--out", str(tmp_path / "a")]) == 0
    assert "ended on a bound" not in capsys.readouterr().err
    data = json.loads(fit.read_text())
    data["parameters"]["p1.stiffness"] |= {"estimated": True, "at_bound": "lower"}
    fit.write_text(json.dumps(data))
    assert main([*run, "--out", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    assert "`p1.stiffness` ended on a bound" in err and "narrower" in err
    data["covariance"]["off_bounds"] = [{"bound": "p1.stiffness",
                                         "move": {"p1.stiffness": 0.02, "p1.length": -4e-4}}]
    fit.write_text(json.dumps(data))
    assert main([*run, "--out", str(tmp_path / "c")]) == 0
    assert "ended on a bound" not in capsys.readouterr().err
    mc = json.loads((tmp_path / "c" / "montecarlo.json").read_text())
    assert "p1.stiffness" in mc["parameters"]
    data["covariance"]["to_predicted_modes"] = [{"mode": "`p1.mass` at its tank mode's 0.4 kg",
                                                 "move": {"p1.mass": -0.9, "fixed.mass": 0.8}}]
    fit.write_text(json.dumps(data))
    assert main([*run, "--out", str(tmp_path / "d")]) == 0
    assert ("half the draws are moved to the refit with `p1.mass` at its tank mode's 0.4 kg"
            in capsys.readouterr().err)


def test_cli_export_c_and_fmu(tmp_path, capsys):
    from derive.export_c import has_c_compiler
    from estimate.cli import main

    fit = fit_json(tmp_path / "fit.json")
    assert main(["export", str(fit)]) == 2
    assert "nothing to write" in capsys.readouterr().err
    # only rk4 can be generated as C: the only choice offered
    with pytest.raises(SystemExit) as stop:
        main(["export", str(fit), "--out", str(tmp_path / "c"), "--integrator", "adaptive"])
    assert stop.value.code == 2
    assert "--integrator: invalid choice: 'adaptive'" in capsys.readouterr().err
    args = ["export", str(fit), "--out", str(tmp_path / "c")]
    if not has_c_compiler():
        args.append("--no-build")
    assert main(args) == 0
    header = (tmp_path / "c" / "slosh_model.h").read_text()
    assert "p1.length" in header and "0.05529" in header
    assert has_c_compiler() is False or (tmp_path / "c" / "simulate").exists()
    assert main(["export", str(fit), "--out", str(tmp_path / "v"), "--interface", "vehicle",
                 "--planar", "--no-build", "--set", "p1.hinge_height=0.1",
                 "--set", "fixed.height=0.05", "--set", "fixed.inertia=0.001"]) == 0
    assert "vehicle.alpha_y" in (tmp_path / "v" / "slosh_model.h").read_text()


def test_a_diaphragm_model_derives_the_same_quantities_in_monte_carlo_and_the_fit(tmp_path):
    """One home per derived quantity: the fit report and the Monte Carlo summary both ask
    the components, so both have the diaphragm terms. The frequency and damping ratio are
    checked against the hand formulas ``w^2 = g/L + (k + k_d)/(m L^2)`` and
    ``zeta = (c + c_d) / (2 m L^2 w)``."""
    from pathlib import Path

    from estimate import FitProblem, fit, load_case, model_from_spec

    case = load_case(Path(__file__).resolve().parents[3] / "examples" / "A1.toml")
    held = {"p1.diaphragm_stiffness": 0.05, "p1.diaphragm_damping": 1e-4}
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:diaphragm", case), hold=held))
    g, m, L = 9.80665, res.value("p1.mass"), res.value("p1.length")
    k, c = res.value("p1.stiffness") + 0.05, res.value("p1.damping") + 1e-4
    w = math.sqrt(g / L + k / (m * L**2))
    assert res.derived["p1.frequency_hz"][0] == pytest.approx(w / (2 * math.pi), rel=1e-12)
    assert res.derived["p1.damping_ratio"][0] == pytest.approx(c / (2 * m * L**2 * w), rel=1e-12)
    assert res.derived_units == {"p1.frequency_hz": "Hz", "p1.damping_ratio": "-"}
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(res.to_dict()))
    exp = res.problem.experiments[0]
    mc = monte_carlo(exp.derived, case.time, exp.excitation, read_fit(path), 8,
                     fixed=exp.fixed, seed=1, executor=LocalExecutor())
    summary = {k for k in mc.summary() if not k.startswith("peak_")}
    assert summary == set(res.derived)
    # the draws scatter around the estimate: the median frequency within 5 standard errors
    # (the spread of the draws when the stiffness ends at its bound of 0, where the
    # frequency has no Wald standard error)
    f, se = res.derived["p1.frequency_hz"]
    spread = mc.summary()["p1.frequency_hz"]["std"]
    assert spread > 0
    assert abs(mc.summary()["p1.frequency_hz"]["p50"] - f) < 5 * (se if math.isfinite(se) else spread)


def test_envelope_plot_shows_the_deviation_from_the_nominal_with_the_measurement(fit):
    """The bands are drawn as deviation from the nominal, on an axis sized by them and the
    measured deviation (not the full force), with the measured trace under the nominal."""
    from plot_checks import assert_distinguishable, assert_units, line

    dm, t, exc, fixed = _problem()
    res = monte_carlo(dm, t, exc, fit, 40, fixed=fixed, seed=3, batch_size=16)
    nominal = res.nominal["force_x"]
    values = {**{k: v for k, v in fit.values.items() if k in dm.parameter_names}, **fixed}
    ref = simulate(dm, values, t, exc, integrator=RK4()).output("force_x")
    assert np.max(np.abs(nominal - ref)) <= SAME_ARITHMETIC * np.max(np.abs(ref))
    measured = ref + 0.01 * np.sin(7.0 * t)  # a "measurement" 0.01 N off the nominal
    fig = res.plot(output="force_x", measured=measured)
    top, dev = fig.axes
    assert_units(top, x=False)
    assert_units(dev)
    assert dev.get_ylabel() == "force_x - nominal [N]"
    assert_distinguishable(line(top, "measured"), line(top, "nominal"))
    env = res.envelopes["force_x"]
    band = max(np.max(np.abs(env[q] - nominal)) for q in (2.5, 97.5))
    lo, hi = dev.get_ylim()
    assert lo == -hi and band <= hi <= 1.5 * max(band, 0.01)  # sized by the bands, all shown
