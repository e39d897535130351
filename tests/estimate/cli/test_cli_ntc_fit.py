"""`slosh ntc SPACECRAFT.toml --fit FIT.json`: the tank's analog from a fit record gives the
same nutation time constant as the spacecraft file written by hand with the fit's numbers."""

import json
from pathlib import Path

import pytest

from analogs.errors import InputError
from estimate.cli import main
from estimate.cli.ntc import analog_tables

ROOT = Path(__file__).resolve().parents[3]
A1 = str(ROOT / "examples" / "A1.toml")
#: A small spinning bus (the tank's analog matters), its centre of mass held (a cheaper
#: derivation), the tank 0.3 m off the spin axis.
BUS = """[spacecraft]
spin_rate = 5.0
mass = 30.0
inertia_x = 2.0
inertia_y = 2.1
inertia_z = 3.0
translation = false

[tank]
radius = 0.3
height = 0.1
axis = "inward"
"""
#: What a lateral record does not determine, given on the command line.
SET = {"p1.hinge_height": 0.15, "fixed.height": 0.1, "fixed.inertia": 0.004,
       "fixed.axial_inertia": 0.006}


@pytest.fixture(scope="module")
def fit_json(tmp_path_factory):
    out = tmp_path_factory.mktemp("ntcfit") / "A1_fit.json"
    assert main(["fit", A1, "--model", "fixed,p1:nospring", "--json", str(out)]) == 0
    return out


def _set_options() -> list[str]:
    return [x for k, v in SET.items() for x in ("--set", f"{k}={v!r}")]


def test_a_fit_gives_the_ntc_of_its_spacecraft_file(fit_json, tmp_path, capsys):
    spacecraft = tmp_path / "bus.toml"
    spacecraft.write_text(BUS + '\n[[analog]]\ntype = "rotor"\nname = "r9"\ninertia = 0.1\n')
    a = tmp_path / "from_fit.json"
    assert main(["ntc", str(spacecraft), "--fit", str(fit_json), *_set_options(),
                 "--json", str(a)]) == 0
    err = capsys.readouterr().err
    assert "its 1 [[analog]] table(s) are replaced by the analog of" in err
    # the same spacecraft written by hand from the fit record's numbers
    p = json.loads(fit_json.read_text())["parameters"]
    by_hand = tmp_path / "by_hand.toml"
    by_hand.write_text(BUS + f"""
[[analog]]
type = "fixed_mass"
name = "fixed"
mass = {p["fixed.mass"]["value"]!r}
height = 0.1
inertia = 0.004
axial_inertia = 0.006

[[analog]]
type = "spherical_pendulum"
name = "p1"
mass = {p["p1.mass"]["value"]!r}
length = {p["p1.length"]["value"]!r}
hinge_height = 0.15
damping = {p["p1.damping"]["value"]!r}
""")
    b = tmp_path / "by_hand.json"
    assert main(["ntc", str(by_hand), "--json", str(b)]) == 0
    ja, jb = json.loads(a.read_text()), json.loads(b.read_text())
    assert ja["ntc_linearized_s"] == pytest.approx(jb["ntc_linearized_s"], rel=1e-12)
    assert ja["ntc_simulated_s"] == pytest.approx(jb["ntc_simulated_s"], rel=1e-9)
    assert ja["ntc_linearized_s"] < 0  # oblate: the fitted hinge damping damps the nutation
    assert [t["type"] for t in ja["analog_from_fit"]["analogs"]] == ["fixed_mass",
                                                                     "spherical_pendulum"]


def test_what_the_fit_does_not_give_is_named_at_once(fit_json, tmp_path, capsys):
    spacecraft = tmp_path / "bus.toml"
    spacecraft.write_text(BUS)
    assert main(["ntc", str(spacecraft), "--fit", str(fit_json), "--set",
                 "p1.hinge_height=0.15"]) == 2
    err = capsys.readouterr().err
    assert "does not give `fixed.height`, `fixed.inertia`, `fixed.axial_inertia` (a lateral " \
           "record does not determine them): give each with --set NAME=VALUE" in err
    assert main(["ntc", str(spacecraft), "--fit", str(fit_json), *_set_options(),
                 "--set", "p1.colour=3"]) == 2
    assert "--set p1.colour: not a value of the analog of" in capsys.readouterr().err
    assert main(["ntc", str(spacecraft), "--set", "p1.mass=1"]) == 2
    assert "use it with `--fit FIT.json`" in capsys.readouterr().err


def test_an_analog_with_no_spacecraft_form_is_refused():
    values = {"fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.055, "p1.damping": 1e-3,
              "p1.quadratic_damping": 1e-4} | SET
    with pytest.raises(InputError, match=r"`p1` carries a QuadraticDamper, which the "
                                         r"spacecraft's analogs do not have"):
        analog_tables("fixed,p1:nospring:quadratic", values)
    tables = analog_tables("fixed,p1", values | {"p1.stiffness": 0.02})
    assert tables[1] == {"type": "spherical_pendulum", "name": "p1", "mass": 1.3,
                         "length": 0.055, "hinge_height": 0.15, "damping": 1e-3,
                         "stiffness": 0.02}
