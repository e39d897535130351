"""A fit that diverges (IPOPT's ``Invalid_Number_Detected``) is a result that says so, not
a crash: a 60 s spinning-rig record's fit overflowed its simulation at iteration 26, and
SuperLU then raised "Factor is exactly singular" on the covariance's KKT matrix of
infinities."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sps

from estimate.fitting.covariance import uncertainty


def test_the_uncertainty_where_the_sensitivities_are_not_numbers():
    """Infinite and NaN Jacobian entries (a diverged simulation): no covariance, every
    standard error NaN, a warning that says why; the same finite problem has one."""
    rng = np.random.default_rng(0)
    Je = sps.csc_matrix(rng.normal(size=(40, 5)))
    Jg = sps.csc_matrix(np.hstack([np.zeros((2, 3)), np.eye(2)]))
    e = rng.normal(size=40)
    scales = np.ones(3)
    names = ("a", "b", "c")
    ok = uncertainty(Je, Jg, e, 40, 3, scales, names)
    assert np.all(np.isfinite(ok.stderr))
    bad = Je.toarray()
    bad[3, 1], bad[7, 4] = np.inf, np.nan
    unc = uncertainty(sps.csc_matrix(bad), Jg, e, 40, 3, scales, names)
    assert np.all(np.isnan(unc.stderr)) and np.all(np.isnan(unc.covariance))
    assert any("not finite" in w and "diverged" in w for w in unc.warnings)


@pytest.mark.slow
def test_a_long_spinning_record_whose_fit_diverges(tmp_path):
    """The 60 s, 100 Hz spinning-rig record (pendulum and rotor, six channels) of
    ``test_spinning_fit``'s rig: its fit from the first stage diverges (the 20 s record's
    converges). The fit returns, not converged, at the last iterate where the model was
    finite (27 iterations, 29 s measured), with finite estimates."""
    from synthetic_cases import make_spinning_case
    from test_spinning_fit import PEND, RIG, ROTOR

    from estimate import FitProblem, fit, model_from_spec

    case, _ = make_spinning_case(tmp_path, "S60", RIG, pendulum=PEND, rotor=ROTOR,
                                 fixed_mass=1.5, noise=0.01, seed=3, tank_radius=0.1016,
                                 duration=60.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prob = FitProblem.build(case, model_from_spec("fixed,p1:nospring,r1", case),
                                hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0})
        res = fit(prob, progress=False)
    assert not res.converged and res.status == "Invalid_Number_Detected"
    assert np.all(np.isfinite(res.values))
