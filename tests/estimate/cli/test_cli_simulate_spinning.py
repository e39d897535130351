"""``slosh simulate`` on a spinning-rig case: every channel the case measures, from a steady
start, against the independent reference simulator (``tests/reference_spinning.py``)."""

import json
import re

import numpy as np
import pytest
import reference_spinning as rs
from synthetic_cases import make_spinning_case

from estimate.cli import main

#: CVODES (the CLI's --integrator adaptive) and DOP853 both at rtol ~1e-10 on the same
#: analytic rig motion; the steady start is solved on both sides to ~1e-12 rad.
CHANNEL_RMS = 1e-6

RIG = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06, nutation_frequency=-0.5,
             dry_mass=2.0, nutation_ramp=2.0, nutation_start=1.0)
TRUTH = {"fixed.mass": 1.5, "fixed.height": 0.05, "fixed.inertia": 0.0,
         "fixed.axial_inertia": 0.0, "p1.mass": 1.25, "p1.length": 0.062,
         "p1.hinge_height": 0.035, "p1.damping": 5e-4, "p1.stiffness": 0.0,
         "r1.inertia": 0.01, "r1.damping": 0.04}


def test_simulate_writes_six_channels_matching_the_reference_from_a_steady_start(tmp_path):
    case, sim = make_spinning_case(
        tmp_path, "S1", RIG, pendulum=rs.SphericalPendulum(1.25, 0.062, 0.035, damping=5e-4),
        rotor=rs.Rotor(0.01, 0.04, axis="y"), fixed_mass=1.5, fixed_height=0.05, noise=0.0,
        duration=4.0, steady=True, tank_radius=0.1016)
    assert case.test.initial_state == "steady" and case.spin.motion == "input"
    (tmp_path / "truth.json").write_text(json.dumps(TRUTH))
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(case.path), "--params", str(tmp_path / "truth.json"),
                 "--model", "fixed,p1,r1", "--integrator", "adaptive", "--out", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    assert header == ["time", *rs.CHANNELS]
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    for j, name in enumerate(rs.CHANNELS, start=1):
        ref = sim["clean"][name]
        err = np.sqrt(np.mean((data[:, j] - ref) ** 2) / np.mean(ref**2))
        assert err < CHANNEL_RMS, (name, err)
    # the steady start matters: the pendulum starts swung out ~59 deg (from rest it would
    # swing for the whole record)
    assert np.degrees(sim["states"][0, 0]) == pytest.approx(59.0, abs=0.5)


def test_simulate_a_free_start_needs_the_fitted_initial_state(tmp_path, capsys):
    case, _ = make_spinning_case(tmp_path, "S2", RIG, noise=0.0, duration=1.0,
                                 pendulum=rs.SphericalPendulum(1.25, 0.062, 0.035))
    text = case.path.read_text().replace('excitation = "spin"',
                                         'excitation = "spin"\ninitial_state = "free"')
    case.path.write_text(text)
    (tmp_path / "truth.json").write_text(json.dumps(TRUTH))
    code = main(["simulate", str(case.path), "--params", str(tmp_path / "truth.json"),
                 "--model", "fixed,p1", "--out", str(tmp_path / "x.csv")])
    assert code == 2 and not (tmp_path / "x.csv").exists()
    assert re.search(r"case 'S2' starts from an estimated state .* has no `initial_states.S2`",
                     capsys.readouterr().err)
