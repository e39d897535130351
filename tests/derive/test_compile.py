"""Compiled libraries in the cache are checked against their stored hash before loading."""

import os

import casadi as ca
import numpy as np
import pytest

from derive import _compile
from derive._compile import c_compiler, compiled

pytestmark = pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler")


def _square(name):
    x = ca.SX.sym("x")
    return ca.Function(name, [x], [x * x + 1.0])


def test_a_truncated_library_is_rebuilt_not_loaded(tmp_path, monkeypatch):
    """Issue 13, bad finding 6: a truncated `.so` crashed every later run with SIGBUS. Now
    its hash no longer matches, so it is rebuilt with a warning and the result is right."""
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_compile, "_LOADED", {})
    assert float(compiled(_square("sq_truncated"))(3.0)) == 10.0
    (lib,) = (tmp_path / "compiled").glob("sq_truncated_*.so")
    # a new file in its place: this process still maps the first library, and truncating
    # that inode in place would crash it (as it crashed later runs before the hash check)
    damaged = lib.with_suffix(".tmp")
    damaged.write_bytes(lib.read_bytes()[:100])
    os.replace(damaged, lib)
    monkeypatch.setattr(_compile, "_LOADED", {})
    with pytest.warns(RuntimeWarning, match="does not match its stored hash"):
        fn = compiled(_square("sq_truncated"))
    assert float(fn(3.0)) == 10.0
    assert (tmp_path / "compiled").stat().st_mode & 0o077 == 0


def test_a_library_without_its_hash_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_compile, "_LOADED", {})
    compiled(_square("sq_nohash"))
    (stamp,) = (tmp_path / "compiled").glob("sq_nohash_*.so.sha256")
    stamp.unlink()
    monkeypatch.setattr(_compile, "_LOADED", {})
    with pytest.warns(RuntimeWarning, match="stored hash"):
        fn = compiled(_square("sq_nohash"))
    assert np.isclose(float(fn(2.0)), 5.0)
