"""`slosh ntc`: the example file runs and prints both NTCs; a bad file lists every problem."""

import json
from pathlib import Path

from estimate.cli import main

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "spacecraft.toml"


def test_slosh_ntc_prints_both_methods(tmp_path, capsys):
    out = tmp_path / "ntc.json"
    assert main(["ntc", str(EXAMPLE), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "NTC, nonlinear simulation" in text and "linearised about steady spin" in text
    data = json.loads(out.read_text())
    assert data["relative_difference"] < 0.02  # issue 7 acceptance
    assert data["grows"] is False and data["ntc_linearized_s"] < 0  # oblate: decays


def test_slosh_ntc_reports_every_problem(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[spacecraft]\nspin_rate = "fast"\nmass = 1.0\ncolour = 3\n'
                   '[tank]\naxis = "up"\n[[analog]]\ntype = "propeller"\n')
    assert main(["ntc", str(bad)]) == 2
    err = capsys.readouterr().err
    for piece in ("`spin_rate` must be a number", "missing `inertia_x`", "unknown key `colour`",
                  "`axis` must be", "`type` must be one of", "problems in the spacecraft file"):
        assert piece in err, piece


def test_slosh_ntc_mounts_analogs_off_the_tank_origin(tmp_path, capsys):
    f = tmp_path / "two.toml"
    rotor = 'type = "rotor"\naxis = "x"\ninertia = 0.2\ndamping = 0.2\n'
    f.write_text('[spacecraft]\nspin_rate = 3.0\nmass = 100.0\ninertia_x = 10.0\n'
                 'inertia_y = 10.0\ninertia_z = 15.0\ntranslation = false\n'
                 f'[[analog]]\nname = "rx"\n{rotor}'
                 f'[[analog]]\nname = "ry"\n{rotor}mount_azimuth = 1.5707963267948966\n')
    assert main(["ntc", str(f)]) == 0
    text = capsys.readouterr().out
    assert "Mounted(Rotor('ry'" in text and "Nutation decays" in text
    f.write_text(f.read_text().replace("mount_azimuth = 1.5707963267948966",
                                       'mount_axis = "up"'))
    assert main(["ntc", str(f)]) == 2
    assert "`mount_axis` must be" in capsys.readouterr().err
