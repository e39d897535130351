"""How the diagnosis report writes what it found (new-user report, defect 14): a candidate
that was not fitted shows no gain or BIC change, a trend within the noise is called none,
and the parameter tables say what each fit was fitted on. Wording only: no fit is made."""

from types import SimpleNamespace

import numpy as np
import pytest

from estimate.diagnosis.evidence import SIGNIFICANT_T, Trend
from estimate.diagnosis.outcome import CandidateOutcome
from estimate.diagnosis.report import _candidate_row, _fitted_on
from estimate.diagnosis.scoring import HELD_OUT_BLOCKS, HOLDOUT_BLOCKS, holdout_weights


def _cells(row: str) -> list[str]:
    return [c.strip() for c in row.strip("|").split("|")]


@pytest.mark.parametrize("why", [
    "not tried: the objective's profile over the delay predicts no reduction",
    "screened: the step points to `rig.friction_coulomb` = -0.00213, which is not physical"])
def test_a_candidate_not_fitted_has_no_gain_and_no_bic_change(why):
    c = CandidateOutcome.not_fitted("sensor_delay", ("sensor_delay",), None, 0.06, why,
                                    score=float("-inf"))
    cells = _cells(_candidate_row(1, c, accepted=False))
    assert cells == ["1", "sensor_delay", "sensor_delay", "-", "-", why]


def test_a_fitted_candidate_shows_its_gain_and_bic_change():
    c = CandidateOutcome("slosh_mode", ("p2",), 0.216, None, rms_after=0.1, gain=0.538,
                         bic_change=-36020.4, heldout_chi2=900.0)
    assert _cells(_candidate_row(1, c, accepted=True)) == ["1", "slosh_mode", "p2", "53.8 %",
                                                           "-36020", "accepted"]
    tiny = CandidateOutcome("sensor_offset", ("rig.force_offset",), 0.06, None, rms_after=0.06,
                            gain=-0.0004, bic_change=-0.3, heldout_chi2=0.1,
                            rejected="held-out chi-square fell by 0.1")
    assert _cells(_candidate_row(2, tiny, accepted=False))[3:5] == ["0.0 %", "+0"]


def _trend(quantity, values, slope, se):
    return Trend(quantity, (0.37, 0.45), values, slope, se)


def test_a_trend_within_the_noise_is_called_none():
    """A1's null trends read 'frequency falls -0.0 %' and 'damping ratio falls x1.00'."""
    f = _trend("frequency", (2.11964, 2.11946), -0.00217, 0.0047).text()
    z = _trend("damping ratio", (0.010022, 0.009979), -0.00053, 0.0021).text()
    assert f == ("frequency: no significant change (-0.0085 %) from 0.37 rad to 0.45 rad swing "
                 "(slope 0.5 standard errors)")
    assert z.startswith("damping ratio: no significant change (-0.43 %) from 0.37 rad")
    for text in (f, z):
        assert "falls" not in text and "-0.0 %" not in text and "x1.00" not in text


def test_a_trend_says_which_way_and_by_how_much():
    assert _trend("damping ratio", (0.01, 0.005), -0.02, 0.003).text().startswith(
        "damping ratio falls x0.50 from 0.37 rad to 0.45 rad swing (slope 6.7 standard errors)")
    assert _trend("frequency", (2.0, 1.97), -0.1, 0.01).text().startswith("frequency falls 1.5 % ")
    assert _trend("frequency", (2.0, 2.03), 0.1, 0.01).text().startswith("frequency rises 1.5 % ")
    # the threshold: exactly SIGNIFICANT_T standard errors is a trend
    assert "rises" in _trend("frequency", (2.0, 2.03), SIGNIFICANT_T, 1.0).text()


def _fit(weights, left_out=None):
    """A fit result as far as `_fitted_on` reads it: its weights and its problem's held-out
    samples (weight 0, not left out as clipped or spikes)."""
    from estimate.fitting.problem import FitProblem

    n = 3001 if weights is None else weights[0].size
    case = SimpleNamespace(time=np.zeros(n))
    problem = SimpleNamespace(experiments=(SimpleNamespace(case=case),), weights=weights,
                              left_out=() if left_out is None else (left_out,))
    problem.held_out = lambda i, w=None: FitProblem.held_out(problem, i, w)
    return SimpleNamespace(weights=weights, problem=problem)


def test_the_parameter_tables_say_what_each_fit_was_fitted_on():
    n = 3001
    baseline = _fit((holdout_weights(n),))
    assert int(np.sum(baseline.weights[0] == 0)) == pytest.approx(
        n * len(HELD_OUT_BLOCKS) / HOLDOUT_BLOCKS, abs=len(HELD_OUT_BLOCKS))
    assert _fitted_on(baseline) == ("7 of 10 interleaved blocks; the other 3 held out to score "
                                    "the candidates")
    assert _fitted_on(_fit(None)) == "every sample"
    assert _fitted_on(_fit((np.ones(n),))) == "every sample"
    # samples left out as clipped or spikes hold nothing out
    clipped = np.zeros(n, bool)
    clipped[100:140] = True
    assert _fitted_on(_fit((np.where(clipped, 0.0, 1.0),), clipped)) == "every sample"
