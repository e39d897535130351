"""Benchmark of the open-ended diagnosis (issue 14): ``diagnose`` on 30 s, 3001-sample
records of each kind.

Run: ``python benchmarks/bench_diagnose.py [REPEAT]`` (default 3). Prints, per record, the
median wall time (target < 20 s), the median number of candidate fits and what was named.
The records are the synthetic ones of ``tests/estimate/diagnosis/test_open_diagnosis.py``
(independent reference simulator; start from rest with a ramp, force and displacement
noise, a motor tone) and the bundled example A1 (synthetic, clean).
"""

import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from estimate import diagnose, load_case  # noqa: E402  (before tests/ goes on the path)

sys.path.insert(1, str(ROOT / "tests"))
sys.path.insert(1, str(ROOT / "tests" / "estimate" / "diagnosis"))

import test_open_diagnosis as records  # noqa: E402

KINDS = {
    "clean control (steps)": "ctrl_steps",
    "offset + drift + pink noise": "ctrl_offset",
    "full-size tank (4x radius)": "ctrl_full_size",
    "hinge dry friction": "friction_a",
    "hardening hinge (diaphragm)": "cubic_b",
    "second mode + sensor delay": "mode_delay",
    "outside: asymmetric hinge": "outside_asymmetric",
    "outside: transducer saturation": "outside_saturation",
}


def main(repeat: int = 3) -> None:
    folder = Path(tempfile.mkdtemp())
    cases = {"A1 (bundled example, clean)": load_case(ROOT / "examples" / "A1.toml")}
    for label, name in KINDS.items():
        cases[label] = records.build(name, folder)[0]
    print(f"{'record':32s} {'median':>8s} {'fits':>5s}  named (verdict)")
    for label, case in cases.items():
        times, fits = [], []
        for _ in range(repeat):
            d = diagnose(case)
            times.append(d.seconds)
            fits.append(d.candidate_fits)
        named = ",".join(f.cause for f in d.findings) or "none"
        verdict = "unexplained" if d.unexplained else "explained"
        print(f"{label:32s} {np.median(times):7.1f}s {int(np.median(fits)):5d}  {named} ({verdict})",
              flush=True)
    print("target: median < 20 s per record (issue 14)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
