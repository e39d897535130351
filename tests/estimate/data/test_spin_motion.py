"""Spinning-rig records as the SSTR makes them: measured rig angles and schedules in
`[rig.spin]`, `[test] initial_state`, and the rig's input signals built from them."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import reference_spinning as rs

from estimate.data import load_case, write_case
from estimate.data.case import CaseError, Liquid, Rig, Spin, Tank, TestInfo
from estimate.data.spin import rig_angle_derivatives, spin_excitation

CHANNELS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
TOML = """\
[test]
id = "S1"
rig = "spinning"
data = "S1.csv"
{test}
[tank]
shape = "sphere"
radius = 0.1016
fill_fraction = 0.6
diaphragm = false

[liquid]
density = 998.2
kinematic_viscosity = 1.004e-6

[rig]
dry_mass = 2.0
gravity = 9.80665

[rig.spin]
rate = 6.0
radius = 0.4
nutation_angle = 0.06
nutation_frequency = -0.5
{spin}"""
#: A table spun up over 8 s and coned in over 4 s from 8 s, recorded at 50 Hz.
REF_RIG = rs.Rig(spin_rate=6.0, radius=0.4, nutation_angle=0.06, nutation_frequency=-0.5,
                 spin_up=8.0, nutation_ramp=4.0)
TIME = np.arange(751) / 50.0


def _write(tmp_path: Path, spin: str = "", test: str = "", angles: dict | None = None) -> Path:
    rng = np.random.default_rng(0)
    cols = {c: rng.standard_normal(TIME.size) for c in CHANNELS}
    if angles is None:
        angles = {n: a[0] for n, a in zip(("table_angle", "precession", "cone"),
                                          REF_RIG.angles(TIME))}
    cols |= angles
    header = "time," + ",".join(cols)
    rows = [",".join([f"{t:.2f}"] + [repr(float(v[i])) for v in cols.values()])
            for i, t in enumerate(TIME)]
    (tmp_path / "S1.csv").write_text("\n".join([header, *rows]) + "\n")
    path = tmp_path / "S1.toml"
    path.write_text(TOML.format(spin=spin, test=test))
    return path


def test_schedules_and_columns_load_and_set_the_rig_motion(tmp_path: Path) -> None:
    case = load_case(_write(tmp_path, "spin_up = 8.0\nnutation_ramp = 4.0\n",
                            'initial_state = "steady"\n'))
    assert case.spin.motion == "input" and case.spin.ramp_start == 8.0
    assert case.test.initial_state == "steady"
    plain = load_case(_write(tmp_path))
    assert plain.spin.motion == "constant" and plain.test.initial_state is None
    measured = load_case(_write(tmp_path, 'spin_angle = "table_angle"\n'
                                          'nutation_phase = "precession"\ncone_angle = "cone"\n'))
    assert measured.spin.columns == {"spin_angle": "table_angle", "nutation_phase": "precession",
                                     "cone_angle": "cone"}
    # written back, the keys survive
    out = write_case(tmp_path / "out" / "S2.toml",
                     test=TestInfo("S2", "spinning", "S2.csv", "spin", initial_state="free"),
                     tank=case.tank, liquid=case.liquid, rig=measured.rig, time=case.time,
                     channels=measured.channels)
    assert out.spin == measured.spin and out.test.initial_state == "free"


def test_every_motion_problem_is_reported_with_its_key(tmp_path: Path) -> None:
    spin = ('spin_angle = "table_angle"\nspin_rate = 6.0\nspin_up = 12.0\n'
            'nutation_start = 3.0\ncone_angle = "cone_deg"\n')
    with pytest.raises(CaseError) as err:
        load_case(_write(tmp_path, spin, 'initial_state = "settled"\n'))
    text = str(err.value)
    assert re.search(r'\[test\] initial_state: unknown value "settled" \(expected one of "rest", '
                     r'"steady", "free"\)', text)
    assert re.search(r"\[rig.spin\] spin_rate: expected the name of a CSV column of measured rig "
                     r"motion .* found a float `6.0`", text)
    assert "[rig.spin] spin_rate: give the measured spin angle (`spin_angle`) or rate" in text
    assert re.search(r"\[rig.spin\] spin_up: a schedule for a motion the CSV column "
                     r"`table_angle` \(`spin_angle`\) already measures", text)
    assert re.search(r"\[rig.spin\] nutation_start: a schedule for a motion the CSV column "
                     r"`cone_deg`", text)
    assert re.search(r"\[rig.spin\] nutation_start: the coning can only start later with a ramp",
                     text)


def test_a_named_column_must_exist_and_turn_at_the_nominal_rate(tmp_path: Path) -> None:
    with pytest.raises(CaseError, match=r"S1.toml: \[rig.spin\] cone_angle: the CSV has no column "
                                        r"`cone_deg` \(its columns are `force_x`"):
        load_case(_write(tmp_path, 'cone_angle = "cone_deg"\n'))
    slow = {"table_angle": 5.0 * TIME}
    with pytest.raises(CaseError, match=r"\[rig.spin\] rate: 6.0 rad/s, but column `table_angle` "
                                        r"turns at 5 rad/s over the last tenth"):
        load_case(_write(tmp_path, 'spin_angle = "table_angle"\n', angles=slow))


def test_schedule_inputs_are_the_reference_rig_angles(tmp_path: Path) -> None:
    case = load_case(_write(tmp_path, "spin_up = 8.0\nnutation_ramp = 4.0\n"))
    exc = spin_excitation(case)
    assert exc.analytic  # closed form: evaluated inside generated code
    values = exc.values(TIME)
    # the reference writes its ramps out independently (tests/reference_spinning.py)
    expected = np.vstack([np.vstack(a) for a in REF_RIG.angles(TIME)])
    assert np.max(np.abs(values - expected)) < 1e-12


#: A 16-bit-class encoder (1e-4 rad noise) at 50 Hz: the smoothing spline gives the rates to
#: ~5e-4 rad/s and the accelerations to ~1e-2 rad/s^2 (spin-up peak 1.4 rad/s^2); noise-free
#: angles are reproduced to interpolation accuracy.
ANGLE_RATE_TOL, ANGLE_ACC_TOL = 2e-3, 2e-2


def test_measured_angles_are_smoothed_and_differentiated_without_lag(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    angles = {n: a[0] + 1e-4 * rng.standard_normal(TIME.size)
              for n, a in zip(("table_angle", "precession", "cone"), REF_RIG.angles(TIME))}
    # an encoder reading modulo 2 pi is unwrapped
    angles["table_angle"] = np.mod(angles["table_angle"], 2 * np.pi)
    case = load_case(_write(tmp_path, 'spin_angle = "table_angle"\n'
                                      'nutation_phase = "precession"\ncone_angle = "cone"\n',
                            angles=angles))
    values = spin_excitation(case).values(TIME)
    for i, truth in enumerate(REF_RIG.angles(TIME)):
        value, rate, acc = values[3 * i:3 * i + 3]
        assert np.max(np.abs(rate - truth[1])) < ANGLE_RATE_TOL, i
        assert np.max(np.abs(acc - truth[2])) < ANGLE_ACC_TOL, i
    # the spin angle keeps its absolute phase (no lag: the tilt direction in the tank
    # is spin angle minus nutation phase)
    assert np.max(np.abs(values[0] - REF_RIG.angles(TIME)[0][0])) < 1e-3
    # a rate column integrates to the same angle
    x, xd, xdd = rig_angle_derivatives(TIME, REF_RIG.angles(TIME)[0][0])
    assert np.max(np.abs(xd - REF_RIG.angles(TIME)[0][1])) < 1e-4


def test_spinning_case_with_motion_keys_round_trips_through_write_case(tmp_path: Path) -> None:
    spin = Spin(6.0, 0.4, 0.06, -0.5, spin_up=8.0, nutation_ramp=4.0, nutation_start=9.0)
    case = write_case(tmp_path / "S3.toml",
                      test=TestInfo("S3", "spinning", "S3.csv", "spin", initial_state="rest"),
                      tank=Tank("sphere", 0.1016, 0.6, False), liquid=Liquid(998.2, 1.004e-6),
                      rig=Rig(2.0, 9.80665, spin=spin), time=TIME,
                      channels={c: np.sin(TIME) for c in CHANNELS})
    assert case.spin == spin and case.spin.ramp_start == 9.0
    assert "nutation_start = 9.0" in (tmp_path / "S3.toml").read_text()


def test_a_decimated_record_unwraps_the_table_angle_before_its_low_pass(tmp_path: Path) -> None:
    """The table's angle written wrapped to [-pi, pi) at 200 Hz, decimated by 2: the angle
    comes back continuous and equal to the reference's to 1e-6 rad away from the ends (the
    low-pass across a wrap would smear a 2 pi step over the filter's length), and the spin
    rate read from it passes the check against ``[rig.spin] rate``."""
    t = np.arange(3001) / 200.0
    table, precession, cone = (a[0] for a in REF_RIG.angles(t))
    wrapped = np.mod(table + np.pi, 2 * np.pi) - np.pi
    rng = np.random.default_rng(0)
    cols = {c: rng.standard_normal(t.size) for c in CHANNELS}
    cols |= {"table_angle": wrapped, "precession": precession, "cone": cone}
    rows = [",".join([f"{x:.3f}"] + [repr(float(v[i])) for v in cols.values()])
            for i, x in enumerate(t)]
    (tmp_path / "S1.csv").write_text("\n".join(["time," + ",".join(cols), *rows]) + "\n")
    (tmp_path / "S1.toml").write_text(TOML.format(
        spin='spin_angle = "table_angle"\nnutation_phase = "precession"\ncone_angle = "cone"\n',
        test="decimate = 2\n"))
    case = load_case(tmp_path / "S1.toml")
    inner = slice(200, -200)
    assert np.max(np.abs(case.columns["table_angle"][inner] - table[::2][inner])) < 1e-6
    assert np.max(np.abs(case.columns["precession"][inner] - precession[::2][inner])) < 1e-6
