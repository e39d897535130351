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
def test_a_long_spinning_record_is_fitted_from_its_first_part(tmp_path):
    """The 60 s, 100 Hz spinning-rig record (pendulum and rotor, six channels) of
    ``test_spinning_fit``'s rig: its fit from the first stage diverges and crashed in the
    covariance (the 20 s record's converges once solved again with the rotor's RK4 bound;
    here that retry does not converge either). Now it is fitted on its first 20 s, then on
    the whole record from there (27 + 24 + 3 iterations measured before that retry
    existed), and converges to the truth: the pendulum within 1 %, the rotor within 5 % (its
    tolerances in ``test_spinning_fit``: 5 and 10 %)."""
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
    assert res.converged, res.status
    assert any("first 2000 samples" in n and "Invalid_Number_Detected" in n
               for n in res.problem.notes), res.problem.notes
    v = dict(zip(res.names, res.values))
    assert v["p1.mass"] == pytest.approx(PEND.mass, rel=0.01)
    assert v["p1.length"] == pytest.approx(PEND.length, rel=0.01)
    assert v["r1.inertia"] == pytest.approx(ROTOR.inertia, rel=0.05)
    assert v["r1.damping"] == pytest.approx(ROTOR.damping, rel=0.05)


def test_the_first_part_of_a_problem(tmp_path):
    """A third of a 3,001-sample record (1,000 samples) with its weights, the model and
    estimates unchanged; none for a record shorter than 2,000 samples or whose carriage
    motion is estimated (its spline covers the whole record)."""
    import reference_models as ref
    from synthetic_cases import rig_record

    from estimate import FitProblem, model_from_spec
    from estimate.fitting.segment_start import first_part

    case, _, _ = rig_record(tmp_path, "r", lambda f1: ref.Sine(0.002, 0.9 * f1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = model_from_spec("fixed,p1", case)
        filtered = FitProblem.build(case, model, input="filtered")
        estimated = FitProblem.build(case, model, input="estimated")
    assert case.time.size == 3001
    short, what = first_part(filtered)
    assert what == "the first 1000 samples (9.99 s)"
    x = short.experiments[0]
    assert x.case.time.size == x.case.force.size == x.case.displacement.size == 1000
    np.testing.assert_array_equal(x.case.force, case.force[:1000])
    assert short.estimated == filtered.estimated and short.names == filtered.names
    assert all(w is None or w.size == 1000 for w in short.weights)
    assert first_part(estimated) is None
    assert first_part(short) is None
