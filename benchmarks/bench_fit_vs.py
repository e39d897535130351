"""bench_fit's estimated-input fits of this checkout against another one, pair by pair.

Run: ``python benchmarks/bench_fit_vs.py OTHER_CHECKOUT [--pairs 20]``. On a shared machine
two benchmark runs made minutes apart differ by more than the changes they are meant to
compare (the same code's fit took 0.83 s in one run and 1.17 s ten minutes later). Here
each checkout runs in its own long-lived process that fits bench_fit's records
(``RECORDS``: SYNTHETIC, from the independent reference simulator) on request; the two
are asked in turn, alternating which goes first, so every pair of fits meets the same
load. Printed per record: the median and smallest CPU time of each checkout and the
median of the pairwise ratios (this / other), the figure to compare with a target such
as "within 10 %", with its distribution-free 95 % interval (order statistics of the pair
ratios: the median lies between them with 95 % probability whatever the load's
distribution, pairs taken as independent).
"""

import argparse
import statistics
import subprocess
import sys
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)

ROOT = Path(__file__).resolve().parents[1]

_WORKER = r"""
import sys, tempfile, time
from pathlib import Path
root, label = Path(sys.argv[1]), sys.argv[2]
sys.path.insert(0, str(root)); sys.path.insert(0, str(root / "benchmarks"))
import _common  # noqa: F401
import estimate  # noqa: F401  (this checkout's package before tests/ joins the path)
sys.path.append(str(root / "tests"))
import bench_fit
from synthetic_cases import rig_record
drive, opts = bench_fit.RECORDS[label]
case, _, _ = rig_record(Path(tempfile.mkdtemp()), "r", drive, **opts)
bench_fit.ours(case, "estimated")  # derivations and compiled code cached
print("ready", flush=True)
for _ in sys.stdin:
    c = time.process_time()
    bench_fit.ours(case, "estimated")
    print(time.process_time() - c, flush=True)
"""


def compare(label: str, other: Path, pairs: int) -> str:
    """One record's line: CPU times of this checkout and ``other``, fitted in turn."""
    procs = [subprocess.Popen([sys.executable, "-c", _WORKER, str(root), label],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
             for root in (ROOT, other)]
    try:
        for p in procs:
            if p.stdout.readline().strip() != "ready":
                raise RuntimeError(f"the worker of {label!r} did not start (see its stderr)")
        times: tuple[list, list] = ([], [])
        for k in range(pairs):
            for j in ((0, 1) if k % 2 == 0 else (1, 0)):
                procs[j].stdin.write("go\n")
                procs[j].stdin.flush()
                times[j].append(float(procs[j].stdout.readline()))
    finally:
        for p in procs:
            p.stdin.close()
            p.wait()
    ours, theirs = times
    ratios = sorted(a / b for a, b in zip(ours, theirs))
    lo, hi = median_interval(ratios)
    return (f"  {label:22s} this: median {statistics.median(ours):.3f} s, min {min(ours):.3f} s"
            f" | other: median {statistics.median(theirs):.3f} s, min {min(theirs):.3f} s"
            f" | this/other, median of {pairs} pairs: {statistics.median(ratios):.3f}"
            f" (95 % interval {lo:.3f}-{hi:.3f})")


def median_interval(values, level: float = 0.95) -> tuple[float, float]:
    """A distribution-free interval of the median of ``values`` (sorted): the order
    statistics ``k`` and ``n - 1 - k`` with ``k`` the largest for which a Binomial(n, 1/2)
    count falls below ``k`` or above ``n - 1 - k`` with probability at most ``1 - level``
    (the whole range when ``n`` is too small for that)."""
    from scipy.stats import binom

    n = len(values)
    k = int(binom.ppf((1 - level) / 2, n, 0.5))
    k = k - 1 if binom.cdf(k, n, 0.5) > (1 - level) / 2 else k
    k = max(k, 0)
    return values[k], values[n - 1 - k]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("other", type=Path, help="the other checkout (a git worktree)")
    ap.add_argument("--pairs", type=int, default=20, help="fits per checkout and record")
    args = ap.parse_args()
    other = args.other.resolve()
    if not (other / "benchmarks" / "bench_fit.py").is_file():
        raise SystemExit(f"{other}: no benchmarks/bench_fit.py (expected a checkout of this "
                         f"project)")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_fit import RECORDS

    print(f"CPU time of bench_fit's estimated-input fits, this checkout vs {other}:")
    for label in RECORDS:
        print(compare(label, other, args.pairs), flush=True)


if __name__ == "__main__":
    main()
