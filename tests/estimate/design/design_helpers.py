"""Records and fits for the design tests, from the independent reference simulators
(``tests/reference_models.py``, ``tests/reference_spinning.py``): a first record that
leaves a question open, the rig's limits, and the truth that answers it."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import reference_models as ref
from scipy.interpolate import make_interp_spline
from synthetic_cases import make_case, pendulum

from estimate import FitProblem, fit, load_case, model_from_spec, write_case
from estimate.data.case import Limits, Prediction

G = 9.80665
#: The rig: 100 mm stroke, 0.3 m/s, 2 m/s^2, records of up to 30 s.
LIMITS = Limits(stroke=0.1, velocity=0.3, acceleration=2.0, duration=30.0)
#: The 8-inch sphere at 60 % fill as ``rig_record`` makes it (masses kg, length m), and the
#: prediction its case file carries.
FIXED, DRY, MASS, LENGTH = 1.5, 1.2, 1.30, 0.0553
PREDICTION = Prediction(1.338, 0.057, 1.456, 0.007)
#: Record noise as on rigs (test-records.md): force 1.3 % of its RMS plus a 25 Hz motor
#: tone, displacement 2e-5 m.
NOISE = {"noise": 0.013, "displacement_noise": 2e-5, "tone": ref.Tone(0.05, 25.0)}


class FromCSV:
    """A drive file (``time,displacement``) played by the rig: a quintic interpolating
    spline of the samples (SciPy), with its derivatives; at rest outside the file."""

    def __init__(self, path: Path) -> None:
        data = np.loadtxt(path, delimiter=",", skiprows=1)
        self.time, self.displacement = data[:, 0], data[:, 1]
        self.spline = make_interp_spline(self.time, self.displacement, k=5)

    def __call__(self, t):
        t = np.clip(np.asarray(t, float), self.time[0], self.time[-1])
        return self.spline(t), self.spline(t, 1), self.spline(t, 2)


def with_limits(case_path: Path, limits: Limits = LIMITS):
    """Rewrite a case file with ``[rig.limits]`` (through ``write_case``) and load it."""
    case = load_case(case_path)
    return write_case(case_path, test=case.test, tank=case.tank, liquid=case.liquid,
                      rig=replace(case.rig, limits=limits), time=case.time, force=case.force,
                      displacement=case.displacement, channels=dict(case.columns) or None,
                      prediction=case.prediction, overwrite=True)


def lateral_record(folder: Path, name: str, drive, *, truth: ref.Pendulum, seed: int,
                   diaphragm: bool = False):
    """A 30 s record of ``drive`` (a reference excitation) from rest, with rig noise."""
    case, sim = make_case(folder, name, drive, pendulums=[truth], fixed_mass=FIXED,
                          dry_mass=DRY, seed=seed, prediction=PREDICTION, diaphragm=diaphragm,
                          **NOISE)
    return with_limits(case.path), sim


def fit_json(folder: Path, name: str, cases, spec: str = "fixed,p1", **build) -> tuple[Path, object]:
    """Fit ``cases`` with ``spec`` and write the JSON ``slosh fit`` writes."""
    cases = list(cases)
    res = fit(FitProblem.build(cases, model_from_spec(spec, cases[0]), **build), progress=False)
    data = res.to_dict()
    data["model_spec"] = spec
    path = Path(folder) / f"{name}.json"
    path.write_text(json.dumps(data))
    return path, res


def halfwidth(res, name: str) -> float:
    """95 % half-width of an estimate over its value (as the design states it); for an
    estimate at a bound, from the standard deviation the data allow it away from the bound
    (``FitResult.bound_stderr``: a confounded length slides to its bound)."""
    i = res.names.index(name)
    se = res.stderr[i]
    if not np.isfinite(se) and res.bound_stderr is not None:
        se = res.bound_stderr[i]
    return 1.959963984540054 * se / abs(res.value(name))


def swing_scaled(drive_of_amplitude, truth: ref.Pendulum, max_swing: float,
                 t: np.ndarray) -> float:
    """The amplitude (m) at which the reference simulator's peak swing of
    ``drive_of_amplitude(a)`` is ``max_swing`` (bisection on the truth)."""
    def peak(a):
        sim = ref.simulate_lateral(t, drive_of_amplitude(a), pendulums=[truth], gravity=G,
                                   rtol=1e-8, atol=1e-10)
        return float(np.abs(sim["theta"]).max())

    lo, hi = 0.0, 0.05
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if peak(mid) < max_swing else (lo, mid)
    return lo


def truth_pendulum(stiffness: float = 0.0) -> ref.Pendulum:
    return pendulum(MASS, LENGTH, 0.01, stiffness=stiffness)
