"""Six-axis records of a tank moved in 3-D (``[rig.motion]``, ``[rig.transducer]``): loading,
every problem at once, writing, the rig and model a case gets, the measured motion's
derivatives, and the sign check of the force channels."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import reference_motion as rm
from motion_cases import PENDULUM, make_motion_case

from analogs import MotionRig, Pendulum, SphericalPendulum
from estimate.data import load_case, write_case
from estimate.data.case import CaseError, Motion, Rig, Transducer
from estimate.data.models import model_for_case, model_from_spec, rig_for, rig_values
from estimate.data.motion import axis_derivatives, motion_excitation
from estimate.data.reader import UnknownKey

TOML = """\
[test]
id = "M1"
rig = "lateral"
data = "M1.csv"
excitation = "measured"

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

[rig.motion]
x = "carriage"
pitch = "tilt"

[rig.transducer]
z = -0.045
yaw = 3.141592653589793
"""


def _csv(header: str, n: int = 400) -> str:
    t = np.arange(n) * 0.005
    cols = {"time": t, "carriage": 0.002 * np.sin(2 * np.pi * 1.0 * t),
            "tilt": 0.05 * np.sin(2 * np.pi * 0.7 * t)}
    names = header.split(",")
    rows = [",".join(f"{cols.get(c, 0.01 * np.cos(t))[i]:.9g}" for c in names) for i in range(n)]
    return "\n".join([header, *rows]) + "\n"


def _write(tmp_path: Path, toml: str = TOML, header: str = "time,carriage,tilt,force_x,torque_y"
           ) -> Path:
    (tmp_path / "M1.csv").write_text(_csv(header))
    path = tmp_path / "M1.toml"
    path.write_text(toml)
    return path


def test_six_axis_case_loads_its_motion_transducer_and_channels(tmp_path):
    # the channels are small and the motion slow: nothing for the sign check to judge
    case = load_case(_write(tmp_path))
    assert case.motion == Motion(x="carriage", pitch="tilt") and case.motion.axes == ("x", "pitch")
    assert case.rig.transducer == Transducer(z=-0.045, yaw=math.pi)
    assert case.force is None and case.displacement is None
    assert set(case.channels) == {"carriage", "tilt", "force_x", "torque_y"}
    rig = rig_for(case)
    assert isinstance(rig, MotionRig) and rig.axes == ("x", "pitch")
    assert rig_values(case) == {"rig.gravity": 9.80665, "rig.dry_mass": 1.2,
                                "rig.transducer_x": 0.0, "rig.transducer_y": 0.0,
                                "rig.transducer_z": -0.045, "rig.transducer_roll": 0.0,
                                "rig.transducer_pitch": 0.0, "rig.transducer_yaw": math.pi}


def test_unknown_columns_warn_with_the_nearest_name_and_fail_strict(tmp_path):
    path = _write(tmp_path, header="time,carriage,tilt,forcex,torque_y")
    with pytest.warns(UnknownKey, match=r"unknown column `forcex` \(ignored\); did you mean "
                                        r"`force_x`\?"):
        case = load_case(path)
    assert case.channels.keys() >= {"torque_y"}
    with pytest.raises(CaseError, match=r"unknown column `forcex`; did you mean `force_x`"):
        load_case(path, strict=True)


def test_every_problem_of_the_tables_and_columns_at_once(tmp_path):
    toml = (TOML.replace('pitch = "tilt"', 'pitch = 3\ny = "lateral"')
            .replace("yaw = 3.141592653589793", "yaw = 180.0"))
    with pytest.raises(CaseError) as err:
        load_case(_write(tmp_path, toml))
    text = str(err.value)
    assert "3 problems" in text, text
    assert re.search(r"\[rig.motion\] pitch: expected the name of the CSV column holding the "
                     r"tank's pitch angle \(rad\)", text)
    assert re.search(r"\[rig.transducer\] yaw: expected an angle in rad of magnitude up to "
                     r"2 pi, found 180.0 \(degrees\? 180 deg is 3.14", text)
    assert re.search(r"M1.csv: header \(line 1\): .*no column `lateral` \(`\[rig.motion\] y`\)",
                     text)


@pytest.mark.parametrize("toml, header, match", [
    (TOML, "time,carriage,tilt,bx,by",
     r"no force/torque channel \(expected one or more of `force_x`"),
    (TOML.replace('pitch = "tilt"', 'pitch = "carriage"'), "time,carriage,force_x",
     r"\[rig.motion\] pitch: the column `carriage` is also `x`"),
    (TOML.replace('pitch = "tilt"', 'pitch = "force_x"'), "time,carriage,force_x",
     r"`force_x` is the force/torque channel column, not a motion column"),
    (TOML.replace('x = "carriage"\npitch = "tilt"\n', ""), "time,force_x",
     r"\[rig.motion\]: names no motion column: expected at least one of `x`"),
    (TOML.replace("[rig.motion]\nx = \"carriage\"\npitch = \"tilt\"\n", ""), "time,displacement,force",
     r"\[rig.transducer\]: applies to six-axis records .* name the CSV columns of the measured "
     r"motion in a `\[rig.motion\]` table"),
    (TOML.replace('excitation = "measured"', 'excitation = "crank"'), "time,carriage,tilt,force_x",
     r'\[rig.motion\]: names measured motion columns: it needs `\[test\] excitation = '
     r'"measured"`, found "crank"'),
])
def test_bad_tables_and_columns_are_named(tmp_path, toml, header, match):
    with pytest.raises(CaseError, match=match):
        load_case(_write(tmp_path, toml, header))


def test_write_case_round_trips_a_six_axis_record(tmp_path):
    first = load_case(_write(tmp_path))
    out = write_case(tmp_path / "copy" / "M1.toml", test=first.test, tank=first.tank,
                     liquid=first.liquid, rig=first.rig, time=first.time,
                     channels=first.channels)
    assert out.rig == first.rig
    for name, values in first.channels.items():
        assert np.allclose(out.channels[name], values, rtol=1e-11)
    with pytest.raises(ValueError, match=r"six-axis record .* takes `channels`"):
        write_case(tmp_path / "other" / "bad.toml", test=first.test, tank=first.tank, liquid=first.liquid,
                   rig=first.rig, time=first.time, force=first.time)


def test_pendulums_are_spherical_where_the_record_sees_out_of_plane(tmp_path):
    planar = load_case(_write(tmp_path))  # x and pitch, force_x and torque_y: the x-z plane
    assert type(model_from_spec("fixed,p1", planar).components[2]) is Pendulum
    assert type(model_from_spec("fixed,p1:spherical", planar).components[2]) is SphericalPendulum
    (tmp_path / "b").mkdir()
    transverse = load_case(_write(tmp_path / "b", header="time,carriage,tilt,force_x,force_y"))
    assert type(model_from_spec("fixed,p1", transverse).components[2]) is SphericalPendulum
    # a model made for a lateral case runs on the case's motion rig
    from analogs import FixedMass, LateralRig

    moved = model_for_case(LateralRig(dry_mass=1.2) + FixedMass("fixed"), planar)
    assert isinstance(moved.rig, MotionRig) and moved.rig.axes == ("x", "pitch")


#: A noise-free ramped sine from rest, differentiated by the filter with the rest
#: continued: the error is the filter's own (its 0.1 % gain error at the drive, the end
#: model past the last sample), far below the 7 % the end model alone put into the first
#: half second of a pitch ramp.
RAMP_ACCELERATION = 5e-3


def test_a_motion_from_rest_is_differentiated_without_a_start_transient():
    t = np.arange(4001) * 0.002
    sig = rm.RampedSine(math.radians(5), 0.95, ramp=2.0, start=0.7)
    y, yd, ydd = sig(t)
    _, vd, vdd = axis_derivatives(t, y)
    peak = np.max(np.abs(ydd))
    inner = t < t[-1] - 1.0  # the last second runs on the end model (not at rest there)
    assert np.max(np.abs(vdd - ydd)[inner]) < RAMP_ACCELERATION * peak
    assert np.max(np.abs(vd - yd)[inner]) < RAMP_ACCELERATION * np.max(np.abs(yd))


@pytest.fixture(scope="module")
def sign_folder(tmp_path_factory):
    return tmp_path_factory.mktemp("sign")


@pytest.mark.parametrize("ratio", [0.5, 1.1])
def test_a_transducer_turned_without_saying_so_is_named(sign_folder, ratio):
    f1 = PENDULUM.frequency_hz()
    motion = rm.Motion(x=rm.RampedSine(0.002, ratio * f1, ramp=1.5, start=0.5))
    kw = dict(duration=10.0, rate=200.0, seed=4)
    # the truth (turned by 180 deg, declared so) loads, also just above resonance where the
    # steady force is in antiphase with the acceleration
    case, _ = make_motion_case(sign_folder, f"ok{ratio}", motion, **kw)
    assert case.motion.axes == ("x",)
    with pytest.raises(CaseError, match=r"column `force_x`: the force along the motion has "
                                        r"the opposite sign of mass x acceleration: it reads "
                                        r"-[0-9.]+ kg .*`\[rig.transducer\]`"):
        make_motion_case(sign_folder, f"bad{ratio}", motion,
                         declared=rm.Transducer((0.0, 0.0, -0.045)), **kw)


def test_the_rig_inputs_follow_the_model_order(tmp_path):
    case = load_case(_write(tmp_path))
    exc = motion_excitation(case)
    assert exc.size == 6
    x = exc.values(case.time)
    inner = slice(100, -100)  # a record that neither starts nor ends at rest: its ends aside
    assert np.allclose(x[0][inner], case.channels["carriage"][inner], atol=1e-5)
    assert np.allclose(x[3][inner], case.channels["tilt"][inner], atol=1e-4)
    assert isinstance(Rig(dry_mass=None, gravity=9.8, motion=Motion(x="a")).motion, Motion)
