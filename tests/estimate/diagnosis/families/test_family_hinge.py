"""The hinge families (``estimate.diagnosis.families.hinge``) one by one, on 15 s records of
the independent reference simulator (from rest with a ramp, force and displacement noise, a
motor tone): each is screened with a significant score and physical sign on a record with
its effect, its fit recovers the effect, and it is not proposed on a clean record of the
same drive.

Tolerance: 20 % on the hinge parameter (a 15 s record of three amplitude steps; the full
30 s records of the slow suite are held to 15 %)."""

import pytest
import reference_diagnosis_records as R
import reference_models as ref
from diagnosis_checks import run_family
from synthetic_cases import G

TOL = 0.20
P = R.P60


def _with(**kw):
    return ref.Pendulum(P.mass, P.length, P.stiffness, P.damping, **kw)


def _quadratic(c2):
    return ref.Pendulum(P.mass, P.length, 0.0, ref.hinge_damping(P.mass, P.length, 0.002, gravity=G), c2)


CASES = {
    "nonlinear_damping": (_quadratic(2e-3), "p1.quadratic_damping", 2e-3),
    "dry_friction": (_with(coulomb=4e-4), "p1.coulomb_friction", 4e-4),
    "nonlinear_stiffness": (_with(cubic_stiffness=R.cubic_for(0.08, P.mass, P.length)),
                            "p1.cubic_stiffness", R.cubic_for(0.08, P.mass, P.length)),
}


@pytest.mark.parametrize("cause", list(CASES))
def test_hinge_family_is_screened_and_recovers_its_effect(cause, tmp_path):
    pendulum, name, truth = CASES[cause]
    case, _ = R.write(R.short(cause, R.SHORT_STEPS, (pendulum,), seed=71), tmp_path, cause)
    run = run_family(case, cause)
    assert run.proposed, [(s.term.label, s.statistic, s.unphysical) for s in run.scores]
    assert run.fit.converged, run.fit.status
    assert run.fit.value(name) == pytest.approx(truth, rel=TOL)


@pytest.mark.parametrize("cause", list(CASES))
def test_hinge_family_is_not_proposed_on_a_clean_record(cause, clean_steps):
    run = run_family(clean_steps, cause, fit=False)
    assert not run.proposed, [(s.term.label, s.statistic, s.unphysical) for s in run.scores]
