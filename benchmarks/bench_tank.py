"""Runtime of the exact sphere solver per tank and fill (target < 0.2 s, one thread).

Run: ``python benchmarks/bench_tank.py``
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # oversubscription made such solvers 10x slower here

import statistics
import time

from analogs.tank import Sphere, predict

TARGET = 0.2  # s


def main(repeats: int = 7) -> int:
    tank = Sphere(0.1016)
    predict(tank, fill=0.5)  # warm-up (imports, caches)
    worst = 0.0
    print(f"{'fill':>5} {'solver':>7} {'median [s]':>11} {'min [s]':>9}")
    for fill in (0.1, 0.3, 0.5, 0.6, 0.7, 0.8, 0.9):
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            p = predict(tank, fill=fill)
            times.append(time.perf_counter() - t0)
        med = statistics.median(times)
        worst = max(worst, med)
        print(f"{fill:5.2f} {p.solver:>7} {med:11.4f} {min(times):9.4f}")
    verdict = "meets" if worst < TARGET else "MISSES"
    print(f"worst median {worst:.4f} s per tank and fill: {verdict} the {TARGET} s target")
    return 0 if worst < TARGET else 1


if __name__ == "__main__":
    raise SystemExit(main())
