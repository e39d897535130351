"""Recall table of the diagnosis (slow suite): the full ``diagnose`` on fixed records of the
independent reference simulator (``tests/reference_diagnosis_records.py``): at least two
records per lateral-rig family, the compounds and regressions of issue 24 (a second mode
in a 0.2 mm chirp at 80 % fill; a second mode with a sensor delay; a hardening hinge at
80 % fill; a diaphragm spring with a second mode, an offset and drift), and clean controls
of different drives and tank sizes. A change that loses a family fails a row.

Each row must name exactly its causes (any order; a control names nothing), explain the
data, recover the named parameters within the record's tolerance (15 % unless stated: the
hidden effects are well above the noise), and stay within the diagnosis's CPU-time budget
(:data:`estimate.diagnosis.fitter.SECONDS_PER_SAMPLE`, 45 s for 30 s at 100 Hz) plus the
final fit's: 60 s of CPU time (issue 24: no record of <= 30 s at 100 Hz over 60 s on 2
cores). CPU time, not wall time: it does not depend on what else the machine runs.

The spinning-rig families (rotor, rotary oscillator) have their records in
``test_spinning_diagnose.py`` (minutes each).

Run ``python tests/estimate/diagnosis/test_recall.py [--rate HZ] [NAME ...]`` to print the
table (record, hidden effect, named causes, parameters against the truth, CPU and wall
time); ``--rate 500``: the rows of :data:`RIG_RATE` recorded at 500 Hz.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import pytest

if __name__ == "__main__":  # run as a script: the records live in tests/, whose estimate/
    # folder must not shadow the package (the repository goes first)
    sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
    sys.path.append(str(Path(__file__).resolve().parents[2]))

import reference_diagnosis_records as R  # noqa: E402

from estimate import diagnose  # noqa: E402

#: CPU seconds a diagnosis of a 30 s, 100 Hz record may take (see the module docstring).
MAX_CPU = 60.0


def run(name: str, folder, rate: float = 100.0) -> dict:
    """Diagnose record ``name`` sampled at ``rate`` (Hz); its row of the table."""
    rec = R.RECORDS[name]
    case, _ = R.build(name, folder, rate)
    cpu, wall = time.process_time(), time.perf_counter()
    d = diagnose(case, progress=False)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    final = dict(zip(d.final.names, d.final.values))
    return {"record": name, "effect": rec.effect, "expected": rec.causes,
            "named": tuple(f.cause for f in d.findings), "explained": not d.unexplained,
            "verdict": d.verdict.text,
            "parameters": {k: (final.get(k, float("nan")), v) for k, v in rec.truth.items()},
            "tolerance": rec.tolerance, "cpu": cpu, "wall": wall,
            "budget_ended": [f.text() for f in d.budget_ended]}


def check(row: dict) -> None:
    assert sorted(row["named"]) == sorted(row["expected"]), row["verdict"]
    assert row["explained"], row["verdict"]
    for name, (value, truth) in row["parameters"].items():
        assert value == pytest.approx(truth, rel=row["tolerance"]), name
    assert row["cpu"] < MAX_CPU, (row["cpu"], row["budget_ended"])


def test_every_record_is_a_physical_tank():
    """The analog of each record holds no more mass than the liquid in its tank (the
    sphere's cap volume, computed here): a record that does would be fitted against the
    liquid budget and lose a family to a bias no real tank has."""
    for name, rec in R.RECORDS.items():
        radius, depth = 0.1016 * rec.scale, 2 * 0.1016 * rec.scale * rec.fill
        liquid = 998.2 * math.pi * depth**2 * (3 * radius - depth) / 3
        analog = rec.fixed_mass + sum(p.mass for p in rec.pendulums)
        assert analog <= liquid, (name, analog, liquid)


@pytest.mark.slow
@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=r.known) if r.known else ())
    for n, r in R.RECORDS.items()])
def test_recall(name, tmp_path):
    check(run(name, tmp_path))


#: Rows recorded at 500 Hz (30 s, 15,001 samples; every family and a control), which the
#: diagnosis searches decimated to the slosh band and fits on every sample at the end
#: (issue 27); the same CPU bound.
RIG_RATE = ("sweep60_mode2", "steps_spring80", "steps60_quad", "steps80_friction",
            "steps_cubic80", "sweep60_delay", "sweep60_offset", "steps60_rigfriction",
            "steps80_asymmetric", "ctrl_sweep60")


@pytest.mark.slow
@pytest.mark.parametrize("name", RIG_RATE)
def test_recall_at_the_rig_rate(name, tmp_path):
    check(run(name, tmp_path, rate=500.0))


def _table(rows: list[dict]) -> str:
    out = ["| record | hidden effect | named | parameter vs truth | CPU s | wall s | pass |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        try:
            check(r)
            ok = "yes"
        except AssertionError as err:
            ok = f"NO: {str(err).splitlines()[0][:80]}"
        if R.RECORDS[r["record"]].known:
            ok += " (known failure)"
        params = "; ".join(f"`{k}` {v:.4g} ({100 * (v / t - 1):+.1f} %)"
                           for k, (v, t) in r["parameters"].items()) or "-"
        out.append(f"| {r['record']} | {r['effect']} | {', '.join(r['named']) or 'none'} | "
                   f"{params} | {r['cpu']:.1f} | {r['wall']:.1f} | {ok} |")
    return "\n".join(out)


if __name__ == "__main__":
    import tempfile

    args = sys.argv[1:]
    rate = float(args.pop(args.index("--rate") + 1)) if "--rate" in args else 100.0
    args = [a for a in args if a != "--rate"]
    names = args or (list(RIG_RATE) if rate != 100.0 else list(R.RECORDS))
    rows = []
    for n in names:
        rows.append(run(n, Path(tempfile.mkdtemp()), rate))
        print(_table(rows[-1:]).splitlines()[-1], flush=True)
    print(_table(rows))
