"""Outputs are transactions (estimate/outputs.py): checked first, written to temporary names,
renamed into place together; strict JSON."""

from __future__ import annotations

import errno
import json
import math

import numpy as np
import pytest

from estimate.outputs import NON_FINITE_KEY, OutputError, Outputs, json_text

KEEP = b"earlier result, not to be lost\n"


def _strict(text: str):
    def refuse(name):
        raise ValueError(f"non-standard JSON constant {name}")
    return json.loads(text, parse_constant=refuse)


def test_json_is_strict_and_lists_what_was_not_finite():
    data = {"rms_after": float("nan"), "findings": [{"gain": np.float64(np.inf)}],
            "ok": np.float32(1.5), "n": np.int64(3), "a/b": [-math.inf]}
    out = _strict(json_text(data))
    assert out["rms_after"] is None and out["findings"][0]["gain"] is None
    assert out["ok"] == 1.5 and out["n"] == 3
    assert out[NON_FINITE_KEY] == {"/rms_after": "NaN", "/findings/0/gain": "Infinity",
                                   "/a~1b/0": "-Infinity"}
    assert NON_FINITE_KEY not in _strict(json_text({"x": 1.0}))
    assert math.isnan(data["rms_after"])  # the caller's data are not changed


def test_check_lists_every_problem_before_anything_is_computed(tmp_path):
    (tmp_path / "old.json").write_bytes(KEEP)
    (tmp_path / "afile").write_bytes(KEEP)
    out = (Outputs(overwrite=False, inputs=[tmp_path / "in.toml"])
           .file("--json", tmp_path / "missing" / "a.json")
           .file("--plot", tmp_path)
           .file("--csv", tmp_path / "old.json")
           .file("--in", tmp_path / "in.toml")
           .folder("--report", tmp_path / "afile", ["summary.md"]))
    with pytest.raises(OutputError) as info:
        out.check()
    msg = str(info.value)
    assert "--json" in msg and "missing does not exist" in msg
    assert "--plot" in msg and "is a folder; expected a file name" in msg
    assert "old.json exist(s); pass --overwrite" in msg
    assert "--in" in msg and "is an input of the command" in msg
    assert "--report" in msg and "is a file; expected a folder" in msg


def test_two_options_writing_one_file_are_refused(tmp_path):
    out = Outputs(overwrite=True).file("--json", tmp_path / "x").file("--plot", tmp_path / "x")
    with pytest.raises(OutputError, match="--json and --plot both write"):
        out.check()


def test_a_failure_while_writing_leaves_the_previous_files_and_no_temporary_ones(tmp_path):
    """Disk full in the middle of the second output: the first, already complete, is not
    committed either."""
    a, b = tmp_path / "a.json", tmp_path / "b.png"
    a.write_bytes(KEEP)
    b.write_bytes(KEEP)
    out = Outputs(overwrite=True).file("--json", a).file("--plot", b)
    out.check()
    with pytest.raises(OutputError, match=r"could not write --json .*a\.json.*no space left on "
                                          r"device; nothing was written, existing files"):
        with out.writing() as paths:
            paths["--json"].write_text("new")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert a.read_bytes() == KEEP and b.read_bytes() == KEEP
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.png"]


def test_an_exception_while_writing_is_not_committed(tmp_path):
    a = tmp_path / "a.json"
    a.write_bytes(KEEP)
    out = Outputs(overwrite=True).file("--json", a)
    with pytest.raises(KeyboardInterrupt):
        with out.writing() as paths:
            paths["--json"].write_text("partial")
            raise KeyboardInterrupt
    assert a.read_bytes() == KEEP and [p.name for p in tmp_path.iterdir()] == ["a.json"]


def test_all_outputs_are_committed_together_with_the_usual_permissions(tmp_path):
    a, folder = tmp_path / "a.json", tmp_path / "report"
    folder.mkdir()
    (folder / "other.txt").write_bytes(KEEP)
    (folder / "summary.md").write_bytes(KEEP)
    out = Outputs(overwrite=True).file("--json", a).folder("--report", folder,
                                                           ["summary.md", "plot.png"])
    out.check()
    with out.writing() as paths:
        paths["--json"].write_text("{}\n")
        (paths["--report"] / "summary.md").write_text("new\n")
        (paths["--report"] / "plot.png").write_bytes(b"png")
    assert a.read_text() == "{}\n" and a.stat().st_mode & 0o777 == 0o666 & ~_umask()
    assert (folder / "summary.md").read_text() == "new\n"
    assert (folder / "other.txt").read_bytes() == KEEP  # not an output: left alone
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "report"]
    assert sorted(p.name for p in folder.iterdir()) == ["other.txt", "plot.png", "summary.md"]


def test_an_output_that_appeared_meanwhile_is_not_replaced_without_overwrite(tmp_path):
    a = tmp_path / "a.json"
    out = Outputs(overwrite=False).file("--json", a)
    out.check()
    with pytest.raises(OutputError, match="a.json exist"):
        with out.writing() as paths:
            paths["--json"].write_text("new")
            a.write_bytes(KEEP)  # another process was quicker
    assert a.read_bytes() == KEEP


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask
