"""Tests of `estimate.data` case files: loading, validation messages, writing."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from estimate.data import load_case, write_case
from estimate.data.case import (
    MIN_SAMPLES,
    Case,
    CaseError,
    Crank,
    Liquid,
    Prediction,
    Rig,
    Tank,
    TestInfo,
)

GOOD_TOML = """\
# a comment
[test]
id = "A1"
rig = "lateral"
data = "A1.csv"
excitation = "measured"
operator = "extra keys are allowed"

[tank]
shape = "sphere"
radius = 0.1016
fill_fraction = 0.6
diaphragm = false

[liquid]
density = 998.2
kinematic_viscosity = 1.004e-6

[rig]
dry_mass = 1.2
gravity = 9.80665

[prediction]
pendulum_mass = 1.338
pendulum_length = 0.057
fixed_mass = 1.456
damping_ratio = 0.00703
"""

CRANK_TABLE = """
[rig.crank]
radius = 0.01
rod_length = 0.15
frequency = 1.855
"""

N = 200


def _csv_lines(with_displacement: bool = True, n: int = N) -> list[str]:
    t = np.arange(n) * 0.01
    x = 0.005 * np.sin(2 * np.pi * 1.855 * t)
    f = 3.0 * np.sin(2 * np.pi * 1.855 * t + 0.1)
    if with_displacement:
        return ["time,displacement,force"] + [f"{a:.2f},{b:.8g},{c:.8g}" for a, b, c in zip(t, x, f)]
    return ["time,force"] + [f"{a:.2f},{c:.8g}" for a, c in zip(t, f)]


def _write(tmp_path: Path, toml: str = GOOD_TOML, lines: list[str] | None = None) -> Path:
    case = tmp_path / "A1.toml"
    case.write_text(toml)
    (tmp_path / "A1.csv").write_text("\n".join(_csv_lines() if lines is None else lines) + "\n")
    return case


def _problems(path: Path) -> list[str]:
    with pytest.raises(CaseError) as info:
        load_case(path)
    return info.value.problems


# ---------------------------------------------------------------------------------------------
# good input


def test_load_good_case(tmp_path: Path) -> None:
    path = _write(tmp_path)
    before = (tmp_path / "A1.csv").read_bytes(), path.read_bytes()
    case = load_case(path)
    assert isinstance(case, Case)
    assert case.test == TestInfo(id="A1", rig="lateral", data="A1.csv", excitation="measured")
    assert case.tank == Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False)
    assert case.liquid == Liquid(density=998.2, kinematic_viscosity=1.004e-6)
    assert case.rig == Rig(dry_mass=1.2, gravity=9.80665, crank=None)
    assert case.prediction == Prediction(1.338, 0.057, 1.456, 0.00703)
    assert case.n_samples == N and case.time.shape == case.force.shape == (N,)
    assert case.displacement is not None and case.displacement.shape == (N,)
    assert case.sample_rate == pytest.approx(100.0)
    assert case.path == path.resolve() and case.data_path == (tmp_path / "A1.csv").resolve()
    # frozen and read-only, input files untouched
    with pytest.raises(AttributeError):
        case.tank = None  # type: ignore[misc]
    with pytest.raises(ValueError):
        case.force[0] = 1.0
    assert ((tmp_path / "A1.csv").read_bytes(), path.read_bytes()) == before


def test_load_crank_case_without_displacement(tmp_path: Path) -> None:
    toml = GOOD_TOML.replace('"measured"', '"crank"') + CRANK_TABLE
    case = load_case(_write(tmp_path, toml, _csv_lines(with_displacement=False)))
    assert case.displacement is None
    assert case.crank == Crank(radius=0.01, rod_length=0.15, frequency=1.855)


def test_prediction_is_optional_and_integers_are_numbers(tmp_path: Path) -> None:
    toml = GOOD_TOML.split("[prediction]")[0].replace("dry_mass = 1.2", "dry_mass = 2")
    case = load_case(_write(tmp_path, toml))
    assert case.prediction is None and case.rig.dry_mass == 2.0


# ---------------------------------------------------------------------------------------------
# one test per kind of bad input


def test_missing_case_file(tmp_path: Path) -> None:
    with pytest.raises(CaseError, match=r"nope\.toml: case file not found \(expected a TOML"):
        load_case(tmp_path / "nope.toml")


def test_invalid_toml(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("radius = 0.1016", "radius = = 0.1016"))
    with pytest.raises(CaseError, match=r"A1\.toml: invalid TOML: .*line 11"):
        load_case(path)


def test_missing_data_file(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace('data = "A1.csv"', 'data = "other.csv"'))
    with pytest.raises(CaseError, match=r"\[test\] data: data file not found \(expected a CSV "
                                        r"file at `.*other\.csv`\)"):
        load_case(path)


def test_missing_key(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("gravity = 9.80665\n", ""))
    with pytest.raises(CaseError, match=r"A1\.toml: \[rig\] gravity: missing key \(expected a "
                                        r"number in m/s\^2\)"):
        load_case(path)


@pytest.mark.parametrize("line", ["", 'dry_mass = "estimate"\n'])
def test_an_unweighed_container_is_estimated(tmp_path: Path, line: str) -> None:
    # issue 25: `dry_mass` absent or "estimate": the fit estimates the container's mass
    case = load_case(_write(tmp_path, GOOD_TOML.replace("dry_mass = 1.2\n", line)))
    assert case.rig.dry_mass is None


def test_a_dry_mass_string_other_than_estimate_is_refused(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("dry_mass = 1.2", 'dry_mass = "unknown"'))
    with pytest.raises(CaseError, match=r'\[rig\] dry_mass: expected a positive number in kg or '
                                        r'"estimate" \(the container is not weighed\), found the '
                                        r"string 'unknown'"):
        load_case(path)


def test_the_liquid_mass_follows_the_tank_geometry(tmp_path: Path) -> None:
    # the 8-inch sphere at 60 % depth: a spherical cap pi h^2 (3 R - h) / 3 of water
    case = load_case(_write(tmp_path, GOOD_TOML))
    R, h = 0.1016, 0.6 * 2 * 0.1016
    assert case.liquid_mass == pytest.approx(998.2 * math.pi * h**2 * (3 * R - h) / 3, rel=1e-9)


def test_missing_table(tmp_path: Path) -> None:
    toml = GOOD_TOML.replace("[liquid]\ndensity = 998.2\nkinematic_viscosity = 1.004e-6\n", "")
    with pytest.raises(CaseError, match=r"\[liquid\]: missing table"):
        load_case(_write(tmp_path, toml))


def test_wrong_type(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("radius = 0.1016", 'radius = "0.1016"'))
    with pytest.raises(CaseError, match=r"\[tank\] radius: expected a number in m, found a "
                                        r"string `'0.1016'`"):
        load_case(path)


def test_wrong_type_boolean(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("diaphragm = false", "diaphragm = 0"))
    with pytest.raises(CaseError, match=r"\[tank\] diaphragm: expected true or false, found an "
                                        r"integer `0`"):
        load_case(path)


def test_boolean_is_not_a_number(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("gravity = 9.80665", "gravity = true"))
    with pytest.raises(CaseError, match=r"\[rig\] gravity: expected a number in m/s\^2, found a "
                                        r"boolean"):
        load_case(path)


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        ("dry_mass = 1.2", "dry_mass = 0.0",
         r"\[rig\] dry_mass: expected a positive number in kg, found 0\.0"),
        ("radius = 0.1016", "radius = -0.1",
         r"\[tank\] radius: expected a positive number in m, found -0\.1"),
        ("density = 998.2", "density = 0", r"\[liquid\] density: expected a positive number in kg/m\^3"),
        ("kinematic_viscosity = 1.004e-6", "kinematic_viscosity = -1e-6",
         r"\[liquid\] kinematic_viscosity: expected a positive number in m\^2/s"),
        ("gravity = 9.80665", "gravity = 0.0", r"\[rig\] gravity: expected a positive number"),
        ("pendulum_length = 0.057", "pendulum_length = -0.057",
         r"\[prediction\] pendulum_length: expected a positive number in m"),
        ("pendulum_mass = 1.338", "pendulum_mass = 0", r"\[prediction\] pendulum_mass: expected a positive"),
        ("fixed_mass = 1.456", "fixed_mass = -1", r"\[prediction\] fixed_mass: expected a positive"),
        ("damping_ratio = 0.00703", "damping_ratio = -0.01",
         r"\[prediction\] damping_ratio: expected a number >= 0"),
    ],
)
def test_non_positive_values(tmp_path: Path, old: str, new: str, pattern: str) -> None:
    with pytest.raises(CaseError, match=pattern):
        load_case(_write(tmp_path, GOOD_TOML.replace(old, new)))


def test_non_finite_toml_number(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("density = 998.2", "density = nan"))
    with pytest.raises(CaseError, match=r"\[liquid\] density: expected a finite number in "
                                        r"kg/m\^3, found nan"):
        load_case(path)


@pytest.mark.parametrize("fill", ["0.0", "1.0", "1.2", "-0.5"])
def test_fill_fraction_outside_unit_interval(tmp_path: Path, fill: str) -> None:
    path = _write(tmp_path, GOOD_TOML.replace("fill_fraction = 0.6", f"fill_fraction = {fill}"))
    with pytest.raises(CaseError, match=r"\[tank\] fill_fraction: expected a number strictly "
                                        rf"between 0 and 1, found {re.escape(fill)}"):
        load_case(path)


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        ('rig = "lateral"', 'rig = "rotating"',
         r'\[test\] rig: unknown value "rotating" \(expected one of "lateral", "spinning"\)'),
        ('excitation = "measured"', 'excitation = "sine"',
         r'\[test\] excitation: unknown value "sine" \(expected one of "measured", "crank"\)'),
        ('shape = "sphere"', 'shape = "cube"',
         r'\[tank\] shape: unknown value "cube" \(expected one of "sphere", "cylinder", '
         r'"capsule", "rectangular"\)'),
    ],
)
def test_unknown_choice(tmp_path: Path, old: str, new: str, pattern: str) -> None:
    with pytest.raises(CaseError, match=pattern):
        load_case(_write(tmp_path, GOOD_TOML.replace(old, new)))


def test_measured_excitation_without_displacement(tmp_path: Path) -> None:
    path = _write(tmp_path, lines=_csv_lines(with_displacement=False))
    with pytest.raises(CaseError, match=r'A1\.csv: column `displacement`: missing, but `\[test\] '
                                        r'excitation = "measured"` needs the carriage displacement'):
        load_case(path)


def test_crank_excitation_without_crank_table(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD_TOML.replace('"measured"', '"crank"'))
    with pytest.raises(CaseError, match=r'\[rig\.crank\]: missing table \(expected `\[rig\.crank\]` '
                                        r'with radius, rod_length and frequency because `\[test\] '
                                        r'excitation = "crank"`\)'):
        load_case(path)


def test_crank_rod_shorter_than_radius(tmp_path: Path) -> None:
    toml = GOOD_TOML.replace('"measured"', '"crank"') + CRANK_TABLE.replace("0.15", "0.005")
    with pytest.raises(CaseError, match=r"\[rig\.crank\] rod_length: expected a rod longer than "
                                        r"the crank radius \(0\.01 m\), found 0\.005 m"):
        load_case(_write(tmp_path, toml))


@pytest.mark.parametrize("header", ["t,x,F", "time,force,displacement", "time,displacement"])
def test_bad_header(tmp_path: Path, header: str) -> None:
    lines = _csv_lines()
    lines[0] = header
    with pytest.raises(CaseError, match=r"A1\.csv: header \(line 1\): expected "
                                        rf"`time,displacement,force`, found `{header}`"):
        load_case(_write(tmp_path, lines=lines))


def test_bad_header_names_crank_alternative(tmp_path: Path) -> None:
    toml = GOOD_TOML.replace('"measured"', '"crank"') + CRANK_TABLE
    lines = _csv_lines()
    lines[0] = "t,F"
    with pytest.raises(CaseError, match=r"expected `time,displacement,force` or `time,force`, "
                                        r"found `t,F`"):
        load_case(_write(tmp_path, toml, lines))


def test_nan_and_inf_rows(tmp_path: Path) -> None:
    lines = _csv_lines()
    lines[5] = "0.04,nan,1.0"
    lines[9] = "0.08,0.001,inf"
    lines[12] = "0.11,0.001,-inf"
    problems = _problems(_write(tmp_path, lines=lines))
    assert any(re.search(r"A1\.csv: column `displacement`: expected finite numbers, found 1 NaN "
                         r"or inf value\(s\) at line 6$", p) for p in problems), problems
    assert any(re.search(r"column `force`: expected finite numbers, found 2 NaN or inf value\(s\) "
                         r"at lines 10, 13$", p) for p in problems), problems


def test_non_numeric_value(tmp_path: Path) -> None:
    lines = _csv_lines()
    lines[3] = "0.02,abc,1.0"
    with pytest.raises(CaseError, match=r"column `displacement`: expected numbers, found 1 "
                                        r"non-numeric value\(s\): line 4 `abc`"):
        load_case(_write(tmp_path, lines=lines))


def test_wrong_field_count(tmp_path: Path) -> None:
    lines = _csv_lines()
    lines[7] = "0.06,0.001"
    with pytest.raises(CaseError, match=r"rows: expected 3 comma-separated fields per row, found "
                                        r"1 row\(s\) with a different count: line 8 \(2 fields\)"):
        load_case(_write(tmp_path, lines=lines))


def test_non_monotonic_time(tmp_path: Path) -> None:
    lines = _csv_lines()
    lines[20], lines[21] = lines[21], lines[20]
    with pytest.raises(CaseError, match=r"column `time`: expected strictly increasing times, "
                                        r"found 1 decrease\(s\) or repeat\(s\) at line 22"):
        load_case(_write(tmp_path, lines=lines))


def test_repeated_time(tmp_path: Path) -> None:
    lines = _csv_lines()
    lines[31] = lines[30]
    with pytest.raises(CaseError, match=r"strictly increasing times, found 1 decrease\(s\) or "
                                        r"repeat\(s\) at line 32"):
        load_case(_write(tmp_path, lines=lines))


def test_non_uniform_time(tmp_path: Path) -> None:
    lines = _csv_lines()
    del lines[50]  # a dropped sample: one step of 0.02 s
    with pytest.raises(CaseError, match=r"column `time`: expected a uniform step \(median 0\.01 s, "
                                        r"tolerance 0\.001 relative\), found 1 step\(s\) off at "
                                        r"line 51 \(worst: a step of 0\.02 s ending at line 51\)"):
        load_case(_write(tmp_path, lines=lines))


def test_small_time_jitter_is_accepted(tmp_path: Path) -> None:
    lines = _csv_lines()
    t, rest = lines[40].split(",", 1)
    lines[40] = f"{float(t) + 5e-6:.6f},{rest}"  # 0.05% of a step: below TIME_STEP_RTOL
    load_case(_write(tmp_path, lines=lines))


def test_too_few_samples(tmp_path: Path) -> None:
    path = _write(tmp_path, lines=_csv_lines(n=MIN_SAMPLES - 1))
    with pytest.raises(CaseError, match=rf"A1\.csv: rows: expected at least {MIN_SAMPLES} samples, "
                                        rf"found {MIN_SAMPLES - 1}"):
        load_case(path)


def test_empty_csv(tmp_path: Path) -> None:
    with pytest.raises(CaseError, match=r"header: expected `time,displacement,force`, found an "
                                        r"empty file"):
        load_case(_write(tmp_path, lines=[]))


def test_table_of_wrong_type(tmp_path: Path) -> None:
    toml = "prediction = 3\n" + GOOD_TOML.split("[prediction]")[0]
    with pytest.raises(CaseError, match=r"\[prediction\]: expected a table, found an integer `3`"):
        load_case(_write(tmp_path, toml))


# ---------------------------------------------------------------------------------------------
# everything at once


def test_all_problems_reported_together(tmp_path: Path) -> None:
    toml = (GOOD_TOML.replace("gravity = 9.80665\n", "")
            .replace("radius = 0.1016", 'radius = "big"')
            .replace("fill_fraction = 0.6", "fill_fraction = 1.5")
            .replace('shape = "sphere"', 'shape = "cube"')
            .replace('excitation = "measured"', 'excitation = "crank"'))
    lines = _csv_lines()
    lines[4] = "0.03,0.001,nan"
    lines[60], lines[61] = lines[61], lines[60]
    with pytest.raises(CaseError) as info:
        load_case(_write(tmp_path, toml, lines))
    problems = info.value.problems
    expected = [
        r"A1\.toml: \[rig\] gravity: missing key",
        r"A1\.toml: \[tank\] radius: expected a number in m, found a string",
        r"A1\.toml: \[tank\] fill_fraction: expected a number strictly between 0 and 1",
        r"A1\.toml: \[tank\] shape: unknown value \"cube\"",
        r"A1\.toml: \[rig\.crank\]: missing table",
        r"A1\.csv: column `force`: expected finite numbers, found 1 NaN or inf value\(s\) at line 5",
        r"A1\.csv: column `time`: expected strictly increasing times",
    ]
    for pattern in expected:
        assert any(re.search(pattern, p) for p in problems), (pattern, problems)
    assert len(problems) == len(expected), problems
    message = str(info.value)
    assert message.startswith(f"{len(expected)} problems in case:")
    assert all(p in message for p in problems)
    assert isinstance(info.value, ValueError)


# ---------------------------------------------------------------------------------------------
# writing


def _write_args() -> dict:
    t = np.arange(300) * 0.01
    return dict(
        test=TestInfo(id="G1", rig="lateral", data="G1.csv", excitation="measured",
                      note="SYNTHETIC test data"),
        tank=Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False),
        liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
        rig=Rig(dry_mass=1.2, gravity=9.80665),
        prediction=Prediction(1.338, 0.057, 1.456, 0.00703),
        time=t, displacement=0.005 * np.sin(2 * np.pi * 1.855 * t),
        force=2.0 * np.cos(2 * np.pi * 1.855 * t) + 1e-3 / 3,
    )


def test_write_case_round_trip(tmp_path: Path) -> None:
    args = _write_args()
    case = write_case(tmp_path / "G1.toml", comment="SYNTHETIC data\nmade by a test", **args)
    text = (tmp_path / "G1.toml").read_text()
    assert text.startswith("# SYNTHETIC data\n# made by a test\n")
    assert case.test == args["test"] and case.prediction == args["prediction"]
    np.testing.assert_allclose(case.time, args["time"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(case.force, args["force"], rtol=1e-11)
    np.testing.assert_allclose(case.displacement, args["displacement"], rtol=1e-11, atol=1e-15)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["G1.csv", "G1.toml"]


def test_write_crank_case(tmp_path: Path) -> None:
    args = _write_args()
    args["test"] = TestInfo(id="G2", rig="lateral", data="G2.csv", excitation="crank")
    args["rig"] = Rig(dry_mass=1.2, gravity=9.80665, crank=Crank(0.01, 0.15, 1.855))
    args["displacement"] = None
    case = write_case(tmp_path / "G2.toml", **args)
    assert case.crank == Crank(0.01, 0.15, 1.855) and case.displacement is None
    assert (tmp_path / "G2.csv").read_text().startswith("time,force\n")


def test_write_case_refuses_to_overwrite(tmp_path: Path) -> None:
    args = _write_args()
    write_case(tmp_path / "G1.toml", **args)
    before = (tmp_path / "G1.csv").read_bytes()
    args["force"] = args["force"] * 2
    with pytest.raises(FileExistsError, match=r"refusing to overwrite existing file\(s\) .*G1\.toml"
                                              r".*pass `overwrite=True`"):
        write_case(tmp_path / "G1.toml", **args)
    assert (tmp_path / "G1.csv").read_bytes() == before
    case = write_case(tmp_path / "G1.toml", overwrite=True, **args)
    np.testing.assert_allclose(case.force, args["force"], rtol=1e-11)


def test_write_invalid_case_leaves_no_files(tmp_path: Path) -> None:
    args = _write_args()
    args["force"] = args["force"].copy()
    args["force"][3] = np.nan
    with pytest.raises(CaseError, match=r"column `force`: expected finite numbers"):
        write_case(tmp_path / "G1.toml", **args)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# bundled examples

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


@pytest.mark.parametrize("name", ["A1", "A1_crank"])
def test_bundled_examples_load_and_are_marked_synthetic(name: str) -> None:
    case = load_case(EXAMPLES / f"{name}.toml")
    assert case.n_samples == 3001 and case.sample_rate == pytest.approx(100.0)
    assert case.test.note is not None and "SYNTHETIC" in case.test.note
    assert "SYNTHETIC" in (EXAMPLES / f"{name}.toml").read_text().splitlines()[0]
    assert (case.displacement is None) == (name == "A1_crank")


def test_bundled_examples_are_reproducible(tmp_path: Path) -> None:
    import json
    import runpy

    script = runpy.run_path(str(EXAMPLES / "make_example_cases.py"), run_name="not_main")
    assert script["main"](["--out", str(tmp_path)]) == 0
    assert script["main"](["--out", str(tmp_path)]) == 1  # refuses to overwrite
    for name in ("A1", "A1_crank"):
        new, old = load_case(tmp_path / f"{name}.toml"), load_case(EXAMPLES / f"{name}.toml")
        np.testing.assert_allclose(new.force, old.force, rtol=1e-9, atol=1e-9)
    params = json.loads((EXAMPLES / "A1_params.json").read_text())
    assert sorted(params) == ["fixed.mass", "p1.damping", "p1.length", "p1.mass", "p1.stiffness"]
    assert json.loads((tmp_path / "A1_params.json").read_text()) == pytest.approx(params)


# -- spinning rig -------------------------------------------------------------------------

SPIN_TOML = GOOD_TOML.replace('rig = "lateral"', 'rig = "spinning"').replace(
    'excitation = "measured"\n', "").replace("data = \"A1.csv\"", "data = \"S1.csv\"") + """
