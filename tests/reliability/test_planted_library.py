"""Issue 26, bad finding 1: a native library planted in a cache others can write is never
loaded.

The planted library is a real shared object whose constructor (``__attribute__((constructor))``,
run by ``dlopen`` before anything else) writes a marker file. It is placed where the cache
would look for the compiled RK4-like function, with a matching ``.sha256``, and the cache is
made writable by others in each way an attacker could arrange it. A fresh process then asks
for the compiled function: the marker must stay absent, the result must be right (built
anew elsewhere), and the command must say once why the cache was not used. The control
row (everything private to the user) loads the planted library, which shows that the test
sees a load when one happens.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import casadi as ca
import pytest

from derive._compile import c_compiler

pytestmark = [pytest.mark.skipif(c_compiler() is None, reason="needs a C compiler"),
              pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")]

ROOT = Path(__file__).resolve().parents[2]
NOBODY = 65534  # an account that is not the user's (the tests run as root here)

_PROBE = textwrap.dedent("""
    import casadi as ca
    from derive._compile import compiled
    x = ca.SX.sym("x")
    fn = ca.Function("planted_sq", [x], [x * x + 1.0])
    print(float(compiled(fn)(3.0)))
""")


def _function() -> ca.Function:
    x = ca.SX.sym("x")
    return ca.Function("planted_sq", [x], [x * x + 1.0])


def _plant(folder: Path, marker: Path) -> Path:
    """A library with the name the cache looks for, its constructor writing ``marker``,
    and a matching ``.sha256``."""
    key = hashlib.sha256(_function().serialize().encode()).hexdigest()[:24]
    folder.mkdir(parents=True, exist_ok=True)
    src = folder.parent / "evil.c"
    src.write_text('#include <stdio.h>\n'
                   '__attribute__((constructor)) static void planted(void) {\n'
                   f'  FILE *f = fopen("{marker}", "w"); if (f) {{ fputs("ran", f); '
                   'fclose(f); }\n}\n')
    lib = folder / f"planted_sq_{key}.so"
    subprocess.run([c_compiler(), "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
    src.unlink()
    lib.with_name(lib.name + ".sha256").write_text(hashlib.sha256(lib.read_bytes()).hexdigest())
    return lib


def _run(cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "SLOSH_CACHE_DIR": str(cache), "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", _PROBE], env=env, cwd=ROOT, capture_output=True,
                          text=True, timeout=120)


def _root_world_writable(tmp: Path) -> Path:
    cache = tmp / "cache"
    cache.mkdir(mode=0o700)
    (cache / "compiled").mkdir(mode=0o700)     # a private-looking sub-folder ...
    cache.chmod(0o777)                          # ... in a root anyone can write
    return cache


def _link_to_shared(tmp: Path) -> Path:
    shared = tmp / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    (shared / "compiled").mkdir(mode=0o700)
    (tmp / "cache").symlink_to(shared)
    return tmp / "cache"


def _sub_folder_of_another_account(tmp: Path) -> Path:
    cache = tmp / "cache"
    cache.mkdir(mode=0o700)
    (cache / "compiled").mkdir(mode=0o700)
    os.chown(cache / "compiled", NOBODY, NOBODY)
    return cache


def _sub_folder_replaced_by_a_link(tmp: Path) -> Path:
    cache = tmp / "cache"
    cache.mkdir(mode=0o700)
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    elsewhere.chmod(0o777)
    (cache / "compiled").symlink_to(elsewhere)
    return cache


def _root_of_another_account(tmp: Path) -> Path:
    cache = tmp / "cache"
    cache.mkdir(mode=0o700)
    (cache / "compiled").mkdir(mode=0o700)
    os.chown(cache, NOBODY, NOBODY)
    return cache


def _group_writable_library(tmp: Path) -> Path:
    cache = tmp / "cache"
    cache.mkdir(mode=0o700)
    (cache / "compiled").mkdir(mode=0o700)
    return cache


ATTACKS = {
    "cache root chmod 777, compiled/ private-looking": _root_world_writable,
    "cache root a symlink to a folder anyone can write": _link_to_shared,
    "compiled/ owned by another account": _sub_folder_of_another_account,
    "compiled/ replaced by a symlink to a folder anyone can write": _sub_folder_replaced_by_a_link,
    "cache root owned by another account": _root_of_another_account,
}


@pytest.mark.parametrize("attack", list(ATTACKS))
def test_a_planted_library_is_never_loaded(attack, tmp_path):
    tmp_path.chmod(0o700)
    marker = tmp_path / "marker"
    cache = ATTACKS[attack](tmp_path)
    _plant(cache / "compiled", marker)
    proc = _run(cache)
    assert proc.returncode == 0, proc.stderr
    assert not marker.exists(), f"{attack}: the planted library was loaded"
    assert float(proc.stdout.strip().splitlines()[-1]) == 10.0
    assert "is not used" in proc.stderr and "private temporary folder" in proc.stderr


def test_a_library_others_can_write_is_not_loaded_from_a_private_cache(tmp_path):
    tmp_path.chmod(0o700)
    marker = tmp_path / "marker"
    cache = _group_writable_library(tmp_path)
    lib = _plant(cache / "compiled", marker)
    lib.chmod(0o777)
    proc = _run(cache)
    assert proc.returncode == 0, proc.stderr
    assert not marker.exists()
    assert float(proc.stdout.strip().splitlines()[-1]) == 10.0
    assert "compiled library not loaded" in proc.stderr and "writable by group or others" \
        in proc.stderr


def test_control_a_planted_library_in_a_private_cache_is_loaded(tmp_path):
    """The same plant in a cache only the user can write is loaded (its constructor runs):
    the rows above would see a load. The user's own folder is trusted by design."""
    tmp_path.chmod(0o700)
    marker = tmp_path / "marker"
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    _plant(cache / "compiled", marker)
    (cache / "compiled").chmod(0o700)
    _run(cache)
    assert marker.read_text() == "ran"
    shutil.rmtree(cache)
