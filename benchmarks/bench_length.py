"""Benchmark of fit cost against record length (issue 27): rig-rate records from rest.

Run: ``python benchmarks/bench_length.py [--max-samples N]``. Records from the independent
reference simulator (``tests/reference_models.py``): the 8-inch sphere at 60 % fill (the
bundled example's analog), a 1 mm carriage sweep 0.6-1.6 f1 faded in over 1.5 s from rest,
displacement noise 2e-5 m, force noise 1.3 % of its RMS; 3,001 / 10,001 / 30,001 samples at
500 Hz and 120,001 / 600,001 at 1 kHz (2 and 10 minutes). Each record is written once into
``benchmarks/.records/`` (SYNTHETIC data; kept between runs, the reference simulation of the
longest takes minutes) and fitted in a NEW process (`slosh fit`'s default model, estimated
input), so that its peak memory is its own.

Each record is fitted twice: at its full rate, and decimated to 100 Hz by ``[test] decimate``
(500 Hz by 5, 1 kHz by 10: a zero-phase anti-alias low-pass, then every k-th sample;
``estimate/data/decimation.py``). ``--rate full|decimated|both`` picks them (default both).

Printed per row: the record's samples (and those fitted), wall and CPU time of build + fit,
IPOPT iterations, peak resident memory and its growth per recorded sample over the process
after loading the case (KiB), the CPU time per recorded sample as a ratio to the 3,001-sample
row's at the full rate, and every estimate's error against the truth in its standard errors
(z). The SciPy peer on the 3,001-sample records is ``bench_fit.py``'s.
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
RECORDS = Path(__file__).resolve().parent / ".records"
#: (duration s, rate Hz) of the rows.
ROWS = ((6.0, 500.0), (20.0, 500.0), (60.0, 500.0), (120.0, 1000.0), (600.0, 1000.0))
TRUTH = {"fixed.mass": 1.5, "p1.mass": 1.30, "p1.length": 0.0553}

_MAKE = """
import sys
sys.path.insert(0, {root!r}); sys.path.append({tests!r})
from pathlib import Path
from synthetic_cases import sweep_record
from estimate.data.case import Prediction
sweep_record(Path({folder!r}), {name!r}, {duration}, rate={rate}, seed=4,
             prediction=Prediction(1.338, 0.057, 1.456, 0.007))
"""

_FIT = """
import json, resource, sys, time
sys.path.insert(0, {root!r})
from estimate import FitProblem, fit, load_case, model_from_spec
case = load_case({path!r})
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t, c = time.perf_counter(), time.process_time()
res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)), progress=False)
wall, cpu = time.perf_counter() - t, time.process_time() - c
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({{"fitted": int(case.time.size), "wall": wall, "cpu": cpu, "it": res.iterations,
                  "status": res.status, "peak_kib": peak, "base_kib": base,
                  "values": dict(zip(res.names, map(float, res.values))),
                  "stderr": dict(zip(res.names, map(float, res.stderr)))}}))
"""


def record(duration: float, rate: float, env: dict) -> Path:
    """The record's case file, made once (``env``: with the memory budget the writer's
    check of the record needs)."""
    name = f"sweep_{int(duration)}s_{int(rate)}Hz"
    path = RECORDS / f"{name}.toml"
    if not path.exists():
        RECORDS.mkdir(exist_ok=True)
        code = _MAKE.format(root=str(ROOT), tests=str(ROOT / "tests"), folder=str(RECORDS),
                            name=name, duration=duration, rate=rate)
        subprocess.run([sys.executable, "-c", code], check=True, env=env)
    return path


def decimated(path: Path, rate: float) -> Path:
    """A case file beside ``path`` that fits its record decimated to 100 Hz."""
    factor = int(round(rate / 100.0))
    out = path.with_name(f"{path.stem}_d{factor}.toml")
    text = path.read_text()
    assert "[test]\n" in text and "decimate" not in text
    out.write_text(text.replace("[test]\n", f"[test]\ndecimate = {factor}\n", 1))
    return out


def main() -> None:
    from estimate.data.budget import BUDGET_VARIABLE, DEFAULT_BUDGET, FIT_BYTES_PER_SAMPLE

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-samples", type=int, default=700_000,
                    help="skip the rows longer than this many samples")
    ap.add_argument("--rate", choices=("full", "decimated", "both"), default="both",
                    help="fit the records at their full rate, decimated to 100 Hz, or both")
    args = ap.parse_args()
    rows = []
    print("| samples (fitted) | rate | wall s | CPU s | iterations | peak MB | KiB/sample | "
          "CPU/sample vs 3k | z: fixed, p1 mass, p1 length |")
    print("|---|---|---|---|---|---|---|---|---|")
    modes = ("full", "decimated") if args.rate == "both" else (args.rate,)
    base_per = None
    for duration, rate in ROWS:
        if duration * rate + 1 > args.max_samples:
            continue
        # the case reader refuses a record over the memory budget (4 GiB by default:
        # 262,144 samples); the long rows are here to be measured, so the budget is raised
        # to what the reader asks for them (the 600,001-sample row peaks at about 4.9 GB)
        env = dict(os.environ)
        env.setdefault(BUDGET_VARIABLE, str(max(DEFAULT_BUDGET,
                                                int(duration * rate + 1) * FIT_BYTES_PER_SAMPLE)))
        path = record(duration, rate, env)
        for mode in modes:
            case = path if mode == "full" else decimated(path, rate)
            out = subprocess.run([sys.executable, "-c",
                                  _FIT.format(root=str(ROOT), path=str(case))],
                                 check=True, capture_output=True, text=True, env=env).stdout
            r = json.loads(out.strip().splitlines()[-1])
            r["n"] = int(round(duration * rate)) + 1  # the record's samples
            rows.append(r)
            per = r["cpu"] / r["n"]
            base_per = per if base_per is None else base_per  # the first row's
            z = ", ".join(f"{(r['values'][k] - v) / r['stderr'][k]:+.1f}"
                          for k, v in TRUTH.items())
            fitted = f" ({r['fitted']:,})" if r["fitted"] != r["n"] else ""
            print(f"| {r['n']:,}{fitted} | {rate * r['fitted'] / r['n']:.0f} Hz | "
                  f"{r['wall']:.2f} | {r['cpu']:.2f} | {r['it']} | {r['peak_kib'] / 1024:.0f} | "
                  f"{(r['peak_kib'] - r['base_kib']) / r['n']:.1f} | {per / base_per:.2f} | "
                  f"{z} |", flush=True)


if __name__ == "__main__":
    main()
