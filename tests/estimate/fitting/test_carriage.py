"""The estimated carriage motion's spline: its values as a rig excitation agree with its
design matrices (the NLP's path) and with finite differences of its own displacement."""

from __future__ import annotations

import numpy as np
import pytest

from estimate.fitting.carriage import CarriageSpline, carriage_input


@pytest.fixture(scope="module")
def carriage():
    t = np.linspace(0.0, 10.0, 1001)
    ramp = np.clip(t / 1.5, 0, 1) ** 3 * (10 - 15 * np.clip(t / 1.5, 0, 1)
                                          + 6 * np.clip(t / 1.5, 0, 1) ** 2)
    x = 0.003 * ramp * np.sin(2 * np.pi * 1.8 * t)
    x += np.random.default_rng(1).normal(0, 2e-5, t.size)
    force = 2.0 * np.gradient(np.gradient(x, t), t) + np.random.default_rng(2).normal(0, 0.01,
                                                                                      t.size)
    ci, _ = carriage_input(t, x, force=force)
    return t, ci


def test_excitation_values_match_the_design_matrices(carriage):
    """Displacement, velocity and acceleration at the RK4 stage times: the spline evaluated
    directly equals the design matrices times the coefficients (round-off only)."""
    t, ci = carriage
    c = ci.coefficients
    stages = (t[:-1, None] + np.diff(t)[:, None] * np.array([0.0, 0.5, 1.0])[None, :]).ravel()
    values = ci.excitation(c).values(stages)
    for d in range(3):
        ref = ci.design(stages, d) @ c
        assert np.max(np.abs(values[d] - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_excitation_derivatives_match_finite_differences(carriage):
    """Velocity and acceleration are the derivatives of the displacement: central
    differences with a 1e-4 s step agree to 1e-6 of the signal (truncation error
    ~h^2 x''''/6 is far below)."""
    t, ci = carriage
    exc = ci.excitation(ci.coefficients)
    tt = np.linspace(0.5, 9.5, 97)
    h = 1e-4
    x_lo, x_mid, x_hi = (exc.values(tt + s)[0] for s in (-h, 0.0, h))
    v, a = exc.values(tt)[1:]
    assert np.max(np.abs((x_hi - x_lo) / (2 * h) - v)) < 1e-6 * np.max(np.abs(v))
    assert np.max(np.abs((x_hi - 2 * x_mid + x_lo) / h**2 - a)) < 1e-4 * np.max(np.abs(a))


def test_a_quiet_start_is_at_rest(carriage):
    """A record that starts quiet: the carriage velocity and acceleration at t[0] are zero
    for any coefficients (the rest basis)."""
    t, ci = carriage
    assert ci.at_rest
    c = np.random.default_rng(3).normal(size=ci.n_coefficients)
    _, v0, a0 = ci.excitation(c).values(t[:1])[:, 0]
    assert abs(v0) < 1e-9 * np.linalg.norm(c) and abs(a0) < 1e-7 * np.linalg.norm(c)


def test_covering_spline_spans_the_record_exactly():
    s = CarriageSpline.covering(0.3, 7.3, 0.045)
    k = s.degree
    assert s.knots[k] == 0.3 and s.knots[-k - 1] == 7.3
    assert s.spacing <= 0.045


@pytest.mark.parametrize("fractions", [(0.0, 0.5, 1.0), (0.155051, 0.644949, 1.0)])
def test_casadi_matrices_are_the_design_matrices(carriage, fractions):
    """The sparse CasADi matrices the NLP uses (stage inputs, grid inputs, grid
    displacement) equal the SciPy design matrices, whether the grid rows are sliced from the
    stage matrix (RK4 stages include both interval ends) or built on their own (Radau)."""
    t, ci = carriage
    fr = np.asarray(fractions)
    A_stage, A_grid, B0 = ci.casadi_matrices(t, fr)
    stages = (t[:-1, None] + np.diff(t)[:, None] * fr[None, :]).ravel()
    for dm, ref in ((A_stage, ci.inputs_matrix(stages)), (A_grid, ci.inputs_matrix(t)),
                    (B0, ci.design(t))):
        got = dm.sparse()
        assert got.shape == ref.shape
        assert abs(got - ref).max() <= 1e-12 * abs(ref).max()


def test_shift_design_is_the_taylor_series_of_the_lagged_spline(carriage):
    """The lagged displacement's design held as one dense matrix on its pattern
    (:meth:`CarriageInput.shift_design`): its nonzeros times ``[1, lag, ..., lag^5]`` are
    the SciPy sum ``sum_d lag^d D_d`` of the spline's Taylor designs (round-off), and
    times the coefficients they give SciPy's B-spline ``lag`` later to the series'
    remainder (exact inside a knot span, 1e-4 of the motion where the lag crosses a knot:
    bounded here by 1e-3)."""
    import casadi as ca
    import scipy.sparse as sps
    from scipy.interpolate import BSpline

    t, ci = carriage
    lag = 0.02
    pattern, V = ci.shift_design(t, 5)
    nz = np.asarray(ca.evalf(ca.mtimes(V, ca.DM([lag ** d for d in range(6)])))).ravel()
    shifted = sps.csc_matrix((nz, np.array(pattern.row()), np.array(pattern.colind())),
                             shape=(pattern.size1(), pattern.size2()))
    reference = sum(lag ** d * D for d, D in enumerate(ci.taylor_designs(t, 5)))
    assert abs(shifted - reference).max() <= 1e-12 * abs(reference).max()
    c = ci.coefficients
    spline = BSpline(ci.spline.knots, c if ci.basis is None else ci.basis @ c,
                     ci.spline.degree)
    inside = (t + lag) <= t[-1]
    x = spline(t[inside] + lag)
    assert np.max(np.abs((shifted @ c)[inside] - x)) <= 1e-3 * np.max(np.abs(x))
