"""Spinning-rig records as the SSTR makes them, from the independent reference simulator
(``tests/reference_spinning.py``: hand-written Newton-Euler equations, SciPy DOP853):

(a) an off-axis record (r = 0.4 m) that spins the table up over 12 s and ramps the coning in
    over 5 s, with the table angles recorded in the CSV (``[rig.spin] spin_angle``, ...);
(b) an off-axis record that starts in steady spin (the pendulum on its cone, ~59 deg from
    the tank axis; ``[test] initial_state = "steady"``) with a rotor hidden, the coning
    ramped in over 1 s after 1 s. After a steady start the cone ramp is the only thing
    that sets the pendulum swinging at its own frequency (about 2.23 Hz seen from the
    tank, against the nutation's 1.45 Hz), the way the spin-up does in (a). A 3 s ramp
    hardly excites it: measured on this record (seed 12), the fit from the tank prediction
    then settled in another basin (p1.length 0.0546, RMS residual 4x the noise), and even
    started at the true length the fixed mass was only determined to 0.9 % (-2.1 %, 2.3
    standard errors); with the 1 s ramp it is determined to 0.2 %.

Both are hard the way rig records are (``/work/shared/notes/test-records.md``): 1.5 % white
noise on all six channels, a 23 Hz motor tone of 2 % and a transducer drift of 1 % of each
channel's standard deviation over the record.

The fits and the diagnosis take minutes: they are marked slow (``pytest -m slow``).
"""

import json
import math
import re

import numpy as np
import pytest
import reference_spinning as rs
from synthetic_cases import make_spinning_case

from estimate import ChannelOffsets, FitProblem, fit, model_from_spec
from estimate.cli import main

#: Issue 16 acceptance: masses within 2 %, the pendulum frequency within 0.5 %, each mass
#: within 3 of its stated standard errors.
MASS_TOL, FREQ_TOL, N_SE = 0.02, 0.005, 3.0

PEND = rs.SphericalPendulum(1.25, 0.062, 0.035, damping=5e-4)
ROTOR = rs.Rotor(0.01, 0.04, axis="y")
FIXED_MASS, FIXED_HEIGHT = 1.5, 0.05
#: Hard record: white noise, a motor tone (fraction of each channel's std, Hz), drift.
HARD = {"noise": 0.015, "tone": (0.02, 23.0), "drift": 0.01}
#: A table encoder of 16 bits: quantisation noise 2 pi / 2^16 / sqrt(12) ~ 3e-5 rad.
ENCODER_NOISE = 3e-5

RIG_A = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06,
               nutation_frequency=-0.5, dry_mass=2.0, spin_up=12.0, nutation_ramp=5.0)
RIG_B = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06,
               nutation_frequency=-0.5, dry_mass=2.0, nutation_ramp=1.0, nutation_start=1.0)


def _pendulum_frequency_hz(length: float, gravity: float = rs.STANDARD_GRAVITY) -> float:
    """The pendulum's frequency as ``pN.frequency_hz`` defines it on a rig with one
    restoring gravity: sqrt(g / L) / 2 pi. The spinning rig derives none (the centrifugal
    field adds to gravity), so the fitted one is this function of the fitted length: its
    relative error is half the length's (the mode the tank sees, 2.23 Hz here, scales with
    the length the same way)."""
    return math.sqrt(gravity / length) / (2 * math.pi)


def _check_masses(res, truth):
    for name, value in truth.items():
        est, se = res.value(name), res.stderr[res.names.index(name)]
        assert est == pytest.approx(value, rel=MASS_TOL), name
        assert abs(est - value) <= N_SE * se, (name, est, value, se)


@pytest.fixture(scope="module")
def record_a(tmp_path_factory):
    case, _ = make_spinning_case(tmp_path_factory.mktemp("a"), "A1", RIG_A, pendulum=PEND,
                                 fixed_mass=FIXED_MASS, fixed_height=FIXED_HEIGHT, seed=11,
                                 tank_radius=0.1016, duration=30.0, measured_angles=True,
                                 angle_noise=ENCODER_NOISE, **HARD)
    return case


@pytest.fixture(scope="module")
def fit_a(record_a):
    case = record_a
    assert case.spin.motion == "input" and set(case.spin.columns) == {
        "spin_angle", "nutation_phase", "cone_angle"}
    # the transducer's zero and drift of every channel are estimated with the parameters
    prob = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case),
                            hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0},
                            measurement=(ChannelOffsets(),))
    res = fit(prob, progress=False)
    print(f"\n(a) fit {res.seconds:.1f} s:", {n: round(float(v), 6) for n, v in
                                           zip(res.names, res.values)})
    return res


