"""Print the README's table of FMU errors against the host's communication step.

The README case: the A1 analog (``examples/A1_params.json``, dry mass 1.2 kg) as an FMU,
10 s of the README sine (5 mm at 1.855 Hz) sampled at the host step, outputs at every step,
against ``derive.simulate`` (RK4, same grid, exact sine). Errors are the largest
``|force_x|`` difference relative to the peak force, over the whole run and from the second
output on (the first output after the start comes from a single input sample).

Run: ``python docs/make_fmu_table.py`` (needs FMPy and a C compiler).
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import sys
import tempfile
from pathlib import Path

import fmpy
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from derive import RK4, Sine, simulate
from derive.fmu import co_simulate, export_fmu
from estimate.cli.export import export_model
from estimate.fitting.record import read_params

INPUTS = ("rig.x", "rig.x_dot", "rig.x_ddot")
STEPS = (0.001, 0.005, 0.01)
ROWS = (
    ("`simulate_fmu`, `solver.input_extrapolation = 0` (held; before)", 0),
    ("`simulate_fmu` (default: linear extrapolation)", 1),
    ("`simulate_fmu`, `solver.input_extrapolation = 2` (quadratic)", 2),
    ("`co_simulate` (input derivatives)", None),
)


def main() -> None:
    values = read_params(ROOT / "examples" / "A1_params.json") | {"rig.dry_mass": 1.2}
    model, used = export_model("fixed,p1", values)
    w = 2 * np.pi * 1.855
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_fmu(model, Path(tmp) / "analog.fmu", used)
        cells = {}
        for h in STEPS:
            t = np.arange(0.0, 10.0 + h / 2, h)
            x = 0.005 * np.sin(w * t)
            columns = (x, 0.005 * w * np.cos(w * t), -w**2 * x)
            signals = np.array(list(zip(t, *columns)),
                               dtype=[("time", float)] + [(n, float) for n in INPUTS])
            own = simulate(model, used, t, Sine(0.005, 1.855), integrator=RK4()).output("force_x")
            for label, order in ROWS:
                if order is None:
                    force = co_simulate(fmu, t, dict(zip(INPUTS, columns)), ["force_x"])["force_x"]
                else:
                    force = fmpy.simulate_fmu(str(fmu), stop_time=10.0, output_interval=h,
                                              input=signals, output=["force_x"],
                                              start_values={"solver.input_extrapolation": order}
                                              )["force_x"]
                e = 100 * np.abs(force - own) / np.max(np.abs(own))
                cells[label, h] = f"{e[2:].max():.3g} % ({e.max():.3g} %)"
    print("| master | " + " | ".join(f"{h * 1e3:g} ms" for h in STEPS) + " |")
    print("|---|" + "---|" * len(STEPS))
    for label, _ in ROWS:
        print(f"| {label} | " + " | ".join(cells[label, h] for h in STEPS) + " |")


if __name__ == "__main__":
    main()
