"""The result store: keys of every input, exact round trips, atomic writes."""

from __future__ import annotations

import json
import os

import pytest

from estimate.campaign import store as store_module
from estimate.campaign.store import Store, task_key, write_atomic

FILES = [("a" * 64, "b" * 64)]


def test_the_key_changes_with_every_input(monkeypatch):
    base = task_key("fit", FILES, "fixed,p1", {"input": "estimated"})
    others = [task_key("diagnosis", FILES, "fixed,p1", {"input": "estimated"}),
              task_key("fit", [("c" * 64, "b" * 64)], "fixed,p1", {"input": "estimated"}),
              task_key("fit", [("a" * 64, "c" * 64)], "fixed,p1", {"input": "estimated"}),
              task_key("fit", FILES + FILES, "fixed,p1", {"input": "estimated"}),
              task_key("fit", FILES, "fixed,p1:nospring", {"input": "estimated"}),
              task_key("fit", FILES, "fixed,p1", {"input": "filtered"})]
    monkeypatch.setattr(store_module, "package_version", lambda: "9.9.9")
    others.append(task_key("fit", FILES, "fixed,p1", {"input": "estimated"}))
    assert len({base, *others}) == len(others) + 1
    monkeypatch.undo()
    assert task_key("fit", FILES, "fixed,p1", {"input": "estimated"}) == base


def test_outcomes_round_trip_exactly(tmp_path):
    s = Store(tmp_path / "store")
    outcome = {"status": "ok", "x": 0.1 + 0.2, "tiny": 5e-324, "nan": float("nan"),
               "list": [1, "two", None]}
    s.put("k1", outcome, seconds=1.5)
    got = s.get("k1")
    assert got["x"] == 0.1 + 0.2 and got["tiny"] == 5e-324 and got["list"] == [1, "two", None]
    assert got["nan"] != got["nan"]
    assert s.seconds("k1") == 1.5 and s.keys() == {"k1"}
    assert s.get("missing") is None


def test_a_damaged_entry_is_computed_again(tmp_path):
    s = Store(tmp_path)
    (tmp_path / "k1.json").write_text('{"key": "k1", "outcome": ')
    (tmp_path / "k2.json").write_text(json.dumps({"key": "other", "outcome": {}}))
    with pytest.warns(RuntimeWarning, match="damaged"):
        assert s.get("k1") is None
    with pytest.warns(RuntimeWarning, match="names another key"):
        assert s.get("k2") is None


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    target = tmp_path / "t.json"
    target.write_bytes(b"old")

    def fail(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError, match="disk full"):
        write_atomic(target, b"new")
    monkeypatch.undo()
    assert target.read_bytes() == b"old" and os.listdir(tmp_path) == ["t.json"]
    write_atomic(target, b"new")
    assert target.read_bytes() == b"new" and os.listdir(tmp_path) == ["t.json"]
