"""The sensor delay's linearised profile (``estimate.diagnosis.families.delay.delay_profile``):
on a record of the independent reference simulator whose force is recorded 30 ms late, the
profile linearised at the fit without delay has its minimum at the simulated delay, and
the objective reduction it predicts there agrees with an actual fit at that delay.

Tolerances: the delay within 1 ms (a tenth of the 10 ms sample interval; the fitted delay
of the old nine-fit profile search agreed with the simulated one to 0.2 ms); the predicted
reduction within 5 % of the fitted one (one Gauss-Newton step from a fit 30 ms off: the
remaining objective itself is predicted only to a factor of ~3, the profile serves to
place the fit)."""

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import make_case, pendulum

from estimate.diagnosis.families.delay import delay_profile
from estimate.diagnosis.fitter import Fitter
from estimate.diagnosis.scoring import holdout_weights
from estimate.diagnosis.search import baseline_model, force_cutoff
from estimate.fitting.linearise import linearise
from estimate.fitting.measurement import SensorDelay


def test_linearised_delay_profile_finds_the_simulated_delay(tmp_path):
    case, _ = make_case(tmp_path, "late", ref.LinearSweep(0.003, 1.0, 4.0, 30.0),
                        pendulums=[pendulum(1.30, 0.0553, 0.01)], seed=17, sensor_delay=0.03)
    fitter = Fitter([case], [holdout_weights(case.time.size)], "estimated", force_cutoff([case]))
    model = baseline_model(case)
    base = fitter(model, (), {})
    lin = linearise(fitter.problem(model, (), dict(zip(base.names, base.values))),
                    warm_start=base)
    assert lin.objectives(lin.residuals[:, None], base.names)[0] == pytest.approx(
        lin.objective - lin.score(base.names)[0], rel=1e-6)
    grid = np.arange(0.0, 0.1 + 1e-9, 5e-4)
    prof = delay_profile(base, lin, base.measured, grid)
    assert prof.best == pytest.approx(0.03, abs=1e-3)
    at = fitter(model, (SensorDelay(round(prof.best, 5)),), dict(zip(base.names, base.values)),
                warm=base)
    assert at.converged
    assert prof.reduction == pytest.approx(base.objective - at.objective, rel=0.05)
