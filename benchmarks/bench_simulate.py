"""Benchmark of issue 2: derivation, cache load and simulation of the two-pendulum lateral model.

Run: ``python benchmarks/bench_simulate.py``. Prints medians and the ratio against SciPy
``solve_ivp`` of hand-written equations, measured in the same run.
"""

import math
import subprocess
import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np
from _common import median_time
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from derive import RK4, Sine, derive, simulate

G = 9.80665
PEND = [(1.338, 0.057, 0.01, 2e-4), (0.048, 0.018, 0.0, 1e-5)]
PARAMS = {"rig.dry_mass": 1.2, "fixed.mass": 1.456}
for j, (m, L, k, c) in enumerate(PEND, start=1):
    PARAMS |= {f"p{j}.mass": m, f"p{j}.length": L, f"p{j}.stiffness": k, f"p{j}.damping": c}
DECL = ("LateralRig() + FixedMass('fixed') + Pendulum('p1') + HingeSpring('p1') + HingeDamper('p1')"
        " + Pendulum('p2') + HingeSpring('p2') + HingeDamper('p2')")


def _model():
    return eval(DECL)


def _derive_in_new_process(cache: str) -> float:
    code = ("import time; t0 = time.perf_counter()\n"
            "from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum\n"
            "from derive import derive\n"
            f"derive({DECL})\n"
            "print(time.perf_counter() - t0)")
    env = {"SLOSH_CACHE_DIR": cache, "PATH": "", "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def _scipy_reference(t, A, f):
    w = 2 * math.pi * f

    def rhs(tt, y):
        a = -A * w * w * math.sin(w * tt)
        out = []
        for j, (m, L, k, c) in enumerate(PEND):
            th, thd = y[2 * j], y[2 * j + 1]
            torque = m * L * a * math.cos(th) + m * G * L * math.sin(th) + k * th + c * thd
            out += [thd, -torque / (m * L**2)]
        return out

    return solve_ivp(rhs, (t[0], t[-1]), np.zeros(4), method="DOP853", t_eval=t, rtol=1e-8, atol=1e-10)


def main() -> None:
    with tempfile.TemporaryDirectory() as cache:
        cold = [_derive_in_new_process(tempfile.mkdtemp(dir=cache)) for _ in range(3)]
        _derive_in_new_process(cache)
        warm = [_derive_in_new_process(cache) for _ in range(5)]
    print(f"derive, cold (new process, empty cache, incl. imports): median {np.median(cold) * 1e3:8.1f} ms")
    print(f"derive, cache load (new process, incl. imports):        median {np.median(warm) * 1e3:8.1f} ms")

    dm = derive(_model())
    t = np.linspace(0.0, 30.0, 3001)
    exc = Sine(0.005, 1.855)
    rows = []
    for label, integ, outs in [
        ("RK4, CasADi VM, force only", RK4(), ("force_x",)),
        ("RK4, CasADi VM, all outputs", RK4(), None),
        ("RK4, compiled, force only", RK4(compiled=True), ("force_x",)),
        ("RK4, compiled, all outputs", RK4(compiled=True), None),
    ]:
        def run(integ=integ, outs=outs):
            return simulate(dm, PARAMS, t, exc, integrator=integ, outputs=outs)

        rows.append((label, median_time(run)))
    ref = median_time(lambda: _scipy_reference(t, 0.005, 1.855), repeat=5, warmup=1)
    print("simulate 30 s at 100 Hz (3001 samples), two pendulums + fixed mass, 5 mm sine at 1.855 Hz:")
    for label, sec in rows:
        print(f"  {label:32s} median {sec * 1e3:8.3f} ms   speed-up vs solve_ivp {ref / sec:7.1f}x")
    print(f"  {'scipy solve_ivp DOP853 (rtol 1e-8)':32s} median {ref * 1e3:8.3f} ms")


if __name__ == "__main__":
    main()
