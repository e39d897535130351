"""Public hooks other packages use: DerivedModel.memo (get-or-build) and the one atomic
writer (derive.cache.write_atomic, estimate.outputs.write_atomic)."""

import os
import stat

import pytest

from analogs import FixedMass, LateralRig
from derive import derive
from derive.cache import write_atomic
from estimate.outputs import output_mode
from estimate.outputs import write_atomic as write_output


def test_memo_builds_once_per_key():
    dm = derive(LateralRig() + FixedMass("fixed"))
    calls = []

    def build():
        calls.append(1)
        return object()

    first = dm.memo(("test-hook", 1), build)
    assert dm.memo(("test-hook", 1), build) is first and len(calls) == 1
    assert dm.memo(("test-hook", 2), build) is not first and len(calls) == 2
    assert dm.memoized is not None  # the former name


def test_write_atomic_replaces_whole_files_and_leaves_no_temporary(tmp_path):
    path = write_atomic(tmp_path / "a.json", "old")
    write_atomic(path, b"new")
    assert path.read_bytes() == b"new"
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600  # private, as cache entries are
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]


def test_an_interrupted_write_leaves_the_old_file(tmp_path):
    path = write_atomic(tmp_path / "a.txt", "old")

    class Broken(str):
        def encode(self, *args):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_atomic(path, Broken("new"))
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_outputs_get_the_output_mode(tmp_path):
    path = write_output(tmp_path / "store.json", "{}")
    assert stat.S_IMODE(os.stat(path).st_mode) == output_mode()
