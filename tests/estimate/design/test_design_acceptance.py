"""Issue 31 acceptance: the recommended drive, run on the truth (the independent reference
simulator, from rest, noise on both channels) and fitted together with the first record,
narrows the target intervals as predicted, and more than the habitual drives do.

Each test runs ``slosh design`` as a user does, plays its drive file on the reference
simulator (a quintic spline through the CSV, as a rig's controller plays it) and fits the
first record and the new one together (``slosh fit A.toml B.toml`` does the same shared
fit). The fits take tens of seconds each: slow.

Tolerances: "by at least the predicted factor within 30 %" is the issue's (achieved shrink
factor >= 0.7 x predicted). The prediction is made at the first fit's estimates, which are
off the truth by up to two standard errors (the damping ratio by a factor of two on the
first record), so the drive's true swing and the achieved intervals differ a little from
the predicted ones; the sampling of the standard errors over the noise draw is ~1 %.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import reference_models as ref
from design_helpers import (
    LIMITS,
    FromCSV,
    G,
    fit_json,
    halfwidth,
    lateral_record,
    swing_scaled,
    truth_pendulum,
    with_limits,
)
from synthetic_cases import make_case, rig_record

from estimate.cli import main
from estimate.data.case import Limits, Prediction

pytestmark = pytest.mark.slow

#: The issue's "within 30 %".
WITHIN = 0.7
TARGETS = ("p1.mass", "fixed.mass")


def _limits_respected(csv_path, limits, rate: float) -> None:
    """The drive file within the rig's limits, read independently: the CSV's samples and a
    quintic spline through them on a grid 20 times finer (derivatives from SciPy). 0.5 %
    allows for the spline's own error between samples."""
    drive = FromCSV(csv_path)
    t = drive.time
    assert np.allclose(np.diff(t), 1 / rate, rtol=1e-6), "not at the rig's rate"
    fine = np.linspace(t[0], t[-1], 20 * t.size)
    x, v, a = drive(fine)
    assert np.abs(drive.displacement).max() <= limits.stroke / 2
    assert np.abs(x).max() <= limits.stroke / 2 * 1.005
    assert np.abs(v).max() <= limits.velocity * 1.005
    assert np.abs(a).max() <= limits.acceleration * 1.005
    assert t[-1] <= limits.duration + 1e-9
    # from rest, and back to rest
    assert abs(drive.displacement[0]) < 1e-9 and abs(drive.displacement[-1]) < 1e-9


@pytest.fixture(scope="module")
def masses(tmp_path_factory):
    """A steady 4 mm sine at 0.4 f1: the pendulum moves almost like a rigid mass, so the
    fixed and pendulum masses are fixed only together (correlation -0.99)."""
    folder = tmp_path_factory.mktemp("masses")
    truth = truth_pendulum()
    f1 = ref.natural_frequency(truth, G) / (2 * np.pi)
    first, _ = lateral_record(folder, "A", ref.Ramped(ref.Sine(0.004, 0.4 * f1), 1.5),
                              truth=truth, seed=1)
    fit_path, res_a = fit_json(folder, "A_fit", [first])
    out = folder / "design.json"
    assert main(["design", str(fit_path), str(first.path), "--target", ",".join(TARGETS),
                 "--json", str(out), "--plot", str(folder / "design.png")]) == 0
    return folder, truth, f1, first, res_a, json.loads(out.read_text())


def _joint(folder, first, name, drive, truth, seed):
    case, sim = lateral_record(folder, name, drive, truth=truth, seed=seed)
    _, res = fit_json(folder, f"{name}_fit", [first, case])
    assert res.converged
    return res, sim


def test_recommended_drive_narrows_the_masses_as_predicted(masses):
    folder, truth, f1, first, res_a, design = masses
    assert design["targets"] == list(TARGETS)
    _limits_respected(design["drive_file"], LIMITS, 100.0)
    res_b, sim = _joint(folder, first, "B", FromCSV(design["drive_file"]), truth, seed=11)
    table = {}
    for n in TARGETS:
        before = halfwidth(res_a, n)
        predicted = design["recommended"]["predicted"][n]["halfwidth_95_relative"]
        achieved = halfwidth(res_b, n)
        assert design["before"][n]["halfwidth_95_relative"] == pytest.approx(before, rel=1e-6)
        table[n] = (before, predicted, achieved)
        assert before / achieved >= WITHIN * before / predicted, (n, table)
        lo, hi = res_b.interval(n)
        assert lo <= {"p1.mass": truth.mass, "fixed.mass": 1.5}[n] <= hi
    print("\npredicted vs achieved 95 % half-widths:", table)
    # the habitual drives, run on the same truth: a 1-5 Hz sweep of the same duration and
    # peak acceleration, and a sine at the predicted frequency at the largest amplitude
    # whose true swing stays within the design's swing limit
    peak = float(np.abs(sim["acceleration"]).max())
    unit = ref.Ramped(ref.LinearSweep(1.0, 1.0, 5.0, 29.5), 2.0, 0.5)
    t = np.arange(0, 30.0, 1e-3)
    a = peak / np.abs(unit(t)[2]).max()
    sweep = ref.Ramped(ref.LinearSweep(a, 1.0, 5.0, 29.5), 2.0, 0.5)
    f_pred = res_a.derived["p1.frequency_hz"][0]
    amp = swing_scaled(lambda x: ref.Ramped(ref.Sine(x, f_pred), 2.0, 0.5), truth,
                       design["max_swing_rad"], np.arange(3001) * 0.01)
    sine = ref.Ramped(ref.Sine(amp, f_pred), 2.0, 0.5)
    for label, drive, seed in (("sweep", sweep, 12), ("sine at f1", sine, 13)):
        res, _ = _joint(folder, first, label.replace(" ", "_"), drive, truth, seed)
        widths = {n: halfwidth(res, n) for n in TARGETS}
        print(label, widths)
        assert all(table[n][2] < widths[n] for n in TARGETS), (label, widths, table)


