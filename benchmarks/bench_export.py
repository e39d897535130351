"""Benchmark of issue 6: exported C and Monte Carlo.

(a) 30 s at 100 Hz of the two-pendulum lateral model in the exported, compiled C: median
    time of the integration loop (RK4 step + outputs per sample; inputs precomputed), timed
    inside a small C harness, and the ratio against ``simulate`` (CasADi virtual machine,
    and ``RK4(compiled=True)``) on the same grid.
(b) Monte Carlo of a 30 s case (examples/A1, 3001 samples) in-process and on an embedded
    two-worker Dask ``LocalCluster``: wall time and draws per second.

Run: ``python benchmarks/bench_export.py [--draws 10000] [--skip-dask]`` (threads pinned to 1).
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np
from _common import median_time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import RK4, Sine, derive, simulate
from derive.export_c import CFLAGS, export_c

PARAMS = {"rig.dry_mass": 1.2, "fixed.mass": 1.456, "p1.mass": 1.338, "p1.length": 0.057,
          "p1.stiffness": 0.01, "p1.damping": 2e-4, "p2.mass": 0.048, "p2.length": 0.018,
          "p2.stiffness": 0.0, "p2.damping": 1e-5}

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "slosh_model.h"

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    const int n = argc > 1 ? atoi(argv[1]) : 3000, repeat = argc > 2 ? atoi(argv[2]) : 200;
    const double h = 0.01, w = 2.0 * 3.141592653589793 * 1.855, A = 0.005;
    double *U = malloc(sizeof(double) * (size_t)n * SLOSH_MODEL_NU * SLOSH_MODEL_NSTAGES);
    double *times = malloc(sizeof(double) * (size_t)repeat), x[SLOSH_MODEL_NX], y[SLOSH_MODEL_NY];
    double u[SLOSH_MODEL_NU], sink = 0.0;
    int k, j, r, i;
    for (k = 0; k < n; ++k)
        for (j = 0; j < SLOSH_MODEL_NSTAGES; ++j) {
            double t = h * (k + j / (double)(SLOSH_MODEL_NSTAGES - 1));
            double *Uk = U + ((size_t)k * SLOSH_MODEL_NSTAGES + j) * SLOSH_MODEL_NU;
            Uk[0] = A * sin(w * t); Uk[1] = A * w * cos(w * t); Uk[2] = -A * w * w * sin(w * t);
        }
    for (r = 0; r < repeat; ++r) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (i = 0; i < SLOSH_MODEL_NX; ++i) x[i] = 0.0;
        for (k = 0; k < n; ++k) {
            slosh_model_step_stages(x, U + (size_t)k * SLOSH_MODEL_NSTAGES * SLOSH_MODEL_NU,
                                    slosh_model_default_parameters, h * k, h);
            for (i = 0; i < SLOSH_MODEL_NU; ++i)
                u[i] = U[((size_t)k * SLOSH_MODEL_NSTAGES + SLOSH_MODEL_NSTAGES - 1) * SLOSH_MODEL_NU + i];
            slosh_model_outputs(x, u, slosh_model_default_parameters, h * (k + 1), y);
            sink += y[0];
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        times[r] = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
    }
    qsort(times, (size_t)repeat, sizeof(double), cmp);
    printf("%.9g %.17g %.17g\n", times[repeat / 2], x[0], sink);
    free(U);
    free(times);
    return 0;
}
"""


