"""The tanks a case file describes (sphere, cylinder with its length, capsule, upright
rectangular tank): the liquid mass and the first-mode prediction a fit starts from,
checked against closed forms; and the messages for sizes that are missing or misplaced."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import reference_rig_records as rig

from estimate.data import load_case, write_case
from estimate.data.case import CaseError, Liquid, Rig, Tank, TestInfo
from estimate.fitting.initial import _tank_prediction, predicted_values

RHO, G = 998.2, 9.80665
#: Closed forms against the modal solvers (converged to < 2e-8 on flat-bottomed
#: cylinders, tests/analogs/tank) and against exact volumes (Gauss rules, round-off).
CLOSED_FORM = 1e-6
VOLUME = 1e-12


def _case(tmp_path: Path, tank: Tank):
    t = np.arange(200) * 0.01
    return write_case(tmp_path / "c.toml", test=TestInfo("c", "lateral", "c.csv", "measured"),
                      tank=tank, liquid=Liquid(RHO, 1.004e-6), rig=Rig(1.0, G), time=t,
                      force=np.sin(2 * np.pi * 1.5 * t),
                      displacement=0.005 * np.sin(2 * np.pi * 1.5 * t), overwrite=True)


@pytest.mark.parametrize("radius, length, fill", [(0.1, 0.3, 0.5), (0.25, 0.2, 0.7)])
def test_cylinder_uses_its_length(tmp_path, radius, length, fill):
    """The liquid mass and first mode of an upright cylinder follow its length (a cylinder
    was assumed as tall as its diameter before): SP-106's closed form at the depth
    ``fill * length``."""
    case = _case(tmp_path, Tank("cylinder", radius, fill, False, length=length))
    depth = fill * length
    ref = rig.cylinder_first_mode(radius, depth, RHO, G)
    assert case.tank.liquid_mass(RHO) == pytest.approx(ref["liquid_mass"], rel=VOLUME)
    mode = _tank_prediction(case, 1).modes[0]
    assert mode.mass == pytest.approx(ref["mass"], rel=CLOSED_FORM)
    assert mode.length == pytest.approx(ref["length"], rel=CLOSED_FORM)
    assert mode.frequency_hz == pytest.approx(ref["frequency"], rel=CLOSED_FORM)
    # the fit's start values come from that prediction
    from estimate.data.models import model_from_spec

    start = predicted_values(case, model_from_spec("fixed,p1", case))
    assert start["p1.mass"] == pytest.approx(ref["mass"], rel=CLOSED_FORM)
    assert start["fixed.mass"] == pytest.approx(ref["liquid_mass"] - ref["mass"],
                                                rel=CLOSED_FORM)


def test_capsule_liquid_mass_and_prediction(tmp_path):
    """A capsule filled into its straight section holds a hemisphere plus a cylinder of
    liquid; with no straight section it is the sphere of its radius."""
    R, c, fill = 0.15, 0.4, 0.6
    case = _case(tmp_path, Tank("capsule", R, fill, False, cylinder_length=c))
    depth = fill * (c + 2 * R)
    hand = RHO * (2 / 3 * math.pi * R**3 + math.pi * R**2 * (depth - R))
    assert case.tank.liquid_mass(RHO) == pytest.approx(hand, rel=VOLUME)
    p = _tank_prediction(case, 1)
    assert p.liquid_mass == pytest.approx(hand, rel=VOLUME)
    assert p.fixed_mass.mass + p.modes[0].mass == pytest.approx(hand, rel=VOLUME)
    ball = _case(tmp_path, Tank("capsule", R, 0.6, False, cylinder_length=0.0))
    sphere = _case(tmp_path, Tank("sphere", R, 0.6, False))
    assert _tank_prediction(ball, 1).modes[0].frequency_hz == pytest.approx(
        _tank_prediction(sphere, 1).modes[0].frequency_hz, rel=CLOSED_FORM)


def test_rectangular_tank(tmp_path):
    """An upright box, moved along its length: SP-106 / Ibrahim's closed form,
    ``omega^2 = (pi g / a) tanh(pi h / a)``, ``m1 = m 8 tanh(pi h / a) / (pi^3 h / a)``."""
    a, b, H, fill = 0.4, 0.2, 0.3, 0.5
    case = _case(tmp_path, Tank("rectangular", None, fill, False, length=a, width=b, height=H))
    h = fill * H
    m_liquid = RHO * a * b * h
    om2 = math.pi * G / a * math.tanh(math.pi * h / a)
    assert case.tank.liquid_mass(RHO) == pytest.approx(m_liquid, rel=VOLUME)
    mode = _tank_prediction(case, 1).modes[0]
    assert mode.frequency_hz == pytest.approx(math.sqrt(om2) / (2 * math.pi), rel=VOLUME)
    assert mode.mass == pytest.approx(
        m_liquid * 8 * math.tanh(math.pi * h / a) / (math.pi**3 * h / a), rel=VOLUME)
    assert mode.length == pytest.approx(G / om2, rel=VOLUME)
    # written and read back with its three sizes
    text = (tmp_path / "c.toml").read_text()
    assert re.search(r"^length = 0\.4", text, re.M) and "radius" not in text


def _toml(tank_lines: str) -> str:
    return f"""[test]
id = "c"
rig = "lateral"
data = "c.csv"
excitation = "measured"

[tank]
{tank_lines}
fill_fraction = 0.5
diaphragm = false

[liquid]
density = 998.2
kinematic_viscosity = 1.004e-6

[rig]
dry_mass = 1.0
gravity = 9.80665
"""


def _problems(tmp_path: Path, tank_lines: str) -> list[str]:
    _case(tmp_path, Tank("sphere", 0.1, 0.5, False))
    path = tmp_path / "c.toml"
    path.write_text(_toml(tank_lines))
    with pytest.raises(CaseError) as info:
        load_case(path)
    return info.value.problems


@pytest.mark.parametrize("lines, expected", [
    ('shape = "cylinder"\nradius = 0.1',
     r"c.toml: \[tank\] length: missing key \(expected the inside length in m for "
     r"`shape = \"cylinder\"`: the inside height, which the fill fraction is measured against"),
    ('shape = "capsule"\nradius = 0.1\nlength = 0.5',
     r"c.toml: \[tank\] length: not a size of a capsule .*`cylinder_length`"),
    ('shape = "rectangular"\nradius = 0.1\nlength = 0.4\nwidth = 0.2\nheight = 0.3',
     r"c.toml: \[tank\] radius: not a size of a rectangular \(expected only `length`, "
     r"`width`, `height`"),
    ('shape = "rectangular"\nlength = 0.4\nwidth = -0.2\nheight = 0.3',
     r"c.toml: \[tank\] width: expected a positive number in m, found -0.2"),
    ('shape = "sphere"\nradius = 0.1\nheight = 0.3',
     r"c.toml: \[tank\] height: not a size of a sphere"),
    ('shape = "cube"\nradius = 0.1',
     r'c.toml: \[tank\] shape: unknown value "cube" \(expected one of "sphere", "cylinder", '
     r'"capsule", "rectangular"\)'),
])
def test_tank_size_problems_name_the_key(tmp_path, lines, expected):
    problems = _problems(tmp_path, lines)
    assert any(re.search(expected, p) for p in problems), problems