def test_diaphragm_length_and_spring_are_separated(tmp_path):
    """A hinge spring (a diaphragm) carrying a third of the restoring stiffness: a sine
    below resonance determines only the frequency, so the length and the spring are
    confounded (length +/- hundreds of %). The recommended drive, with the first record,
    determines the length to better than +/-5 %, and the interval holds the truth."""
    m, L = 1.30, 0.0553
    k = 0.5 * m * G * L
    truth = truth_pendulum(stiffness=k)
    f1 = ref.natural_frequency(truth, G) / (2 * np.pi)
    first, _ = lateral_record(tmp_path, "D", ref.Ramped(ref.Sine(0.004, 0.6 * f1), 1.5),
                              truth=truth, seed=3, diaphragm=True)
    # the spring starts at a positive value: from zero this record's fit settles in
    # another basin (a massless pendulum); what matters here is a fit that converged
    fit_path, res_a = fit_json(tmp_path, "D_fit", [first], initial={"p1.stiffness": 0.2})
    assert halfwidth(res_a, "p1.length") > 1.0  # confounded: +/- more than 100 %
    out = tmp_path / "design.json"
    assert main(["design", str(fit_path), str(first.path), "--target", "p1.length,p1.stiffness",
                 "--json", str(out)]) == 0
    design = json.loads(out.read_text())
    _limits_respected(design["drive_file"], LIMITS, 100.0)
    assert design["pinned_down"]["p1.length"]
    case, _ = lateral_record(tmp_path, "B", FromCSV(design["drive_file"]), truth=truth,
                             seed=5, diaphragm=True)
    start = {n: res_a.value(n) for n in res_a.names}
    _, res = fit_json(tmp_path, "DB_fit", [first, case], initial=start)
    assert halfwidth(res, "p1.length") < 0.05
    lo, hi = res.interval("p1.length")
    assert lo <= L <= hi
    lo, hi = res.interval("p1.stiffness")
    assert lo <= k <= hi
    print("\nlength: predicted", design["recommended"]["predicted"]["p1.length"],
          "achieved", halfwidth(res, "p1.length"))


def test_full_size_tank_as_predicted(tmp_path):
    """The same question on a full-size tank (the 8-inch sphere scaled 4x: masses 64x, f1
    1.06 Hz) on a bigger rig (400 mm, 0.4 m/s, 1 m/s^2, 60 s records): nothing in the
    design is tuned to one tank."""
    scale = 4.0
    limits = Limits(stroke=0.4, velocity=0.4, acceleration=1.0, duration=60.0)
    first, _, truth = rig_record(tmp_path, "A", lambda f1: ref.Sine(0.01, 0.4 * f1),
                                 scale=scale, seed=7)
    first = with_limits(first.path, limits)
    fit_path, res_a = fit_json(tmp_path, "A_fit", [first])
    out = tmp_path / "design.json"
    assert main(["design", str(fit_path), str(first.path), "--target", ",".join(TARGETS),
                 "--json", str(out)]) == 0
    design = json.loads(out.read_text())
    _limits_respected(design["drive_file"], limits, 100.0)
    second, _ = make_case(tmp_path, "B", FromCSV(design["drive_file"]),
                          pendulums=[truth["pendulum"]], fixed_mass=truth["fixed.mass"],
                          dry_mass=1.2 * scale**3, noise=0.013, displacement_noise=2e-5,
                          seed=8, tone=ref.Tone(0.05 * scale**3, 25.0), duration=60.0,
                          prediction=Prediction(1.338 * scale**3, 0.057 * scale,
                                                1.456 * scale**3, 0.007))
    _, res = fit_json(tmp_path, "AB_fit", [first, second])
    for n in TARGETS:
        before = halfwidth(res_a, n)
        predicted = design["recommended"]["predicted"][n]["halfwidth_95_relative"]
        achieved = halfwidth(res, n)
        print(f"\n{n}: before {before:.4g}, predicted {predicted:.4g}, achieved {achieved:.4g}")
        assert before / achieved >= WITHIN * before / predicted
        lo, hi = res.interval(n)
        assert lo <= truth[n] <= hi
