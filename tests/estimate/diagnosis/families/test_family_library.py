"""The hinge-torque library (``estimate.diagnosis.families.library``) on 15 s amplitude
steps of the independent reference simulator: an asymmetric hinge spring (torque
0.13 theta^2, no named family is even in the angle) makes ``angle_squared`` the best-scoring
library term, and its fit recovers the coefficient; the clean record has no significant
library term.

Tolerance: 20 % on the coefficient (15 s, three amplitude steps)."""

import pytest
import reference_diagnosis_records as R
import reference_models as ref
from diagnosis_checks import run_family

K2 = 0.13


def test_asymmetric_spring_is_the_best_library_term(tmp_path):
    P = R.P60
    p = ref.Pendulum(P.mass, P.length, P.stiffness, P.damping, extra=lambda th, thd: K2 * th**2)
    case, _ = R.write(R.short("asymmetric", R.SHORT_STEPS, (p,), seed=76), tmp_path, "asym")
    run = run_family(case, "hinge_torque")
    assert run.proposed, [(s.term.label, s.statistic) for s in run.scores]
    assert run.proposals[0].added == ("p1:torque_angle_squared",)
    assert run.fit.converged, run.fit.status
    assert run.fit.value("p1.torque_angle_squared") == pytest.approx(K2, rel=0.2)


def test_no_library_term_on_a_clean_record(clean_steps):
    run = run_family(clean_steps, "hinge_torque", fit=False)
    assert not run.proposed, [(s.term.label, s.statistic) for s in run.scores]
