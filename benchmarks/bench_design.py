"""Benchmark of the design issue (``slosh design``, issue 31): a design must finish in
under 30 s.

Run: ``python benchmarks/bench_design.py``. The first record is the acceptance test's: a
30 s lateral-rig record from the independent reference simulator (``tests/reference_models.py``)
of a 4 mm sine at 0.4 f1 from rest, with force noise 1.3 % plus a 25 Hz tone and
displacement noise 2e-5 m, fitted with ``fixed,p1``; the rig's limits are 100 mm, 0.3 m/s,
2 m/s^2 and 30 s. Printed, from one run:

* the in-process time of ``design`` (all four lateral families, three finalists and two
  standard alternatives judged by the fit's linearisation), wall and CPU, median of 3
  after a first run that compiles the sensitivity functions (kept on disk),
* the wall time of ``slosh design`` in a new process (imports included, warm cache),
* the number of drives simulated and the ratio of the wall time to the 30 s budget.
"""

import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
from _common import median_times

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
import estimate  # noqa: F401,E402  (the package before tests/ joins the path)

sys.path.append(str(ROOT / "tests"))
sys.path.append(str(ROOT / "tests" / "estimate" / "design"))
import numpy as np  # noqa: E402
import reference_models as ref  # noqa: E402
from design_helpers import G, fit_json, lateral_record, truth_pendulum  # noqa: E402

from estimate import load_case  # noqa: E402
from estimate.design import DesignProblem, design  # noqa: E402

BUDGET = 30.0


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="bench_design_"))
    try:
        truth = truth_pendulum()
        f1 = ref.natural_frequency(truth, G) / (2 * np.pi)
        first, _ = lateral_record(folder, "A", ref.Ramped(ref.Sine(0.004, 0.4 * f1), 1.5),
                                  truth=truth, seed=1)
        fit_path, _ = fit_json(folder, "A_fit", [first])
        case = load_case(first.path)
        problem = DesignProblem.build(fit_path, case, targets=["p1.mass", "fixed.mass"])
        runs = []

        def once():
            runs.append(design(problem))

        wall, cpu = median_times(once, repeat=3, warmup=1)
        last = runs[-1]
        t0 = time.perf_counter()
        slosh = shutil.which("slosh")
        cmd = ([slosh] if slosh else [sys.executable, "-c", "import sys; from estimate.cli "
                                      "import main; sys.exit(main(sys.argv[1:]))"])
        subprocess.run(cmd + ["design", str(fit_path), str(first.path), "--target",
                              "p1.mass,fixed.mass", "--json", str(folder / "d.json")],
                       check=True, capture_output=True, cwd=ROOT)
        cli = time.perf_counter() - t0
        d = json.loads((folder / "d.json").read_text())
        print("| design | wall [s] | CPU [s] | drives simulated | wall / 30 s |")
        print("|---|---|---|---|---|")
        print(f"| in-process, lateral 30 s record, 4 families | {wall:.1f} | {cpu:.1f} | "
              f"{last.search.evaluations} | {wall / BUDGET:.2f} |")
        print(f"| `slosh design` (new process) | {cli:.1f} | - | {d['evaluations']} | "
              f"{cli / BUDGET:.2f} |")
        print("recommended:", d["recommended"]["description"], "; ", "; ".join(d["gain"]))
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
