"""Benchmark of issue 17: the bundled 12-record SYNTHETIC campaign (``examples/campaign``).

Run: ``python benchmarks/bench_campaign.py``. Every figure is the wall time of a fresh
command, as a user runs it (process start, imports and the derivation cache included):

* ``slosh campaign`` with 1 and 2 local threads and on a 2-worker Dask ``LocalCluster``
  (cluster start included), 15 tasks: 12 record fits and 3 group fits;
* the 12 records fitted one ``slosh fit`` command each, as before the campaign command;
* the per-record overhead: what a command adds to the fit itself (the fit's own time is the
  task's time kept in the campaign store).
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "examples" / "campaign"
MODEL = "fixed,p1:nospring"          # the bundled campaign.toml's model
CLI = "import sys; from estimate.cli import main; sys.exit(main(sys.argv[1:]))"


def _run(*args: str) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", CLI, *args], cwd=ROOT, capture_output=True,
                          text=True, env=os.environ)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{args}: {proc.stderr[-2000:]}")
    return seconds


def _task_seconds(out: Path) -> dict[str, float]:
    """Seconds of each stored task, by the record or group it fitted."""
    tasks = {}
    for path in (out / "store").glob("*.json"):
        entry = json.loads(path.read_text())
        cases = entry["outcome"]["cases"]
        tasks[cases[0] if len(cases) == 1 else "+".join(cases)] = entry["seconds"]
    return tasks


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    records = sorted(p.stem for p in BUNDLED.glob("F*.toml"))
    print(f"{len(records)} records; load average {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores")
    _run("tank", "--shape", "sphere", "--radius", "0.1016", "--fill", "0.6")   # warm caches

    walls = {}
    for label, extra in (("1 local thread", ["--threads", "1"]),
                         ("2 local threads", ["--threads", "2"]),
                         ("2 Dask workers (LocalCluster)", ["--cluster", "2"])):
        out = tmp / label.replace(" ", "_")
        walls[label] = _run("campaign", str(BUNDLED), "--out", str(out), *extra)
        tasks = _task_seconds(out)
        print(f"slosh campaign, {label:30s} {walls[label]:6.1f} s wall  "
              f"({len(tasks)} tasks, {sum(tasks.values()):6.1f} s of fits)")
    one = _task_seconds(tmp / "1_local_thread")
    fits = {r: _run("fit", str(BUNDLED / f"{r}.toml"), "--model", MODEL,
                    "--json", str(tmp / f"{r}.json")) for r in records}
    total = sum(fits.values())
    print(f"12 x slosh fit, one command each      {total:6.1f} s wall  "
          f"(median {statistics.median(fits.values()):.1f} s per record)")
    fit_overhead = statistics.median(fits[r] - one[r] for r in records)
    record_fits = sum(one[r] for r in records)
    group_fits = sum(s for k, s in one.items() if "+" in k)
    campaign_overhead = (walls["1 local thread"] - record_fits - group_fits) / len(records)
    print(f"per-record overhead over the fit itself: slosh fit {fit_overhead:.2f} s (median), "
          f"slosh campaign {campaign_overhead:.2f} s (1 thread; group fits "
          f"{group_fits:.1f} s not counted)")
    base = walls["1 local thread"]
    print("speed-up over 1 thread: " + ", ".join(f"{k} {base / v:.2f}x" for k, v in walls.items()
                                                if k != "1 local thread"))


if __name__ == "__main__":
    main()
