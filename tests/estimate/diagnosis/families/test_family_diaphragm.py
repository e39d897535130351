"""The diaphragm family (``estimate.diagnosis.families.diaphragm``) on 15 s chirps of the
independent reference simulator: a hinge spring raising the first mode's frequency by 15 %
(the length as predicted, 10 % less slosh mass) is proposed because the fitted frequency is
off the free-surface prediction, and its fit (length held within 1 % of the prediction)
recovers the stiffness; the clean chirp (frequency 1.5 % from the prediction, no diaphragm
in the case file) proposes no spring.

Tolerance: stiffness and mass within 20 % (a 15 s chirp; the slow suite's 30 s records are
held to 10 %)."""

import pytest
import reference_diagnosis_records as R
from diagnosis_checks import run_family

M, L, RAISE = 0.9 * 1.338, 0.057, 0.15


def test_diaphragm_spring_is_proposed_and_recovered(tmp_path):
    p = R.spring_mode(M, L, RAISE, 0.05)
    case, _ = R.write(R.short("diaphragm", R.SHORT_SWEEP, (p,), seed=74), tmp_path, "diaphragm")
    run = run_family(case, "diaphragm_stiffness")
    assert run.proposed
    assert run.fit.converged, run.fit.status
    assert run.fit.value("p1.stiffness") == pytest.approx(p.stiffness, rel=0.2)
    assert run.fit.value("p1.mass") == pytest.approx(M, rel=0.2)


def test_no_spring_is_proposed_on_a_clean_chirp(clean_sweep):
    run = run_family(clean_sweep, "diaphragm_stiffness", fit=False)
    assert not run.proposed
