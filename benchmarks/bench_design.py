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
* the number of drives simulated and the ratio of the wall time to the 30 s budget,
* the same for the spinning rig (``tests/estimate/design/test_design_spinning.py``'s first
  record: 6 rad/s, coning at -0.2 Hz, six channels, nine parameters; limits 8 rad/s, 1 Hz,
  0.08 rad, 30 s), one timed run after a first one.
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


def _spinning(folder: Path) -> DesignProblem:
    import reference_spinning as rs
    from design_helpers import with_limits
    from synthetic_cases import make_spinning_case

    from estimate.data.case import Limits

    rig = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.03,
                 nutation_frequency=-0.2, dry_mass=2.0, spin_up=12.0, nutation_ramp=5.0)
    case, _ = make_spinning_case(folder, "S", rig,
                                 pendulum=rs.SphericalPendulum(1.25, 0.062, 0.035, damping=5e-4),
                                 fixed_mass=1.5, fixed_height=0.05, seed=11, tank_radius=0.1016,
                                 duration=30.0, noise=0.015)
    case = with_limits(case.path, Limits(spin_rate=8.0, nutation_frequency=1.0, cone_angle=0.08,
                                         duration=30.0))
    fit_path, _ = fit_json(folder, "S_fit", [case])
    return DesignProblem.build(fit_path, case, targets=["fixed.mass", "p1.mass"])


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
        spin_problem = _spinning(folder)
        spins = []
        swall, scpu = median_times(lambda: spins.append(design(spin_problem)), repeat=1,
                                   warmup=1)
        spin = spins[-1]
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
        print(f"| in-process, spinning rig, 30 s record | {swall:.1f} | {scpu:.1f} | "
              f"{spin.search.evaluations} | {swall / BUDGET:.2f} |")
        print("lateral:", d["recommended"]["description"], "; ", "; ".join(d["gain"]))
        print("spinning:", spin.recommended.drive.describe(), "; ", "; ".join(spin.gains()))
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
