"""The rows of each case in a fit's residual vector (``scoring.case_rows``), the one place
the diagnosis reads them (the slosh-mode scan, the delay profile and the spinning scans
used three different computations, and the mode scan's was wrong for every case after the
first: it skipped the first case's force rows but not its displacement rows).

Two 8 s records from the independent reference simulator, fitted together with the
estimated carriage motion (each case contributes force rows, then displacement rows): the
rows of case k of the linearisation's residual vector are case k's force residuals
divided by its force noise, exactly (to round-off), and the two cases' rows do not overlap
their displacement rows."""

import numpy as np
import reference_models as ref
from synthetic_cases import make_case, pendulum

from estimate.diagnosis.fitter import Fitter
from estimate.diagnosis.scoring import case_rows, holdout_weights
from estimate.diagnosis.search import baseline_model
from estimate.fitting.linearise import linearise


def test_case_rows_hold_each_cases_force_residuals(tmp_path):
    cases = [make_case(tmp_path, f"c{k}", ref.Ramped(ref.Sine(0.003, f), 1.0, 0.0),
                       pendulums=[pendulum(1.30, 0.0553, 0.01)], duration=8.0, seed=90 + k)[0]
             for k, f in enumerate((1.9, 2.3))]
    fitter = Fitter(cases, [holdout_weights(c.time.size) for c in cases], "estimated", None)
    model = baseline_model(cases[0])
    res = fitter(model, (), {})
    assert res.displacement_residuals[0] is not None  # the layout this test is about
    lin = linearise(fitter.problem(model, (), dict(zip(res.names, res.values))), warm_start=res)
    assert lin.residuals.size == res.sensitivity.shape[0]
    rows = [case_rows(res, k) for k in range(2)]
    assert rows[1].start == cases[0].time.size + res.displacement_residuals[0].size
    for k, r in enumerate(rows):
        scale = res.problem.channel_scales(k)["force_x"]
        expected = res.residuals[k] * res.weights[k] / scale
        np.testing.assert_allclose(lin.residuals[r], expected, rtol=1e-6,
                                   atol=1e-9 * np.max(np.abs(expected)))