[rig.spin]
rate = 6.0
radius = 0.4
nutation_angle = 0.06
nutation_frequency = 0.3
"""
SPIN_COLUMNS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")


def _spin_csv(n: int = 60, header: str = "time," + ",".join(SPIN_COLUMNS) + ",table_angle") -> str:
    t = np.arange(n) * 0.01
    cols = header.split(",")
    rows = [",".join(["%.2f" % ti] + [str(np.sin(ti + k)) for k in range(len(cols) - 1)])
            for ti in t]
    return "\n".join([header, *rows]) + "\n"


def _write_spin(tmp_path: Path, toml: str = SPIN_TOML, csv_text: str | None = None) -> Path:
    (tmp_path / "S1.csv").write_text(_spin_csv() if csv_text is None else csv_text)
    path = tmp_path / "S1.toml"
    path.write_text(toml)
    return path


def test_spinning_case_loads_with_channels_and_defaults(tmp_path: Path) -> None:
    case = load_case(_write_spin(tmp_path))
    assert case.test.rig == "spinning" and case.test.excitation == "spin"
    assert case.spin is not None and case.spin.rate == 6.0 and case.spin.height == 0.0
    assert case.spin.tank_axis == "spin" and case.spin.gravity_on
    assert set(case.channels) == set(SPIN_COLUMNS) | {"table_angle"}
    assert case.force is None
    with pytest.raises(ValueError):
        case.channels["torque_y"][0] = 1.0  # read-only


def test_lateral_case_channels_are_the_force(tmp_path: Path) -> None:
    case = load_case(_write(tmp_path, GOOD_TOML))
    assert list(case.channels) == ["force_x"]
    assert np.array_equal(case.channels["force_x"], case.force)


def test_spinning_case_reports_every_problem(tmp_path: Path) -> None:
    toml = SPIN_TOML.replace("rate = 6.0", 'rate = "fast"').replace(
        "nutation_angle = 0.06", "nutation_angle = 2.0") + 'tank_axis = "radial"\n'
    header = "time,force_x,force_y,force_z,torque_x,torque_y"
    with pytest.raises(CaseError) as err:
        load_case(_write_spin(tmp_path, toml, _spin_csv(header=header)))
    text = str(err.value)
    assert "4 problems" in text
    assert re.search(r"S1.toml: \[rig.spin\] rate: expected a number in rad/s, found a string", text)
    assert re.search(r"\[rig.spin\] nutation_angle: expected a cone half-angle below pi/2 rad, "
                     r"found 2.0 rad", text)
    assert re.search(r'\[rig.spin\] tank_axis: unknown value "radial" \(expected one of "spin", '
                     r'"inward"\)', text)
    assert re.search(r"S1.csv: header \(line 1\): expected `time,force_x,force_y,force_z,torque_x,"
                     r"torque_y,torque_z` .* \(no column `torque_z`\)", text)


def test_spinning_case_needs_the_spin_table_and_rejects_lateral_excitations(tmp_path: Path) -> None:
    toml = SPIN_TOML.split("[rig.spin]")[0].replace('rig = "spinning"',
                                                      'rig = "spinning"\nexcitation = "crank"')
    with pytest.raises(CaseError, match=r"(?s)\[test\] excitation: unknown value \"crank\" "
                                        r"\(expected one of \"spin\"\).*\[rig.spin\]: missing table"):
        load_case(_write_spin(tmp_path, toml))


def test_spinning_csv_nan_is_reported_with_column_and_line(tmp_path: Path) -> None:
    lines = _spin_csv().splitlines()
    fields = lines[5].split(",")
    fields[5] = "nan"  # torque_y
    lines[5] = ",".join(fields)
    with pytest.raises(CaseError, match=r"S1.csv: column `torque_y`: expected finite numbers, "
                                        r"found 1 NaN or inf value\(s\) at line 6"):
        load_case(_write_spin(tmp_path, csv_text="\n".join(lines) + "\n"))


def test_write_case_round_trips_a_spinning_case(tmp_path: Path) -> None:
    from estimate.data.case import Spin

    case = load_case(_write_spin(tmp_path))
    out = write_case(tmp_path / "out" / "S2.toml",
                     test=TestInfo(id="S2", rig="spinning", data="S2.csv", excitation="spin"),
                     tank=case.tank, liquid=case.liquid,
                     rig=Rig(dry_mass=2.0, gravity=9.80665,
                             spin=Spin(6.0, 0.4, 0.06, 0.3, height=0.1, tank_axis="inward",
                                       gravity_on=False)),
                     time=case.time, channels=case.channels)
    assert out.spin == Spin(6.0, 0.4, 0.06, 0.3, height=0.1, tank_axis="inward", gravity_on=False)
    for k, v in case.channels.items():
        assert np.allclose(out.channels[k], v, rtol=1e-11)
    with pytest.raises(ValueError, match="a spinning-rig case takes `channels`"):
        write_case(tmp_path / "x.toml", test=out.test, tank=out.tank, liquid=out.liquid,
                   rig=out.rig, time=case.time, force=case.time)
