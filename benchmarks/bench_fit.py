"""Benchmark of the input-aware estimation issue: 5-parameter fits of 3001-sample records.

Run: ``python benchmarks/bench_fit.py``. Three lateral-rig records from the independent
reference simulator (``tests/reference_models.py``), each starting at rest with a 1.5 s
ramp, displacement noise 2e-5 m, force noise 1.3 % plus a 25 Hz tone: a sine at 0.9 f1
(2.5 mm), a sine at 1.15 f1 (2 mm) and a 0.2 mm chirp. For each, in one run:

* the median in-process time of ``fit`` (problem build + solve) with the estimated input
  and with the filtered input, wall and CPU time (the CPU time is the steadier on a shared
  machine; both are single-threaded),
* the seed's approach: SciPy ``least_squares`` on a ``solve_ivp`` single-shooting
  simulation (RK45, rtol 1e-6) of hand-written equations, finite-difference Jacobian,
  Savitzky-Golay derivatives of the displacement and the force low-passed at 10 Hz,

with the errors of the masses against the truth and the ratios of the times. Then the wall
time of ``slosh fit`` on the bundled example (a new process: imports included, warm cache).
"""

import math
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np
from _common import median_times
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares
from scipy.signal import savgol_filter

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
import estimate  # noqa: F401  (the package before tests/ joins the path: editable installs)

sys.path.append(str(ROOT / "tests"))
import reference_models as ref
from synthetic_cases import rig_record

from estimate import FitProblem, fit, model_from_spec
from estimate.data.signals import lowpass
from estimate.fitting.carriage import forget_records
from estimate.fitting.first_stage import forget_stages

NAMES = ("fixed.mass", "p1.mass", "p1.length", "p1.damping", "p1.stiffness")
RECORDS = {
    "sine 0.9 f1, 2.5 mm": (lambda f1: ref.Sine(0.0025, 0.9 * f1), dict(seed=2)),
    "sine 1.15 f1, 2 mm": (lambda f1: ref.Sine(0.002, 1.15 * f1), dict(seed=3, ramp=2.0)),
    "chirp 1-5 Hz, 0.2 mm": (lambda f1: ref.LinearSweep(0.0002, 1.0, 5.0, 30.0),
                             dict(seed=5, ramp=1.0)),
}


def ours(case, mode, spec="fixed,p1"):
    forget_records()  # time a first fit of the record: no spline or noise analysis kept
    forget_stages()
    problem = FitProblem.build(case, model_from_spec(spec, case), input=mode)
    return fit(problem, progress=False)


def scipy_fit(case, start, bounds):
    """The seed's lsqnonlin approach: single shooting, finite-difference Jacobian."""
    t = case.time
    dt = float(np.median(np.diff(t)))
    g, m_dry = case.rig.gravity, case.rig.dry_mass
    # a 0.51 s, 4th-order Savitzky-Golay second derivative: smooth enough for solve_ivp
    xdd = savgol_filter(case.displacement, 51, 4, deriv=2, delta=dt)
    acc = CubicSpline(t, xdd)
    F = lowpass(t, case.force, cutoff_hz=10.0)
    sims = [0]

    def residual(theta):
        mf, m, L, c, k = theta
        sims[0] += 1

        def rhs(tt, y):
            a = acc(tt)
            th, thd = y
            torque = m * L * a * math.cos(th) + m * g * L * math.sin(th) + k * th + c * thd
            return [thd, -torque / (m * L**2)]

        sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-6, atol=1e-9)
        th, thd = sol.y
        thdd = -(m * L * xdd * np.cos(th) + m * g * L * np.sin(th) + k * th + c * thd) / (m * L**2)
        force = (m_dry + mf) * xdd + m * (xdd + L * thdd * np.cos(th) - L * thd**2 * np.sin(th))
        return force - F

    lo = [b[0] for b in bounds]
    hi = [b[1] for b in bounds]
    x0 = np.clip(start, np.array(lo) + 1e-12, hi)
    res = least_squares(residual, x0, bounds=(lo, hi), x_scale=np.maximum(np.abs(x0), 1e-3))
    return res, sims[0]


def errors(values, truth):
    return "  ".join(f"{n.split('.')[0]} {100 * (values[n] / truth[n] - 1):+.2f} %"
                     for n in ("fixed.mass", "p1.mass"))


