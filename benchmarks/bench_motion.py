"""Benchmark of issue 29: a 30 s, 500 Hz six-channel record of a tank moved in 3-D.

Run: ``python benchmarks/bench_motion.py``. The record is acceptance record (b) of
``tests/estimate/fitting/test_motion_records.py`` (a 5 deg pitch at 0.45 f1 with x and y
translations, from rest, noise, a tone and a drift on all six channels; 15001 samples),
made by the independent reference simulator. Printed, each the median of 3 runs after a
warm-up (the derivation and the compiled RK4 step cached): wall and CPU time of
``FitProblem.build`` + ``fit`` with the transducer's offsets and drifts estimated (19
parameters) and without them (7), against the issue's 10 s, with the estimates' errors.
"""

import math
import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
from _common import median_times

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
import estimate  # noqa: F401  (the package before tests/ joins the path: editable installs)

sys.path.append(str(ROOT / "tests"))
import reference_motion as rm
from motion_cases import PENDULUM, make_motion_case, truth

from estimate import ChannelOffsets, FitProblem, fit, model_from_spec

TARGET_S = 10.0


def main() -> None:
    f1 = PENDULUM.frequency_hz()
    motion = rm.Motion(x=rm.RampedSine(0.004, 0.77 * f1, ramp=2.0, start=0.5),
                       y=rm.RampedSine(0.003, 1.27 * f1, math.pi / 3, ramp=2.0, start=1.0),
                       pitch=rm.RampedSine(math.radians(5), 0.45 * f1, 0.0, ramp=2.0, start=0.7))
    with tempfile.TemporaryDirectory() as tmp:
        case, _ = make_motion_case(Path(tmp), "B", motion, seed=2)
        print(f"record: {case.n_samples} samples at {case.sample_rate:.0f} Hz, channels "
              f"{', '.join(c for c in case.channels if c.startswith(('force', 'torque')))}")
        model = model_from_spec("fixed,p1:nospring", case)
        tr = truth()
        for label, measurement in (("with offsets and drifts", (ChannelOffsets(),)),
                                   ("without", ())):
            out = {}

            def run(measurement=measurement, out=out):
                prob = FitProblem.build(case, model, measurement=measurement)
                out["res"] = fit(prob, progress=False)

            wall, cpu = median_times(run, repeat=3, warmup=1)
            res = out["res"]
            errors = ", ".join(f"{n} {100 * (res.value(n) / tr[n] - 1):+.2f} %"
                               for n in ("fixed.mass", "p1.mass", "p1.length"))
            heights = ", ".join(f"{n} {1e3 * (res.value(n) - tr[n]):+.2f} mm"
                                for n in ("fixed.height", "p1.hinge_height"))
            print(f"fit {label} ({len(res.names)} parameters, {res.iterations} iterations): "
                  f"wall {wall:.2f} s, CPU {cpu:.2f} s ({cpu / TARGET_S:.2f} x the issue's "
                  f"{TARGET_S:g} s); {errors}; {heights}")


if __name__ == "__main__":
    main()
