"""`slosh export` without a C compiler: the sources are written and the output says so;
an FMU, which holds a compiled binary, is a one-line error before anything is written."""

import importlib
from pathlib import Path

import pytest

from estimate.cli import main

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


@pytest.fixture
def no_compiler(monkeypatch):
    # the module, not the function `derive.export_c` that the package re-exports
    module = importlib.import_module("derive.export_c")
    monkeypatch.setattr(module, "has_c_compiler", lambda: False)


def test_export_without_a_compiler_says_it_wrote_sources_only(no_compiler, tmp_path, capsys):
    out = tmp_path / "model_c"
    assert main(["export", str(EXAMPLES / "A1_params.json"), "--set", "rig.dry_mass=1.2",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "no C compiler found" in text and "wrote the sources only" in text, text
    assert f"make -C {out}" in text
    assert (out / "slosh_model.c").exists() and (out / "Makefile").exists()
    assert not (out / "simulate").exists()


def test_fmu_without_a_compiler_is_one_line_with_status_2(no_compiler, tmp_path, capsys):
    fmu = tmp_path / "analog.fmu"
    assert main(["export", str(EXAMPLES / "A1_params.json"), "--fmu", str(fmu)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"slosh export: error: --fmu {fmu}: an FMU holds a compiled binary "
                          "and no C compiler was found"), err
    assert not fmu.exists()


def test_vehicle_export_of_an_analog_with_no_3d_form_is_one_line(tmp_path, capsys):
    out = tmp_path / "vehicle_c"
    assert main(["export", str(EXAMPLES / "A1_params.json"), "--model", "fixed,p1:quadratic",
                 "--interface", "vehicle", "--out", str(out), "--no-build"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "cannot be made three-dimensional (slosh along tank x and y): QuadraticDamper on " \
           "'p1'" in err and "`--planar`" in err, err
    assert not out.exists()
