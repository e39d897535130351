"""Benchmark of issue 5: ``diagnose`` on 30 s, 3001-sample cases.

Run: ``python benchmarks/bench_diagnose.py``. Prints the median wall time and the number
of fits for a clean case (the bundled example A1) and for a case hiding a second slosh
mode under a 1-5 Hz sweep (synthetic, from the tests' reference simulator).
"""

import math
import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import reference_models as ref
from synthetic_cases import G, make_case, pendulum

from estimate import diagnose, load_case


def main(repeat: int = 3) -> None:
    folder = Path(tempfile.mkdtemp())
    mode, _ = make_case(folder, "mode", ref.LinearSweep(0.003, 1.0, 5.0, 30.0),
                        pendulums=[pendulum(1.30, 0.0553, 0.01),
                                   pendulum(0.06, G / (2 * math.pi * 3.8) ** 2, 0.01)],
                        fixed_mass=1.45, seed=11)
    for label, case in (("A1 (clean, bundled example)", load_case(ROOT / "examples" / "A1.toml")),
                        ("second slosh mode under a sweep", mode)):
        times, fits, found = [], [], []
        for _ in range(repeat):
            d = diagnose(case)
            times.append(d.seconds)
            fits.append(d.candidate_fits)
            found.append(",".join(f.cause for f in d.findings) or "none")
        print(f"{label:34s} median {np.median(times):6.1f} s  (target < 20 s)  fits {int(np.median(fits))}  "
              f"findings: {found[0]}")


if __name__ == "__main__":
    main()
