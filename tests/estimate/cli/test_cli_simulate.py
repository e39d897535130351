"""``slosh simulate``: same numbers as the Python API, and clear errors."""

import json
import shutil
import subprocess

import numpy as np
import pytest

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import Adaptive, Sine, simulate
from estimate.cli import main
from estimate.data import load_case, write_case
from estimate.data.case import Liquid, Rig, Tank, TestInfo

PARAMS = {"fixed.mass": 1.456, "p1.mass": 1.338, "p1.length": 0.057, "p1.stiffness": 0.0,
          "p1.damping": 1e-4}
SINE = Sine(0.005, 1.855)


@pytest.fixture()
def case_file(tmp_path):
    t = np.arange(1001) * 0.01
    write_case(tmp_path / "c1.toml",
               test=TestInfo(id="c1", rig="lateral", data="c1.csv", excitation="measured"),
               tank=Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False),
               liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
               rig=Rig(dry_mass=1.2, gravity=9.80665),
               time=t, displacement=SINE.values(t)[0], force=np.zeros_like(t))
    (tmp_path / "params.json").write_text(json.dumps(PARAMS))
    return tmp_path / "c1.toml"


def _read(path):
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert path.read_text().splitlines()[0] == "time,force"
    return data[:, 0], data[:, 1]


def test_cli_reproduces_the_python_api(case_file, tmp_path):
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(case_file), "--params", str(tmp_path / "params.json"),
                 "--out", str(out)]) == 0
    t, force = _read(out)
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
    ref = simulate(model, {**PARAMS, "rig.dry_mass": 1.2}, t, SINE, integrator=Adaptive())
    # the CLI differentiates the sampled displacement (zero-phase smoothing, then splines);
    # against the analytic sine this costs well under 0.1 % of the force
    err = np.sqrt(np.mean((force - ref.output("force_x")) ** 2) / np.mean(ref.output("force_x") ** 2))
    assert err < 1e-3
    assert np.array_equal(t, load_case(case_file).time)


def test_console_script_runs(case_file, tmp_path):
    exe = shutil.which("slosh")
    if exe is None:
        pytest.skip("the `slosh` console script is not installed (pip install -e .)")
    out = tmp_path / "sim2.csv"
    subprocess.run([exe, "simulate", str(case_file), "--params", str(tmp_path / "params.json"),
                    "--out", str(out)], check=True, capture_output=True)
    assert _read(out)[1].size == 1001


def test_bad_case_path_is_named(tmp_path, capsys):
    (tmp_path / "p.json").write_text(json.dumps(PARAMS))
    code = main(["simulate", str(tmp_path / "nope.toml"), "--params", str(tmp_path / "p.json"),
                 "--out", str(tmp_path / "o.csv")])
    assert code == 2
    err = capsys.readouterr().err
    assert "nope.toml" in err and "not found" in err and err.count("error:") == 1


def test_missing_parameter_is_named(case_file, tmp_path, capsys):
    p = tmp_path / "missing.json"
    p.write_text(json.dumps({k: v for k, v in PARAMS.items() if k != "p1.length"}))
    assert main(["simulate", str(case_file), "--params", str(p), "--out", str(tmp_path / "o.csv")]) == 2
    assert "missing parameter `p1.length` (m)" in capsys.readouterr().err


def test_unknown_parameter_is_named(case_file, tmp_path, capsys):
    p = tmp_path / "unknown.json"
    p.write_text(json.dumps({**PARAMS, "p1.lenght": 0.05}))
    assert main(["simulate", str(case_file), "--params", str(p), "--out", str(tmp_path / "o.csv")]) == 2
    assert "unknown parameter `p1.lenght`" in capsys.readouterr().err


def test_existing_output_is_not_overwritten_without_asking(case_file, tmp_path, capsys):
    out = tmp_path / "keep.csv"
    out.write_text("precious\n")
    args = ["simulate", str(case_file), "--params", str(tmp_path / "params.json"), "--out", str(out)]
    assert main(args) == 2
    assert out.read_text() == "precious\n"
    assert "--overwrite" in capsys.readouterr().err
    assert main(args + ["--overwrite"]) == 0


def test_fit_result_json_is_accepted_as_params(case_file, tmp_path):
    fit = {"model": ["fixed", "p1"],
           "parameters": {k: {"value": v, "stderr": 0.0, "unit": "-"} for k, v in PARAMS.items()}}
    (tmp_path / "fit.json").write_text(json.dumps(fit))
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    main(["simulate", str(case_file), "--params", str(tmp_path / "params.json"), "--out", str(a)])
    main(["simulate", str(case_file), "--params", str(tmp_path / "fit.json"), "--out", str(b)])
    assert a.read_text() == b.read_text()
