"""Campaign discovery: records of a folder or glob, groups by tank/fill/liquid/rig or from
campaign.toml, and every problem of a campaign file reported at once."""

from __future__ import annotations

import pytest
from campaign_helpers import case_toml

from analogs.errors import InputError
from estimate.campaign import discover


def test_records_of_one_tank_fill_and_liquid_form_a_group(tmp_path):
    for name, fill, rho in (("a", 0.4, 998.2), ("b", 0.4, 998.2), ("c", 0.6, 998.2),
                            ("d", 0.4, 1000.0)):
        case_toml(tmp_path / "sub", name, fill=fill, density=rho)
    (tmp_path / "notes.toml").write_text('[other]\nx = 1\n')      # not a case file
    c = discover(str(tmp_path))
    assert [r.id for r in c.records] == ["a", "b", "c", "d"]
    assert {g.records for g in c.groups} == {("a", "b"), ("c",), ("d",)}
    # the liquid varies across the campaign, so it is part of the names
    names = {g.records: g.name for g in c.groups}
    assert names[("a", "b")] == "sphere-R0.1016-fill0.4-density998.2"
    assert names[("d",)] == "sphere-R0.1016-fill0.4-density1000"
    assert c.model == "fixed,p1" and all(g.model == "fixed,p1" for g in c.groups)
    assert c.skipped == (str(tmp_path / "notes.toml"),)
    assert c.record("a").relpath == "sub/a.toml"


def test_keys_do_not_depend_on_paths_but_on_bytes(tmp_path):
    case_toml(tmp_path / "x", "a")
    case_toml(tmp_path / "y", "a")
    a, b = discover(str(tmp_path / "x")).records[0], discover(str(tmp_path / "y")).records[0]
    assert (a.toml_sha256, a.data_sha256) == (b.toml_sha256, b.data_sha256)
    (tmp_path / "y" / "a.csv").write_text("time,displacement,force\n0,0,1\n")
    assert discover(str(tmp_path / "y")).records[0].data_sha256 != a.data_sha256


def test_a_glob_uses_the_campaign_file_of_its_top_folder(tmp_path):
    for name, fill in (("F40_a", 0.4), ("F40_b", 0.4), ("F60_a", 0.6)):
        case_toml(tmp_path / "data", name, fill=fill)
    (tmp_path / "campaign.toml").write_text(
        '[campaign]\ntitle = "T"\nmodel = "fixed,p1:nospring"\n'
        '[groups.low]\nrecords = ["F40_*"]\nmodel = "fixed,p1"\n'
        '[groups.mid]\nrecords = ["data/F60_a.toml"]\n')
    c = discover(str(tmp_path / "**" / "*.toml"))
    assert c.title == "T" and c.model == "fixed,p1:nospring"
    assert [(g.name, g.records, g.model) for g in c.groups] == [
        ("low", ("F40_a", "F40_b"), "fixed,p1"), ("mid", ("F60_a",), "fixed,p1:nospring")]
    assert c.model_of("F40_a") == "fixed,p1"
    # --model replaces every model the file names
    assert {g.model for g in discover(str(tmp_path), model="fixed,p1,p2").groups} == {
        "fixed,p1,p2"}


def test_every_problem_of_the_campaign_file_is_listed(tmp_path):
    case_toml(tmp_path, "a")
    case_toml(tmp_path, "b")
    (tmp_path / "campaign.toml").write_text(
        '[campaign]\nmodle = "fixed"\ninput = "smoothed"\n[extra]\n'
        '[groups.g1]\nrecords = ["a", "zz*"]\n[groups.g2]\nrecords = ["a"]\ncolour = 1\n'
        '[groups.g3]\nrecords = "b"\n')
    with pytest.raises(InputError, match="7 problems in the campaign file") as err:
        discover(str(tmp_path))
    text = str(err.value)
    for expected in ("unknown table `[extra]`", "unknown key `modle`", "input: expected one of",
                     "'zz*' matches no record", "record 'a' is already in group 'g1'",
                     "[groups.g2]: unknown key `colour`", "[groups.g3] records: expected a list"):
        assert expected in text


@pytest.mark.parametrize("setup, message", [
    (lambda p: None, "no case files"),
    (lambda p: (case_toml(p / "x", "a"), case_toml(p / "y", "a")), r"\[test\] id 'a' in x/a.toml, y/a.toml"),
])
def test_campaign_errors(tmp_path, setup, message):
    setup(tmp_path)
    with pytest.raises(InputError, match=message):
        discover(str(tmp_path))


def test_a_missing_folder_is_named(tmp_path):
    with pytest.raises(InputError, match="no such folder"):
        discover(str(tmp_path / "nowhere"))


def test_unreadable_files_are_records_without_keys(tmp_path):
    case_toml(tmp_path, "a", data=False)
    (tmp_path / "broken.toml").write_bytes(b"[test\nid = ")
    c = discover(str(tmp_path))
    assert [r.id for r in c.records] == ["a", "broken"]
    assert c.record("a").data_sha256 is None and c.record("broken").setup is None
    assert [g.records for g in c.groups] == [("a",)]       # 'broken' is in no group
