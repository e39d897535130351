"""The measurement families (``estimate.diagnosis.families.measurement``) one by one, on 15 s
chirps of the independent reference simulator (from rest with a ramp, force and
displacement noise, a motor tone): a transducer offset with drift, and rig friction seen by
the transducer, are each screened with a significant score on a record with the effect,
recovered by the family's fit, and not proposed on the clean chirp.

Tolerances: offset and drift within 3 of their standard errors (a correct interval misses
by that 0.3 % of the time; the drift, 0.15 N over the record, trades with the estimated
carriage motion's slow content, so its error is a few per cent); rig friction within 20 %
(its viscous and Coulomb parts are both in phase with the carriage velocity, so they
trade)."""

import pytest
import reference_diagnosis_records as R
import reference_models as ref
from diagnosis_checks import run_family

CASES = {
    "sensor_offset": ({"offset": 0.3, "drift": 0.01},
                      {"rig.force_offset": (0.3, None), "rig.force_drift": (0.01, None)}),
    "rig_friction": ({"friction": ref.Friction(coulomb=0.1, viscous=2.0)},
                     {"rig.friction_viscous": (2.0, 0.2), "rig.friction_coulomb": (0.1, 0.2)}),
}
#: Standard errors an offset or drift may be from the truth (``None`` tolerance above).
SE = 3.0


@pytest.mark.parametrize("cause", list(CASES))
def test_measurement_family_is_screened_and_recovers_its_effect(cause, tmp_path):
    effects, truth = CASES[cause]
    case, _ = R.write(R.short(cause, R.SHORT_SWEEP, seed=72, **effects), tmp_path, cause)
    run = run_family(case, cause)
    assert run.proposed, [(s.term.label, s.statistic, s.unphysical) for s in run.scores]
    assert run.fit.converged, run.fit.status
    fit = run.fit
    for name, (value, tol) in truth.items():
        if tol is None:
            se = fit.stderr[fit.names.index(name)]
            assert abs(fit.value(name) - value) <= SE * se, (name, fit.value(name), se)
        else:
            assert fit.value(name) == pytest.approx(value, rel=tol), name


@pytest.mark.parametrize("cause", list(CASES))
def test_measurement_family_is_not_proposed_on_a_clean_record(cause, clean_sweep):
    run = run_family(clean_sweep, cause, fit=False)
    assert not run.proposed, [(s.term.label, s.statistic, s.unphysical) for s in run.scores]


def test_an_offset_without_drift_is_a_plausible_sensor_offset(tmp_path):
    """A transducer offset that does not drift: the family's fit holds a drift not distinct
    from zero, and is still plausible (one of its parts at least is distinct), with the
    offset within 3 standard errors of the truth."""
    case, _ = R.write(R.short("offset_only", R.SHORT_SWEEP, seed=73, offset=0.3), tmp_path,
                      "offset_only")
    run = run_family(case, "sensor_offset")
    assert run.proposed, [(s.term.label, s.statistic, s.unphysical) for s in run.scores]
    fit = run.fit
    assert fit.converged, fit.status
    drift_se = fit.stderr[fit.names.index("rig.force_drift")]
    assert abs(fit.value("rig.force_drift")) < 3 * drift_se  # the drift is not resolved
    assert run.proposals[0].plausible(fit) is None
    se = fit.stderr[fit.names.index("rig.force_offset")]
    assert abs(fit.value("rig.force_offset") - 0.3) <= SE * se
