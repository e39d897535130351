"""Derivation happens once: later derives, also in new processes, load from disk."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import derive

ROOT = Path(__file__).resolve().parents[2]


def _two_pendulum():
    return (LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
            + Pendulum("p2") + HingeDamper("p2"))


def test_second_derive_in_a_new_process_loads_from_cache_without_sympy(tmp_path):
    env = {**os.environ, "SLOSH_CACHE_DIR": str(tmp_path)}
    script = (
        "import sys, json\n"
        "from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum\n"
        "from derive import derive\n"
        "m = (LateralRig() + FixedMass('fixed') + Pendulum('p1') + HingeSpring('p1') + HingeDamper('p1')"
        " + Pendulum('p2') + HingeDamper('p2'))\n"
        "dm = derive(m)\n"
        "print(json.dumps({'cached': dm.from_cache, 'sympy': 'sympy' in sys.modules}))\n"
    )
    runs = [json.loads(subprocess.run([sys.executable, "-c", script], env=env, cwd=ROOT, check=True,
                                      capture_output=True, text=True).stdout) for _ in range(2)]
    assert runs[0] == {"cached": False, "sympy": True}
    assert runs[1] == {"cached": True, "sympy": False}


def test_two_processes_deriving_one_model_at_once_derive_it_once(tmp_path):
    # both wait for a go file, then derive at the same moment: without the lock both would
    # run SymPy (both report cached False); with it the second waits and loads the entry
    env = {**os.environ, "SLOSH_CACHE_DIR": str(tmp_path / "cache")}
    go = tmp_path / "go"
    script = (
        "import json, time, pathlib\n"
        "from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum\n"
        "from derive import derive\n"
        "m = (LateralRig() + FixedMass('fixed') + Pendulum('p1') + HingeSpring('p1') + HingeDamper('p1')"
        " + Pendulum('p2') + HingeDamper('p2'))\n"
        f"while not pathlib.Path({str(go)!r}).exists(): time.sleep(0.01)\n"
        "print(json.dumps(derive(m).from_cache))\n"
    )
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env, cwd=ROOT, stdout=subprocess.PIPE,
                              text=True) for _ in range(2)]
    go.touch()
    cached = sorted(json.loads(p.communicate(timeout=300)[0]) for p in procs)
    assert [p.returncode for p in procs] == [0, 0]
    assert cached == [False, True]


def test_cached_model_evaluates_like_a_fresh_derivation():
    fresh = derive(_two_pendulum(), use_cache=False)
    derive(_two_pendulum())  # store
    cached = derive(_two_pendulum())
    assert cached.from_cache and not fresh.from_cache
    args = ([0.1, -0.2, 0.3, 0.4], [0.0, 0.1, -2.0], list(range(1, len(fresh.parameter_names) + 1)), 0.5)
    assert np.array_equal(np.asarray(fresh.outputs(*args)), np.asarray(cached.outputs(*args)))
    assert np.array_equal(np.asarray(fresh.rhs(*args)), np.asarray(cached.rhs(*args)))


def test_changing_the_structure_changes_the_cache_key_but_values_do_not():
    a = LateralRig() + FixedMass("fixed", mass=1.0) + Pendulum("p1")
    b = LateralRig() + FixedMass("fixed", mass=2.0) + Pendulum("p1", bounds={"length": (0.01, 0.1)})
    c = LateralRig() + FixedMass("fixed") + Pendulum("p1", plane="yz")
    assert a.structure_key() == b.structure_key()
    assert a.structure_key() != c.structure_key()


_SLIDING = '''
from analogs import Component, Param

class SlidingMass(Component):
    coordinates = ("s",)
    coordinate_units = {{"s": "m"}}
    parameters = {{"mass": Param("kg", lower=0.0), "stiffness": Param("N/m", lower=0.0)}}

    def declare(self, k):
        s, p = k.q.s, k.p
        k.add_particle(p.mass, s * k.tank.x)
        k.add_potential({factor} * p.stiffness * s**2 / 2)
'''


def _sliding_rhs(factor: float) -> float:
    """Acceleration of an exec-defined sliding mass at s = 0.1 m with k = 10 N/m, m = 1 kg,
    the carriage at rest: -factor k s / m."""
    ns: dict = {}
    exec(_SLIDING.format(factor=factor), ns)  # no source file: inspect cannot read it
    model = LateralRig() + ns["SlidingMass"]("s1")
    with pytest.warns(RuntimeWarning, match="without the on-disk cache"):
        dm = derive(model)
    assert not dm.from_cache
    values = dict(zip(dm.parameter_names, [0.0] * len(dm.parameter_names)))
    values |= {"rig.dry_mass": 1.0, "rig.gravity": 9.81, "s1.mass": 1.0, "s1.stiffness": 10.0}
    p = [values[n] for n in dm.parameter_names]
    return float(np.asarray(dm.rhs([0.1, 0.0], [0.0, 0.0, 0.0], p, 0.0))[1, 0])


def test_an_exec_defined_component_is_rederived_after_a_change():
    """The bug: the second derive hit the cache (keyed by the class name) and returned the
    first spring. A class without readable source is never cached."""
    assert _sliding_rhs(1.0) == pytest.approx(-1.0, rel=1e-12)
    assert _sliding_rhs(5.0) == pytest.approx(-5.0, rel=1e-12)


def test_base_class_and_module_helper_are_in_the_key(tmp_path, monkeypatch):
    """Editing a base class or a module-level helper that ``declare`` calls changes the key
    (importlib.reload gives new class objects from the edited files)."""
    import importlib

    (tmp_path / "base_mod.py").write_text(
        "from analogs import Component, Param\n"
        "class Base(Component):\n"
        "    parameters = {'mass': Param('kg', lower=0.0)}\n")
    (tmp_path / "sub_mod.py").write_text(
        "from base_mod import Base\n"
        "def height(p):\n    return 0.1\n"
        "class Sub(Base):\n"
        "    coordinates = ('s',)\n"
        "    coordinate_units = {'s': 'm'}\n"
        "    def declare(self, k):\n"
        "        k.add_particle(k.p.mass, k.q.s * k.tank.x + height(k.p) * k.tank.z)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import base_mod
    import sub_mod

    def key():
        return (LateralRig() + sub_mod.Sub("s1")).structure_key()

    k0 = key()
    (tmp_path / "base_mod.py").write_text((tmp_path / "base_mod.py").read_text()
                                         + "    hinge_angles = ('s',)\n")
    importlib.reload(base_mod)
    importlib.reload(sub_mod)
    k1 = key()
    (tmp_path / "sub_mod.py").write_text(
        (tmp_path / "sub_mod.py").read_text().replace("return 0.1", "return 0.2"))
    importlib.reload(sub_mod)
    k2 = key()
    assert len({k0, k1, k2}) == 3


def test_damaged_cache_entries_are_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    model = _two_pendulum()
    derive(model)
    (entry,) = tmp_path.glob("*.json")
    good = entry.read_bytes()
    args = ([0.1, -0.2, 0.3, 0.4], [0.0, 0.1, -2.0],
            list(range(1, len(derive(model).parameter_names) + 1)), 0.5)
    expected = np.asarray(derive(model, use_cache=False).rhs(*args))
    for damage in (b"", good[: len(good) // 2], good.replace(b"p1.theta", b"p1.thetb")):
        entry.write_bytes(damage)
        with pytest.warns(RuntimeWarning, match="damaged"):
            dm = derive(model)
        assert not dm.from_cache
        assert np.array_equal(np.asarray(dm.rhs(*args)), expected)
        assert derive(model).from_cache  # rewritten whole
    assert tmp_path.stat().st_mode & 0o077 == 0  # created private to the user


def test_a_cache_folder_writable_by_others_is_not_used(tmp_path, monkeypatch):
    """Issue 26: serialized functions are not read from, nor written to, a folder others
    can write; the model is derived in a private temporary folder, with a warning."""
    from derive.cache import UntrustedCache, ensure_private_dir

    folder = tmp_path / "shared"
    folder.mkdir(mode=0o777)
    folder.chmod(0o777)
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(folder))
    with pytest.warns(UntrustedCache, match="shared is writable by group or others"):
        dm = derive(_two_pendulum())
    assert not dm.from_cache and not list(folder.iterdir())
    with pytest.raises(PermissionError, match="writable by group or others"):
        ensure_private_dir(folder)


def test_a_structure_is_kept_in_memory_per_thread_until_its_entry_changes(tmp_path,
                                                                          monkeypatch):
    """A second derive of the same structure in the same thread reuses the loaded functions
    and what was built from them (the memo), with the caller's own model; another thread
    loads its own copy; a cache entry rewritten on disk is read again."""
    import threading

    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    first = derive(_two_pendulum())
    again_model = _two_pendulum()
    again = derive(again_model)
    assert again.rhs is first.rhs and again._memo is first._memo
    assert again.model is again_model and again.from_cache
    other = {}
    thread = threading.Thread(target=lambda: other.setdefault("dm", derive(_two_pendulum())))
    thread.start()
    thread.join()
    assert other["dm"].rhs is not first.rhs and other["dm"]._memo is not first._memo
    (entry,) = tmp_path.glob("*.json")
    st = entry.stat()
    os.utime(entry, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    reread = derive(_two_pendulum())
    assert reread.rhs is not first.rhs and reread.from_cache


def test_maps_are_built_once_per_length_and_the_oldest_lengths_leave(tmp_path, monkeypatch):
    """``DerivedModel.mapped``: the same map object for the same function and length, its
    values those of ``fn.map``; beyond the kept number of lengths the oldest is rebuilt."""
    from derive import derived

    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    dm = derive(_two_pendulum())
    f = dm.rhs
    first = dm.mapped(("rhs",), f, 5)
    assert dm.mapped(("rhs",), f, 5) is first
    args = (np.ones((4, 5)), np.zeros((3, 5)), np.arange(1, len(dm.parameter_names) + 1.0),
            np.zeros((1, 5)))
    assert np.array_equal(np.asarray(first(*args)), np.asarray(f.map(5)(*args)))
    for n in range(6, 6 + derived._MAPS_KEPT):
        dm.mapped(("rhs",), f, n)
    assert sum(1 for k in dm._memo if k[0] == "map") == derived._MAPS_KEPT
    assert dm.mapped(("rhs",), f, 5) is not first
