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

Rig-rate records (issue 27, target < 60 s for 60 s at 500 Hz), each as recorded (the
diagnosis searches it decimated to 100 Hz and fits its baseline and final model on every
sample) and decimated to 100 Hz throughout (``--decimate 5``): ``sweep60`` the 60 s,
500 Hz sweep of ``bench_length.py`` (the model exact: nothing to find) and ``hardware60``
a 60 s, 500 Hz
sweep through resonance through the six-axis transducer's model (coloured noise, lines,
quantisation) 20 ms behind the displacement, the container not weighed (a stream lag to
find). All synthetic, from the reference simulators.
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


def _hardware60(folder: Path):
    """The ``hardware60`` record (see the module)."""
    import reference_models as ref
    import reference_rig_records as rr
    from synthetic_cases import G, make_case, pendulum

    p = pendulum(1.30, 0.0553, 0.01)
    f1 = ref.natural_frequency(p, G) / (2 * np.pi)
    drive = ref.Ramped(ref.LinearSweep(0.0015, 1.5 * f1, 0.7 * f1, 60.0), 1.5, 0.0)
    _, sim = make_case(folder, "hardware60", drive, pendulums=[p], fixed_mass=2.842 - p.mass,
                       dry_mass=1.2, duration=60.0, rate=500.0, seed=7, noise=0.0,
                       sensor_delay=0.02)
    rr.force_through_sensor(folder / "hardware60.csv", sim, 7)
    toml = folder / "hardware60.toml"
    toml.write_text(toml.read_text().replace("dry_mass = 1.2", 'dry_mass = "estimate"'))
    return load_case(toml)


def _rate_records(folder: Path, only: tuple[str, ...]) -> dict:
    """The rig-rate records asked for, each at its full rate and decimated by 5."""
    import os

    from bench_length import record

    from estimate.data.decimation import decimate_case

    made = {}
    if not only or "sweep60" in only:
        made["60 s sweep, 500 Hz"] = load_case(record(60.0, 500.0, dict(os.environ)))
    if not only or "hardware60" in only:
        made["60 s hardware-like, 500 Hz"] = _hardware60(folder)
    out = {}
    for label, case in made.items():
        out[label] = case
        out[label.replace("500 Hz", "decimated 5")] = decimate_case(case, 5, "--decimate")
    return out


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
    cases |= _rate_records(folder, only)
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
    print("target: median < 20 s per 30 s, 100 Hz record (issues 14, 27); < 60 s for 60 s at "
          "500 Hz (issue 27)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3, tuple(sys.argv[2:]))