def main() -> None:
    folder = Path(tempfile.mkdtemp())
    print("5-parameter fits (fixed,p1) of 3001-sample records from rest (reference simulator):")
    ratios = {(mode, clock): [] for mode in ("estimated", "filtered") for clock in ("wall", "cpu")}
    for k, (label, (drive, opts)) in enumerate(RECORDS.items()):
        case, _, truth = rig_record(folder, f"r{k}", drive, **opts)
        times, results = {}, {}
        for mode in ("estimated", "filtered"):
            results[mode] = ours(case, mode)
            times[mode] = median_times(lambda c=case, m=mode: ours(c, m), repeat=5, warmup=1)
        est = {e.name: e for e in results["filtered"].problem.estimated}
        start = np.array([est[n].initial for n in NAMES])
        bounds = [(est[n].lower, est[n].upper) for n in NAMES]
        t0, c0 = time.perf_counter(), time.process_time()
        sres, nsim = scipy_fit(case, start, bounds)
        peer = (time.perf_counter() - t0, time.process_time() - c0)
        print(f"  {label}:")
        for mode in ("estimated", "filtered"):
            r, (wall, cpu) = results[mode], times[mode]
            ratios[mode, "wall"].append(peer[0] / wall)
            ratios[mode, "cpu"].append(peer[1] / cpu)
            print(f"    {mode:9s} input : median wall {wall:6.3f} s, CPU {cpu:6.3f} s "
                  f"({r.iterations} iterations)  {errors(dict(zip(r.names, r.values)), truth)}   "
                  f"SciPy / this: wall {peer[0] / wall:5.1f}x, CPU {peer[1] / cpu:5.1f}x")
        print(f"    SciPy peer      : single run wall {peer[0]:6.3f} s, CPU {peer[1]:6.3f} s "
              f"({nsim} simulations)  {errors(dict(zip(NAMES, sres.x)), truth)}")
    for (mode, clock), r in ratios.items():
        print(f"  median speed-up over the SciPy peer, {mode} input, {clock} time: "
              f"{np.median(r):.1f}x")
    transport(folder)
    slosh = shutil.which("slosh")
    cmd = ([slosh] if slosh else [sys.executable, "-c", "import sys; from estimate.cli import main; "
                                  "sys.exit(main())"]) + ["fit", str(ROOT / "examples" / "A1.toml")]
    subprocess.run(cmd, capture_output=True, check=True)  # warm the cache
    walls = []
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run(cmd, capture_output=True, check=True)
        walls.append(time.perf_counter() - t0)
    print(f"slosh fit examples/A1.toml (new process, imports included): median wall "
          f"{float(np.median(walls)):.2f} s")


def transport(folder: Path) -> None:
    """Issue 25's speed target: a 13.6 s, 500 Hz transport record (6,801 samples: 1 s at
    rest, a 0.4 m move in 0.8 s, 11.8 s of decay; six-axis sensor, 18 ms stream lag, the
    container not weighed) fits in under 2 s (build, first stage and solve)."""
    import transport_cases as tc

    print("Transport records, 13.6 s at 500 Hz, fixed,p1:nospring, container and lag estimated:")
    for tank in (tc.small_cylinder(), tc.sphere_8in()):
        for planned in (False, True):
            rec = tc.transport_record(folder, tank, planned=planned, decay=11.8, seed=3)
            r = ours(rec.case, "estimated", "fixed,p1:nospring")
            wall, cpu = median_times(lambda c=rec.case: ours(c, "estimated", "fixed,p1:nospring"),
                                     repeat=3, warmup=0)
            truth = rec.truth
            lag = next(n for n in r.names if n.endswith("rig.lag"))
            print(f"  {tank.name:14s} {'planned ' if planned else 'measured'}: {r.n_samples} "
                  f"samples, median wall {wall:6.3f} s, CPU {cpu:6.3f} s ({r.iterations} "
                  f"iterations, {r.verdict.split(' (')[0]})  p1.mass "
                  f"{100 * (r.value('p1.mass') / truth['p1.mass'] - 1):+.2f} %, container "
                  f"{100 * (r.value('rig.dry_mass') / truth['rig.dry_mass'] - 1):+.2f} %, lag "
                  f"{1e3 * (r.value(lag) - truth['lag']):+.2f} ms")


if __name__ == "__main__":
    main()
