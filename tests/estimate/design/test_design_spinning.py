"""``slosh design`` on the spinning rig: spin rate, coning frequency and cone angle as the
design variables within ``[rig.limits]``, checked on the independent reference simulator
(``tests/reference_spinning.py``: hand-written Newton-Euler equations, SciPy DOP853).

The first record spins at 6 rad/s and cones slowly (-0.2 Hz, 0.03 rad), with the pendulum
swung out on its cone: the fixed and pendulum masses are fixed only together (correlation
-0.99, +/-0.36 %). The recommended test, run on the truth with noise on all six channels and
fitted with the first record, narrows them at least as much as predicted. (The prediction
is conservative here: the noise of the new record is taken as the fitted record's, while
the generator's noise is 1.5 % of each channel's spread, smaller at a slower spin.) A
spinning fit of two records takes a minute or more: slow.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import reference_spinning as rs
from design_helpers import fit_json, halfwidth, with_limits
from synthetic_cases import make_spinning_case

from estimate.cli import main
from estimate.data.case import Limits

pytestmark = pytest.mark.slow

PEND = rs.SphericalPendulum(1.25, 0.062, 0.035, damping=5e-4)
FIXED_MASS, FIXED_HEIGHT = 1.5, 0.05
LIMITS = Limits(spin_rate=8.0, nutation_frequency=1.0, cone_angle=0.08, duration=30.0)
#: The issue's "within 30 %" for the predicted shrink factor.
WITHIN = 0.7


def test_spinning_design_within_limits_and_as_predicted(tmp_path):
    rig = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.03,
                 nutation_frequency=-0.2, dry_mass=2.0, spin_up=12.0, nutation_ramp=5.0)
    first, _ = make_spinning_case(tmp_path, "S", rig, pendulum=PEND, fixed_mass=FIXED_MASS,
                                  fixed_height=FIXED_HEIGHT, seed=11, tank_radius=0.1016,
                                  duration=30.0, noise=0.015)
    first = with_limits(first.path, LIMITS)
    fit_path, res_a = fit_json(tmp_path, "S_fit", [first])
    out = tmp_path / "design.json"
    assert main(["design", str(fit_path), str(first.path), "--target", "fixed.mass,p1.mass",
                 "--json", str(out), "--plot", str(tmp_path / "design.png")]) == 0
    d = json.loads(out.read_text())
    spin = d["recommended"]["spin"]
    # within the limits the case file gives
    assert abs(spin["rate_rad_s"]) <= LIMITS.spin_rate
    assert abs(spin["nutation_frequency_hz"]) <= LIMITS.nutation_frequency
    assert 0 < spin["cone_angle_rad"] <= LIMITS.cone_angle
    assert spin["spin_up_s"] + spin["nutation_ramp_s"] < LIMITS.duration
    table = np.loadtxt(d["drive_file"], delimiter=",", skiprows=1)
    assert np.abs(table[:, 2]).max() <= LIMITS.spin_rate * (1 + 1e-9)
    assert np.abs(table[:, 4]).max() <= LIMITS.cone_angle * (1 + 1e-9)
    # the recommended test on the truth, fitted with the first record
    new = rs.Rig(spin_rate=spin["rate_rad_s"], radius=0.4, height=0.1,
                 nutation_angle=spin["cone_angle_rad"],
                 nutation_frequency=spin["nutation_frequency_hz"], dry_mass=2.0,
                 spin_up=spin["spin_up_s"], nutation_ramp=spin["nutation_ramp_s"],
                 nutation_start=spin["spin_up_s"])
    second, _ = make_spinning_case(tmp_path, "T", new, pendulum=PEND, fixed_mass=FIXED_MASS,
                                   fixed_height=FIXED_HEIGHT, seed=4, tank_radius=0.1016,
                                   duration=30.0, noise=0.015)
    start = {n: res_a.value(n) for n in res_a.names}
    _, res = fit_json(tmp_path, "ST_fit", [first, second], initial=start)
    assert res.converged
    for n in ("fixed.mass", "p1.mass"):
        before = d["before"][n]["halfwidth_95_relative"]
        predicted = d["recommended"]["predicted"][n]["halfwidth_95_relative"]
        achieved = halfwidth(res, n)
        print(f"\n{n}: before {before:.4g}, predicted {predicted:.4g}, achieved {achieved:.4g}")
        assert before / achieved >= WITHIN * before / predicted
        lo, hi = res.interval(n)
        assert lo <= {"fixed.mass": FIXED_MASS, "p1.mass": PEND.mass}[n] <= hi
