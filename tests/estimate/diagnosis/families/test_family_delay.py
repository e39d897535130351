"""The sensor-delay family (``estimate.diagnosis.families.delay``) on 15 s chirps of the
independent reference simulator: a force recorded 30 ms late is proposed (the residual
correlates with dF/dt), placed by the linearised profile and refitted to the delay; on the
clean chirp the profile predicts no significant reduction and no delay is proposed, saying
why.

Tolerance: the delay within 1 ms (a tenth of the sample interval)."""

import pytest
import reference_diagnosis_records as R
from diagnosis_checks import run_family

from estimate.fitting.measurement import SensorDelay

TAU = 0.03


def test_delay_is_proposed_and_recovered(tmp_path):
    case, _ = R.write(R.short("late", R.SHORT_SWEEP, seed=75, sensor_delay=TAU), tmp_path, "late")
    run = run_family(case, "sensor_delay")
    assert run.proposed
    assert run.fit.converged, run.fit.status
    (delay,) = [m.delay for m in run.fit.problem.measurement if isinstance(m, SensorDelay)]
    assert delay == pytest.approx(TAU, abs=1e-3)


def test_no_delay_is_proposed_on_a_clean_chirp(clean_sweep):
    from estimate.diagnosis.families import family

    run = run_family(clean_sweep, "sensor_delay", fit=False)
    assert not run.proposed
    why = family("sensor_delay").why_not(run.context)
    assert "the objective's profile over the delay predicts" in why, why
