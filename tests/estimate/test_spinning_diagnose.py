"""Diagnosis on the spinning rig: six-axis data from the independent reference simulator
(pendulum + rotor) and a pendulum-only baseline; the diagnosis must name the rotor."""

import pytest

import reference_spinning as rs
from estimate import diagnose
from synthetic_cases import make_spinning_case

#: Rotor parameters within 10 % (issue 7 acceptance) once the rotor is added.
PARAM = 0.10

RIG = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06,
             nutation_frequency=0.3, dry_mass=2.0)
PEND = rs.SphericalPendulum(1.25, 0.062, 0.035, damping=0.0005)


@pytest.mark.slow
@pytest.mark.xfail(reason="the pendulum-only baseline on six channels lands in a poor local "
                          "minimum (fixed-mass inertia runs away, scaled RMS 0.63), so the rotor "
                          "candidate gains nothing; open work", strict=False)
def test_rotor_hidden_in_spinning_data_is_named_with_evidence(tmp_path):
    rotor = rs.Rotor(0.01, 0.04, axis="y")
    case, _ = make_spinning_case(tmp_path, "R1", RIG, pendulum=PEND, rotor=rotor, fixed_mass=1.5,
                                 noise=0.015, seed=5, tank_radius=0.1016, duration=20.0)
    d = diagnose(case)
    assert [f.cause for f in d.findings][:1] == ["rotor"], [r for r in d.rounds]
    finding = d.findings[0]
    assert finding.added == ("r1",)
    assert "torque" in finding.evidence and "held-out" in finding.evidence
    assert finding.gain > 0.10
    final = {k: v["value"] for k, v in d.to_dict()["final"]["parameters"].items()}
    assert final["r1.inertia"] == pytest.approx(rotor.inertia, rel=PARAM)
    assert final["r1.damping"] == pytest.approx(rotor.damping, rel=PARAM)
    assert d.baseline_evidence.channel_share  # where the baseline's residual was