@pytest.mark.slow
def test_a_spin_up_and_cone_ramp_from_measured_table_angles(fit_a):
    res = fit_a
    assert res.converged, res.status
    for name, value in {"fixed.mass": FIXED_MASS, "p1.mass": PEND.mass}.items():
        assert res.value(name) == pytest.approx(value, rel=MASS_TOL), name
    f_hz = _pendulum_frequency_hz(res.value("p1.length"))
    assert f_hz == pytest.approx(_pendulum_frequency_hz(PEND.length), rel=FREQ_TOL)


@pytest.mark.slow
def test_a_masses_within_three_standard_errors_despite_drift(fit_a):
    # without the channel offsets and drifts fixed.mass was 3.3 standard errors off
    # (1.4913 +/- 0.0027 kg): the drift was read as mass
    _check_masses(fit_a, {"fixed.mass": FIXED_MASS, "p1.mass": PEND.mass})
    assert sum(n.startswith("A1:rig.") and n.endswith(("_offset", "_drift"))
               for n in fit_a.names) == 12


@pytest.fixture(scope="module")
def record_b(tmp_path_factory):
    case, sim = make_spinning_case(tmp_path_factory.mktemp("b"), "B1", RIG_B, pendulum=PEND,
                                   rotor=ROTOR, fixed_mass=FIXED_MASS,
                                   fixed_height=FIXED_HEIGHT, seed=12, tank_radius=0.1016,
                                   duration=15.0, steady=True, **HARD)
    return case, sim


@pytest.mark.slow
def test_b_steady_start_with_the_rotor_fits(record_b):
    case, sim = record_b
    assert case.test.initial_state == "steady"
    assert np.degrees(sim["states"][0, 0]) == pytest.approx(59.0, abs=0.5)  # on its cone
    prob = FitProblem.build(case, model_from_spec("fixed,p1:nospring,r1", case),
                            hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0},
                            initial={"r1.inertia": 0.005, "r1.damping": 0.02},
                            measurement=(ChannelOffsets(),))
    res = fit(prob, progress=False)
    assert res.converged, res.status
    assert res.initial_state_kinds == ("steady",)
    # the fitted start is the conical equilibrium of the fitted pendulum
    assert math.degrees(res.initial_states[0]["p1.alpha"]) == pytest.approx(59.0, abs=1.0)
    _check_masses(res, {"fixed.mass": FIXED_MASS, "p1.mass": PEND.mass})
    f_hz = _pendulum_frequency_hz(res.value("p1.length"))
    assert f_hz == pytest.approx(_pendulum_frequency_hz(PEND.length), rel=FREQ_TOL)
    # the rotor too: within 10 % (issue 7) and 3 of its standard errors
    for name, value in {"r1.inertia": ROTOR.inertia, "r1.damping": ROTOR.damping}.items():
        est, se = res.value(name), res.stderr[res.names.index(name)]
        assert est == pytest.approx(value, rel=0.10) and abs(est - value) <= N_SE * se, name
    print(f"\n(b) fit {res.seconds:.1f} s:", {n: round(float(v), 6) for n, v in
                                           zip(res.names, res.values)})


@pytest.mark.slow
def test_b_fits_from_the_command_line_with_honest_bounds(record_b, tmp_path, capsys):
    case, _ = record_b
    out = tmp_path / "fit.json"
    assert main(["fit", str(case.path), "--model", "fixed,p1:nospring,r1",
                 "--json", str(out)]) == 0
    text = capsys.readouterr().out
    data = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"JSON has {c}"))
    assert data["initial_state"] == {"B1": "steady"}
    assert set(data["initial_states"]["B1"]) == {"p1.alpha", "p1.beta", "r1.psi",
                                                 "p1.alpha_dot", "p1.beta_dot", "r1.psi_dot"}
    p = data["parameters"]
    corr = np.array(data["correlation"])
    assert corr.shape == (len(data["covariance"]["parameters"]),) * 2
    assert np.all(np.abs(corr) <= 1.0)
    assert all(v["stderr"] is None or v["stderr"] > 0 for v in p.values() if v["estimated"])
    assert all(("at_bound" in v) == (v["stderr"] is None) for v in p.values() if v["estimated"])
    # the fixed mass's inertias are 0 in the truth: an estimate at its 0 bound is reported as
    # such, with a one-sided limit and no Wald interval
    at_zero = [n for n in ("fixed.inertia", "fixed.axial_inertia")
               if p[n].get("at_bound") == "lower"]
    assert at_zero, {n: p[n] for n in ("fixed.inertia", "fixed.axial_inertia")}
    for n in at_zero:
        assert n not in data["covariance"]["parameters"]
        assert re.search(rf"{re.escape(n)} .* at its lower bound 0 \(one-sided 95 %: <= ", text), text


@pytest.mark.slow
def test_b_diagnose_names_the_hidden_rotor_from_a_steady_start(record_b):
    from estimate import diagnose

    case, _ = record_b
    d = diagnose(case)
    assert [f.cause for f in d.findings][:1] == ["rotor"], d.rounds
