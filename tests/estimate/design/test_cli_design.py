"""``slosh design`` end to end on the bundled example, and its errors.

The fit is written by hand from the example's truth (``examples/A1_truth.json``) with a
covariance in which the two masses are confounded (correlation -0.995, +/-5 %), so these
tests need no fit; the design itself is short (a 10 s record, sines only).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from estimate.cli import main

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
#: The bundled case file without its `[rig.limits]` table (the tests give their own).
WITHOUT_LIMITS = re.sub(r"\[rig\.limits\]\n(?:[^\[\n][^\n]*\n)*\n?", "",
                        (EXAMPLES / "A1.toml").read_text())
LIMITS = "[rig.limits]\nstroke = 0.1\nvelocity = 0.3\nacceleration = 2.0\nduration = 30.0\n"
VALUES = {"fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.05529, "p1.damping": 1.06e-3}


def _fit_json(path: Path) -> Path:
    names = list(VALUES)
    sd = np.array([0.037, 0.032, 2e-4, 3e-5])
    R = np.eye(4)
    R[0, 1] = R[1, 0] = -0.995
    cov = R * np.outer(sd, sd)
    data = {"schema": "slosh-analogs/fit/2", "model_spec": "fixed,p1:nospring",
            "parameters": {n: {"value": v, "stderr": float(s), "unit": "", "estimated": True}
                           for (n, v), s in zip(VALUES.items(), sd)},
            "covariance": {"parameters": names, "matrix": cov.tolist()},
            "derived": {"p1.frequency_hz": 2.1196},
            "residual_variance": 1.0,
            "noise": [{"force_noise_N": 0.0755, "displacement_noise_m": 2e-5}]}
    path.write_text(json.dumps(data))
    return path


@pytest.fixture()
def folder(tmp_path):
    for name in ("A1.toml", "A1.csv"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    _fit_json(tmp_path / "fit.json")
    return tmp_path


def _with_limits(folder: Path, table: str = LIMITS) -> Path:
    path = folder / "A1.toml"
    path.write_text(WITHOUT_LIMITS + "\n" + table)
    return path


def test_design_writes_json_drive_and_plot(folder, capsys):
    case = _with_limits(folder)
    out = folder / "d.json"
    args = ["design", str(folder / "fit.json"), str(case), "--target", "p1.mass,fixed.mass",
            "--budget", "10s", "--families", "sine", "--json", str(out), "--plot",
            str(folder / "d.png")]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "interval of p1.mass from +/-" in printed
    d = json.loads(out.read_text())
    rec = d["recommended"]
    assert d["duration_s"] == 10.0 and d["targets"] == ["p1.mass", "fixed.mass"]
    assert rec["family"] == "sine"
    assert all(v <= 1.0 for v in rec["limit_ratios"].values())
    assert rec["peak_swing_rad"] <= d["max_swing_rad"]
    for n in d["targets"]:  # the new record narrows both intervals
        assert rec["predicted"][n]["halfwidth_95_relative"] < d["before"][n]["halfwidth_95_relative"]
    # the fit's covariance, as given: +/-1.96 sd / value
    assert d["before"]["p1.mass"]["halfwidth_95_relative"] == pytest.approx(1.96 * 0.032 / 1.3,
                                                                            rel=1e-3)
    csv = np.loadtxt(d["drive_file"], delimiter=",", skiprows=1)
    assert Path(d["drive_file"]).read_text().splitlines()[0] == "time,displacement"
    assert csv.shape == (1001, 2) and np.allclose(np.diff(csv[:, 0]), 0.01)
    assert np.abs(csv[:, 1]).max() <= 0.05
    assert (folder / "d.png").stat().st_size > 10_000
    # no overwrite without --overwrite: the files stay as they were
    before = out.read_bytes()
    assert main(args) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert out.read_bytes() == before


@pytest.mark.parametrize("table, extra, message", [
    ("", [], r"A1.toml: has no `\[rig.limits\]` table; .*`stroke = 0.1` \(m, total carriage "
             r"travel\)"),
    (LIMITS, ["--budget", "45s"], r"--budget 45 s: the rig runs records of at most 30 s"),
    (LIMITS, ["--budget", "soon"], r"--budget: expected a positive duration"),
    (LIMITS, ["--target", "p1.volume"], r"--target: `p1.volume` not estimated by the fit"),
    (LIMITS, ["--max-swing", "2.0"], r"max swing must be in \(0, pi/2\) rad"),
    (LIMITS, ["--families", "square"], r"--families: unknown 'square'"),
])
def test_errors_are_one_line(folder, capsys, table, extra, message):

    case = _with_limits(folder, table)
    status = main(["design", str(folder / "fit.json"), str(case), "--json",
                   str(folder / "d.json"), *extra])
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.count("\n") == 1 and re.search(message, err), err
    assert not (folder / "d.json").exists()


def test_a_crank_rig_is_refused(folder, capsys):
    for name in ("A1_crank.toml", "A1_crank.csv"):
        shutil.copy(EXAMPLES / name, folder / name)
    case = folder / "A1_crank.toml"
    case.write_text(case.read_text() + "\n" + LIMITS)
    status = main(["design", str(folder / "fit.json"), str(case), "--json",
                   str(folder / "d.json")])
    assert status == 2
    assert "a crank rig runs one near-sine per crank setting" in capsys.readouterr().err


def test_discrimination_needs_two_models(folder, capsys):
    case = _with_limits(folder)
    diag = folder / "diag.json"
    params = json.loads((folder / "fit.json").read_text())["parameters"]
    diag.write_text(json.dumps({"baseline": {"parameters": params},
                                "final": {"parameters": params}}))
    status = main(["design", str(folder / "fit.json"), str(case), "--discriminate", str(diag),
                   "--json", str(folder / "d.json")])
    assert status == 2
    assert "there are no two models to tell apart" in capsys.readouterr().err
