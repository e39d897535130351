"""``[rig.limits]`` in case files: read, validated, written, and required by a design."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest
from design_helpers import LIMITS

from analogs.errors import InputError
from estimate import CaseError, load_case
from estimate.design import required_limits

ROOT = Path(__file__).resolve().parents[3]
#: The bundled case file without its `[rig.limits]` table (the tests give their own).
WITHOUT_LIMITS = re.sub(r"\[rig\.limits\]\n(?:[^\[\n][^\n]*\n)*\n?", "",
                        (ROOT / "examples" / "A1.toml").read_text())


def _case_with(tmp_path, table: str):
    text = WITHOUT_LIMITS
    (tmp_path / "A1.csv").write_bytes((ROOT / "examples" / "A1.csv").read_bytes())
    path = tmp_path / "A1.toml"
    path.write_text(text + "\n" + table)
    return path


def test_limits_are_read(tmp_path):
    path = _case_with(tmp_path, "[rig.limits]\nstroke = 0.1\nvelocity = 0.5\n"
                                "acceleration = 3\nduration = 60.0\nsample_rate = 200\n")
    lim = load_case(path).rig.limits
    assert (lim.stroke, lim.velocity, lim.acceleration, lim.duration, lim.sample_rate) == \
        (0.1, 0.5, 3.0, 60.0, 200.0)
    assert lim.spin_rate is None
    assert required_limits(load_case(path)) == lim


def test_bad_limits_are_listed_with_file_table_and_key(tmp_path):
    path = _case_with(tmp_path, '[rig.limits]\nstroke = -0.1\nvelocity = "fast"\n'
                                "acceleration = true\nduration = 60.0\n")
    with pytest.raises(CaseError) as err:
        load_case(path)
    problems = err.value.problems
    assert any("A1.toml: [rig.limits] stroke: expected a positive number in m, found -0.1"
               in p for p in problems)
    assert any("[rig.limits] velocity: expected a number in m/s, found a string" in p
               for p in problems)
    assert any("[rig.limits] acceleration: expected a number in m/s^2, found a boolean" in p
               for p in problems)


def test_a_design_needs_the_limits_and_says_which(tmp_path):
    case = load_case(_case_with(tmp_path, ""))
    with pytest.raises(InputError, match=r"A1.toml: has no `\[rig.limits\]` table; .*"
                                         r"stroke = .*velocity = .*acceleration = .*duration"):
        required_limits(case)
    case = load_case(_case_with(tmp_path, "[rig.limits]\nstroke = 0.1\nduration = 20\n"))
    with pytest.raises(InputError, match=r"`\[rig.limits\]` lacks `velocity`, `acceleration`"):
        required_limits(case)


def test_limits_are_written_and_read_back(tmp_path):
    from estimate import write_case

    case = load_case(ROOT / "examples" / "A1.toml")
    out = write_case(tmp_path / "B.toml", test=replace(case.test, data="B.csv"), tank=case.tank,
                     liquid=case.liquid, rig=replace(case.rig, limits=LIMITS), time=case.time,
                     force=case.force, displacement=case.displacement)
    assert out.rig.limits == LIMITS
    assert "[rig.limits]" in (tmp_path / "B.toml").read_text()
