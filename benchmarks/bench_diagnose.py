"""Benchmark of the open-ended diagnosis (issue 14): ``diagnose`` on 30 s, 3001-sample
records of each kind.

Run: ``python benchmarks/bench_diagnose.py [REPEAT [RECORD ...]]`` (default 3, every record;
RECORD: a record name such as ``steps_spring80``). Prints, per record, the median wall time
(target < 20 s), the median CPU time, the median number of fits and what was named.
The records are the synthetic ones of ``tests/estimate/diagnosis/test_open_diagnosis.py``
and ``tests/reference_diagnosis_records.py`` (independent reference simulator; start from
rest with a ramp, force and displacement noise, a motor tone) and the bundled example A1
(synthetic, clean). ``diaphragm spring, steps (80 %)`` is the record of issue 24 that ran
over 20 minutes (1.9 GB) before the diagnosis's fits had budgets and the first mode
stability bounds; ``2nd mode in a 0.2 mm chirp (80 %)`` the recall regression of issue 24.
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

import reference_diagnosis_records as recall  # noqa: E402
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
#: Records of tests/reference_diagnosis_records.py.
RECALL = {
    "diaphragm spring, steps (80 %)": "steps_spring80",
    "2nd mode in a 0.2 mm chirp (80 %)": "chirp_mode2",
}


def main(repeat: int = 3, only: tuple[str, ...] = ()) -> None:
    import time

    folder = Path(tempfile.mkdtemp())
    cases = {}
    if not only or "A1" in only:
        cases["A1 (bundled example, clean)"] = load_case(ROOT / "examples" / "A1.toml")
    for label, name in KINDS.items():
        if not only or name in only:
            cases[label] = records.build(name, folder)[0]
    for label, name in RECALL.items():
        if not only or name in only:
            cases[label] = recall.build(name, folder)[0]
    print(f"{'record':34s} {'median':>8s} {'CPU':>7s} {'fits':>5s}  named (verdict)")
    for label, case in cases.items():
        times, cpu, fits = [], [], []
        for _ in range(repeat):
            c0 = time.process_time()
            d = diagnose(case)
            cpu.append(time.process_time() - c0)
            times.append(d.seconds)
            fits.append(d.candidate_fits)
        named = ",".join(f.cause for f in d.findings) or "none"
        verdict = "unexplained" if d.unexplained else "explained"
        print(f"{label:34s} {np.median(times):7.1f}s {np.median(cpu):6.1f}s "
              f"{int(np.median(fits)):5d}  {named} ({verdict})", flush=True)
    print("target: median < 20 s per record (issue 14)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3, tuple(sys.argv[2:]))
