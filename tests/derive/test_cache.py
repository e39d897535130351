"""Derivation happens once: later derives, also in new processes, load from disk."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

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
