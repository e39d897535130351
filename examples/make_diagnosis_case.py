"""Generate the bundled SYNTHETIC diagnosis example D1_two_modes (notebook 02).

A lateral-rig test of the 8-inch sphere whose data hide a second slosh mode (0.06 kg at
3.8 Hz) besides the first (1.30 kg, 0.0553 m, 1 % damping), excited by a 1-5 Hz sweep of
3 mm, 1 % force noise, fixed mass 1.45 kg, seed 11. Made with the independent reference
simulator ``tests/reference_models.py`` (hand-written equations, SciPy DOP853), not with
the project's model code. Run ``python examples/make_diagnosis_case.py``; writes
``D1_two_modes.toml`` and ``.csv`` next to this script (replacing them).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import estimate  # noqa: F401  (the project before tests/, whose folders share its names)

sys.path.append(str(HERE.parent / "tests"))
import reference_models as ref
from synthetic_cases import G, make_case, pendulum


def main() -> int:
    first = pendulum(1.30, 0.0553, 0.01)
    second = pendulum(0.06, G / (2 * math.pi * 3.8) ** 2, 0.01)
    make_case(HERE, "D1_two_modes", ref.LinearSweep(0.003, 1.0, 5.0, 30.0),
              pendulums=[first, second], fixed_mass=1.45, seed=11)
    print("wrote D1_two_modes.toml, D1_two_modes.csv (SYNTHETIC)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
