"""Shared helpers of the benchmarks: thread pinning and robust timing."""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import statistics
import time


def median_time(fn, *, repeat: int = 20, warmup: int = 2) -> float:
    """Median wall time of ``fn()`` in seconds over ``repeat`` runs after ``warmup``."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def median_times(fn, *, repeat: int = 5, warmup: int = 1) -> tuple[float, float]:
    """Median wall and CPU (process) time of ``fn()`` in seconds. On a shared machine the
    CPU time of single-threaded code is the steadier of the two: other jobs lengthen the
    wall time of a run, hardly its CPU time."""
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)
