"""The first stage's linear model: the projected residual's exact Jacobian and the lag
profile evaluated for every lag at once, against independent references (central
differences of the residual; the per-lag least-squares fit by SVD)."""

import math

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from estimate.fitting import first_stage_model as fm


def _records():
    """Two records with a mode-like response, a lag off the sample grid, a dropped span."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 20.0, 0.01)
    a = np.sin(2 * np.pi * 1.3 * t) * np.minimum(t / 2, 1.0) + 0.1 * rng.standard_normal(t.size)
    a = np.convolve(a, np.ones(20) / 20, "same")
    F = 3.0 * a + 0.5 * np.sin(2 * np.pi * 2.1 * t) + 0.01 * rng.standard_normal(t.size)
    w = np.ones(t.size)
    w[700:760] = 0.0
    return [fm._prepared(t, CubicSpline(t, a), F, None, 8.0),
            fm._prepared(t, CubicSpline(t, 0.7 * a), 0.6 * F, w, 8.0)]


@pytest.mark.parametrize("lags", [(0.0123, -0.0137), (0.0031, 0.0457)])
def test_the_projected_jacobian_is_exact(lags):
    """Golub-Pereyra's Jacobian (both terms) equals central differences of the projected
    residual. Step 1e-6 in log frequency, log damping and lag [s]: the differences' error
    is ~1e-10 relative (truncation h^2 and rounding 1e-16/h); lags off the sample grid,
    where the held ends make the residual smooth."""
    recs = _records()
    for rec in (recs[:1], recs[1:], recs):
        x = np.r_[math.log(2 * math.pi * 2.0), math.log(0.03), lags[:len(rec)]]
        J = fm._projected_jacobian(rec, x)
        h = 1e-6
        Jn = np.column_stack([(fm._projected(rec, x + h * e)[0] - fm._projected(rec, x - h * e)[0])
                              / (2 * h) for e in np.eye(x.size)])
        scale = np.abs(Jn).max(axis=0)
        assert np.all(np.abs(J - Jn).max(axis=0) <= 1e-6 * scale), np.abs(J - Jn).max(axis=0) / scale


def test_the_projected_masses_are_least_squares():
    """The masses from the scaled normal equations equal an SVD least-squares fit
    (``numpy.linalg.lstsq``) of the stacked design to 1e-9 relative."""
    recs = _records()
    x = np.r_[math.log(2 * math.pi * 1.7), math.log(0.05), 0.01, -0.02]
    X, F, _ = fm._stacked(recs, x)
    reference, *_ = np.linalg.lstsq(X, F, rcond=None)
    r, beta = fm._projected(recs, x)
    assert beta == pytest.approx(reference, rel=1e-9)
    assert r == pytest.approx(F - X @ reference, abs=1e-9 * np.abs(F).max())


def test_the_lag_profile_is_the_per_lag_minimum():
    """The lag profile (every lag of the grid in one filter) picks the grid lag whose own
    least-squares fit (one record, SVD) has the smallest residual among positive masses."""
    recs = _records()
    x0 = np.r_[math.log(2 * math.pi * 2.1), math.log(0.01), 0.0, 0.0]
    grid = np.arange(fm.LAG_RANGE[0], fm.LAG_RANGE[1] + 0.5 * fm.LAG_GRID_STEP, fm.LAG_GRID_STEP)
    picked = fm._lag_profile(recs, x0)
    for i, rec in enumerate(recs):
        costs = []
        for tau in grid:
            X, F, _ = fm._stacked([rec], np.r_[x0[:2], tau])
            beta, *_ = np.linalg.lstsq(X, F, rcond=None)
            r = F - X @ beta
            costs.append(float(r @ r) if beta[0] > 0 and beta[1] > 0 else math.inf)
        assert picked[i] == pytest.approx(grid[int(np.argmin(costs))], abs=1e-12)


def test_the_note_does_not_give_the_noise_only_lag_error_as_an_interval():
    """The first stage's lag standard error is the force noise's alone (a linear mode's
    misfit of a real record is not in it: on bench_fit's 0.2 mm chirp the stage put a lag
    of 7.2 ms where there is none, to 0.03 ms): the note names it so, with its digits,
    and gives no "+/-" interval."""
    from estimate.fitting.identification import FirstStage, StartOutcome

    best = StartOutcome(2.09, 2.12, 0.0095, (0.0072,), 2.03, 1.18, 0.0)
    stage = FirstStage(frequency_hz=2.12, damping_ratio=0.0095, rigid_mass=2.03,
                       slosh_mass=1.18, lags=(0.0072,), lag_stderr=(3.1e-5,), starts=(best,))
    text = stage.describe()
    assert "force stream lag 7.2 ms (standard error 0.031 ms at the force noise alone)" in text
    assert "+/-" not in text
