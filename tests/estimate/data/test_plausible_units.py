"""A lab file's channel read without a unit whose numbers do not look like SI gets a warning
naming the likely unit (new-user report defect 9: a MAT file in mm and lbf mapped without
units was fitted as metres and newtons, 300 iterations, no hint)."""

import glob
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from estimate.cli import main
from estimate.data import load_case
from estimate.data.plausible_units import ImplausibleUnit, linear_force

pytest.importorskip("pint")
import scipy.io  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
LBF = 4.4482216152605  # N


def _mat(folder: Path, *, mm: bool, lbf: bool, columns: str) -> Path:
    """A1 as a MAT v5 file (scipy.io.savemat), displacement in mm and force in lbf when
    asked, mapped by ``columns``."""
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)
    t, x, f = data.T
    scipy.io.savemat(folder / "A1.mat", {"t": t[:, None], "x": (x * (1e3 if mm else 1))[:, None],
                                         "Fx": (f / (LBF if lbf else 1))[:, None]}, format="5")
    text = (EXAMPLES / "A1.toml").read_text().replace('data = "A1.csv"', 'data = "A1.mat"')
    path = folder / "A1_mat.toml"
    path.write_text(text + "\n[data.columns]\n" + columns)
    return path


def _load(path: Path) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_case(path)
    return [str(w.message) for w in caught if issubclass(w.category, ImplausibleUnit)]


def test_mm_and_lbf_read_as_si_are_named(tmp_path):
    path = _mat(tmp_path, mm=True, lbf=True, columns='time = "t"\ndisplacement = "x"\nforce = "Fx"\n')
    found = _load(path)
    assert len(found) == 2
    assert found[0].startswith("A1.mat: channel `x` ([data.columns] displacement) has no unit and "
                               "a peak-to-peak of 12 m")
    assert "looks like mm (12 mm)" in found[0] and 'unit = "mm"' in found[0]
    assert found[1].startswith("A1.mat: channel `Fx` ([data.columns] force) has no unit")
    assert "looks like lbf" in found[1] and '`force = { channel = "Fx", unit = "lbf" }`' in found[1]


def test_a_force_in_kn_alone_is_named(tmp_path):
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)
    t, x, f = data.T
    scipy.io.savemat(tmp_path / "A1.mat", {"t": t, "x": x, "Fx": f / 1e3}, format="5")
    text = (EXAMPLES / "A1.toml").read_text().replace('data = "A1.csv"', 'data = "A1.mat"')
    (tmp_path / "k.toml").write_text(text + '\n[data.columns]\ntime = "t"\ndisplacement = "x"\n'
                                            'force = "Fx"\n')
    (found,) = _load(tmp_path / "k.toml")
    assert "force) has no unit" in found and "looks like kN" in found


def test_units_given_or_si_numbers_give_no_warning(tmp_path):
    given = _mat(tmp_path, mm=True, lbf=True, columns='time = "t"\n'
                 'displacement = { channel = "x", unit = "mm" }\nforce = { channel = "Fx", unit = "lbf" }\n')
    assert _load(given) == []
    si = _mat(tmp_path, mm=False, lbf=False, columns='time = "t"\ndisplacement = "x"\nforce = "Fx"\n')
    assert _load(si) == []


#: The bundled case files (not the spacecraft or the campaign description).
CASES = sorted(p for p in glob.glob(str(EXAMPLES / "*.toml")) + glob.glob(str(EXAMPLES / "campaign"
                                                                              / "*.toml"))
               if Path(p).stem not in ("spacecraft", "campaign"))


@pytest.mark.parametrize("case", CASES, ids=lambda p: Path(p).stem)
def test_no_bundled_record_in_si_looks_like_another_unit(case):
    """Every bundled lateral record, judged as if none of its channels had a unit."""
    from estimate.data.reader import _unit_warnings

    c = load_case(case)
    if c.test.rig != "lateral" or c.displacement is None:
        pytest.skip("no measured carriage displacement")
    cols = {"displacement": "x", "force": "Fx"}
    assert _unit_warnings(c.data_path.name, cols, (c.time, c.displacement, c.force, {}),
                          c.tank, c.liquid, c.rig) == []


def test_the_linear_force_is_the_pendulums_by_hand():
    """At the drive w, a pendulum of mass m and natural frequency w_n (damping z) adds
    m (w_n^2 + 2i z w_n w) / (w_n^2 - w^2 + 2i z w_n w) to the rigid mass."""
    t = np.arange(0, 100, 0.01)
    w, wn, z, m, rigid = 2 * np.pi * 1.0, 2 * np.pi * 1.3, 0.02, 2.0, 1.5
    a = np.sin(w * t)
    h = rigid + m * (wn**2 + 2j * z * wn * w) / (wn**2 - w**2 + 2j * z * wn * w)
    expected = abs(h) * np.sin(w * t + np.angle(h))
    got = linear_force(t, a, rigid, [(m, wn, z)])
    assert np.max(np.abs(got - expected)) < 1e-9 * abs(h)


def test_the_command_prints_the_warning(tmp_path, capsys):
    path = _mat(tmp_path, mm=True, lbf=True, columns='time = "t"\ndisplacement = "x"\nforce = "Fx"\n')
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.0553,
                                  "p1.damping": 0.001, "rig.dry_mass": 1.2}))
    main(["simulate", str(path), "--params", str(params), "--out", str(tmp_path / "s.csv")])
    err = capsys.readouterr().err
    assert "warning: A1.mat: channel `x` ([data.columns] displacement) has no unit" in err
    assert "looks like lbf" in err