def bench_c() -> dict:
    model = (LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
             + Pendulum("p2") + HingeSpring("p2") + HingeDamper("p2"))
    dm = derive(model)
    t = np.linspace(0, 30, 3001)
    exc = Sine(0.005, 1.855)
    with tempfile.TemporaryDirectory() as tmp:
        ex = export_c(dm, tmp, PARAMS)
        harness = Path(tmp) / "bench.c"
        harness.write_text(HARNESS)
        exe = Path(tmp) / "bench"
        subprocess.run(["cc", *CFLAGS, "-o", str(exe), str(harness), *map(str, ex.sources), "-lm"],
                       check=True, cwd=tmp)
        out = subprocess.run([str(exe), "3000", "200"], capture_output=True, text=True, check=True)
        c_median, x_end, _ = map(float, out.stdout.split())
    sim = simulate(dm, PARAMS, t, exc, integrator=RK4())
    assert abs(sim.states[-1, 0] - x_end) <= 1e-9 * max(1.0, abs(x_end)), "C and simulate disagree"
    vm = median_time(lambda: simulate(dm, PARAMS, t, exc, integrator=RK4()), repeat=10)
    simulate(dm, PARAMS, t, exc, integrator=RK4(compiled=True))
    comp = median_time(lambda: simulate(dm, PARAMS, t, exc, integrator=RK4(compiled=True)), repeat=10)
    return {"c_loop_median_s": c_median, "simulate_vm_median_s": vm,
            "simulate_compiled_median_s": comp, "ratio_vm_over_c": vm / c_median,
            "ratio_compiled_over_c": comp / c_median}


def bench_montecarlo(draws: int, dask: bool) -> dict:
    from estimate.analysis.montecarlo import Fit, monte_carlo
    from estimate.data import load_case
    from estimate.data.experiment import experiment
    from estimate.data.models import model_from_spec
    from estimate.executor import DaskExecutor, LocalExecutor

    case = load_case(ROOT / "examples" / "A1.toml")
    exp = experiment(case, model_from_spec("fixed,p1", case))
    names = ("fixed.mass", "p1.mass", "p1.length", "p1.damping")
    values = json.loads((ROOT / "examples" / "A1_params.json").read_text())
    sd = np.array([0.01, 0.01, 5e-4, 5e-5])
    fit = Fit(path=None, model_spec="fixed,p1", case=str(case.path), values=values,
              units={}, lower={n: 1e-9 for n in names}, upper={n: np.inf for n in names},
              estimated=names, covariance_names=names, covariance=np.diag(sd**2))

    def run(ex, n):
        return monte_carlo(exp.derived, case.time, exp.excitation, fit, n, fixed=exp.fixed,
                           seed=0, executor=ex)

    run(LocalExecutor(), 256)  # compile once (disk cache)
    out = {}
    res = run(LocalExecutor(), draws)
    out["local"] = {"draws": draws, "seconds": res.seconds, "draws_per_s": res.draws_per_second}
    if dask:
        t0 = time.perf_counter()
        with DaskExecutor(n_workers=2) as ex:
            start = time.perf_counter() - t0
            res = run(ex, draws)
        out["dask_2_workers"] = {"draws": draws, "seconds": res.seconds,
                                 "draws_per_s": res.draws_per_second,
                                 "cluster_start_s": start}
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=10_000)
    ap.add_argument("--skip-dask", action="store_true")
    args = ap.parse_args()
    c = bench_c()
    print(f"(a) 30 s at 100 Hz, two pendulums: compiled C loop median {1e3 * c['c_loop_median_s']:.3f} ms "
          f"(target < 1 ms); simulate RK4 (CasADi VM) {1e3 * c['simulate_vm_median_s']:.2f} ms "
          f"= {c['ratio_vm_over_c']:.0f}x; RK4(compiled=True) {1e3 * c['simulate_compiled_median_s']:.2f} ms "
          f"= {c['ratio_compiled_over_c']:.1f}x")
    mc = bench_montecarlo(args.draws, not args.skip_dask)
    for k, v in mc.items():
        extra = f", cluster start {v['cluster_start_s']:.1f} s" if "cluster_start_s" in v else ""
        print(f"(b) Monte Carlo {v['draws']} draws of a 30 s case, {k}: {v['seconds']:.2f} s, "
              f"{v['draws_per_s']:.0f} draws/s (10^5 draws ~ {1e5 / v['draws_per_s']:.0f} s){extra}")


if __name__ == "__main__":
    main()
