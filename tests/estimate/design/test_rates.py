"""A rig sampling faster than 200 Hz: the drive file keeps the rig's rate, the record is
predicted on a grid decimated to 200 Hz with each sample standing for the ones it
replaces (noise / sqrt(k)), and that predicts the information of the full-rate record."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from estimate import load_case, write_case
from estimate.data.case import Limits
from estimate.design import DesignProblem, SteadySine
from estimate.design.information import motion_inputs, sensitivities
from estimate.design.search import evaluate

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
LIMITS = Limits(stroke=0.1, velocity=0.3, acceleration=2.0, duration=30.0)


def _fit(path: Path) -> Path:
    """A hand-made fit of the bundled example: its truth, a covariance with the two masses
    confounded, the noise the example was made with."""
    names = ["fixed.mass", "p1.mass", "p1.length", "p1.damping"]
    values = [1.5, 1.3, 0.05529, 1.06e-3]
    sd = np.array([0.037, 0.032, 2e-4, 3e-5])
    R = np.eye(4)
    R[0, 1] = R[1, 0] = -0.995
    path.write_text(json.dumps({
        "model_spec": "fixed,p1:nospring",
        "parameters": {n: {"value": v, "estimated": True} for n, v in zip(names, values)},
        "covariance": {"parameters": names, "matrix": (R * np.outer(sd, sd)).tolist()},
        "derived": {"p1.frequency_hz": 2.1196},
        "noise": [{"force_noise_N": 0.0755, "displacement_noise_m": 2e-5}]}))
    return path


def test_fast_rig_is_predicted_on_a_decimated_grid(tmp_path):
    case = load_case(EXAMPLES / "A1.toml")
    t = np.arange(int(30 * 400) + 1) / 400.0  # the example resampled at 400 Hz
    fast = write_case(tmp_path / "F.toml", test=replace(case.test, id="F", data="F.csv"),
                      tank=case.tank, liquid=case.liquid, rig=replace(case.rig, limits=LIMITS),
                      time=t, force=CubicSpline(case.time, case.force)(t),
                      displacement=CubicSpline(case.time, case.displacement)(t))
    problem = DesignProblem.build(_fit(tmp_path / "fit.json"), fast, duration=10.0)
    assert problem.decimation == 2
    assert np.allclose(np.diff(problem.time), 1 / 200) and np.allclose(np.diff(problem.rig_time),
                                                                       1 / 400)
    c = evaluate(problem, SteadySine(LIMITS, 10.0, frequency=1.5))
    predicted = c.record.information(c.noise)
    # the full-rate record of the same drive, every sample with the rig's noise
    tt = problem.rig_time
    half = np.linspace(tt[0], tt[-1], 2 * tt.size - 1)
    sens = sensitivities(problem.derived, problem.names, problem.channels, tt.size - 1)
    full = sens(problem.values, motion_inputs(c.drive.motion(half)), tt)
    noise = c.noise * np.sqrt(problem.decimation)
    exact = full.information(noise)
    # the sums of J^2 over 2000 and 4000 smooth samples agree to ~1/N of the largest term
    assert np.abs(predicted - exact).max() <= 0.01 * np.abs(exact).max()
    assert np.allclose(np.diag(predicted), np.diag(exact), rtol=0.01)
    assert re.fullmatch(r"steady sine at 1\.5 Hz", c.drive.describe())


def test_the_fitted_record_rate_carries_the_noise_to_the_rig_rate(tmp_path):
    """A fit record says the rate of the record it fitted (``noise[].sample_rate_hz``): its
    noise per sample at 50 Hz (A1 decimated by 2) is a white noise's whose density carries
    over, so a sample of a 400 Hz rig has sqrt(8) times it; a record with no rate (older
    fits) is taken at the rig's."""
    case = load_case(EXAMPLES / "A1.toml")
    t = np.arange(int(30 * 400) + 1) / 400.0
    fast = write_case(tmp_path / "F.toml", test=replace(case.test, id="F", data="F.csv"),
                      tank=case.tank, liquid=case.liquid, rig=replace(case.rig, limits=LIMITS),
                      time=t, force=CubicSpline(case.time, case.force)(t),
                      displacement=CubicSpline(case.time, case.displacement)(t))
    plain = DesignProblem.build(_fit(tmp_path / "fit.json"), fast, duration=10.0)
    raw = json.loads((tmp_path / "fit.json").read_text())
    raw["noise"][0]["sample_rate_hz"] = 50.0
    (tmp_path / "fit50.json").write_text(json.dumps(raw))
    rated = DesignProblem.build(tmp_path / "fit50.json", fast, duration=10.0)
    assert plain.noise[0] == 0.0755 and plain.displacement_noise == 2e-5
    assert rated.noise[0] == np.float64(0.0755 * np.sqrt(8.0))
    assert rated.displacement_noise == 2e-5 * np.sqrt(8.0)
    assert any("per sample at the rig's 400 Hz from the fitted record's 50 Hz: times 2.83"
               in n for n in rated.notes)


def test_a_decimated_case_designs_at_its_rig_rate(tmp_path):
    """The case of a record decimated by 4 (``[test] decimate``, 400 -> 100 Hz): the drive
    file keeps the rig's 400 Hz, and the noise of a fit of that record (per 100 Hz sample)
    is carried to it."""
    case = load_case(EXAMPLES / "A1.toml")
    t = np.arange(int(30 * 400) + 1) / 400.0
    write_case(tmp_path / "F.toml", test=replace(case.test, id="F", data="F.csv", decimate=4),
               tank=case.tank, liquid=case.liquid, rig=replace(case.rig, limits=LIMITS),
               time=t, force=CubicSpline(case.time, case.force)(t),
               displacement=CubicSpline(case.time, case.displacement)(t))
    fast = load_case(tmp_path / "F.toml")
    assert fast.time.size == 3001
    raw = json.loads(_fit(tmp_path / "fit.json").read_text())
    raw["noise"][0]["sample_rate_hz"] = 100.0
    (tmp_path / "fit100.json").write_text(json.dumps(raw))
    problem = DesignProblem.build(tmp_path / "fit100.json", fast, duration=10.0)
    assert problem.rate == 400.0 and np.allclose(np.diff(problem.rig_time), 1 / 400)
    assert problem.noise[0] == np.float64(0.0755 * 2.0)
