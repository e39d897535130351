"""Outliers: a record that disagrees with the other records of its group beyond their
uncertainties, and only that record."""

from __future__ import annotations

import math
from statistics import NormalDist

from estimate.campaign.outliers import find_outliers


def outcome(mass, se=0.01, freq=2.0, fse=0.001, status="ok"):
    return {"status": status, "parameters": {"p1.mass": [mass, se, 0, 0, "kg"]},
            "derived": {"p1.frequency_hz": [freq, fse, 0, 0, "Hz"]}}


def test_one_record_off_by_many_standard_errors_is_flagged_alone():
    outcomes = {"a": outcome(1.00), "b": outcome(1.01), "c": outcome(0.995), "d": outcome(1.005),
                "x": outcome(1.08)}
    found, z = find_outliers([("g", list(outcomes))], outcomes)
    # Bonferroni over 10 comparisons (5 records x 2 quantities), 5 % family-wise
    assert math.isclose(z, NormalDist().inv_cdf(1 - 0.05 / 20), rel_tol=1e-12)
    assert [o.record for o in found] == ["x"]
    # 1.08 against the others' mean 1.0025, combined error sqrt(0.01^2 + 0.01^2 / 4)
    assert "p1.mass = 1.08 against 1.0025" in found[0].reasons[0]
    assert f"{0.0775 / math.sqrt(1.25e-4):+.1f} standard errors" in found[0].reasons[0]
    assert len(found[0].reasons) == 1


def test_an_outlier_does_not_make_its_neighbours_look_wrong():
    # b is 2 standard errors from a and c; against the mean of all others (x included) it
    # is 25 below, but x goes first and b is then compared with a and c only
    outcomes = {"a": outcome(1.00, se=0.002), "b": outcome(1.005, se=0.002),
                "c": outcome(1.00, se=0.002), "x": outcome(1.2, se=0.002)}
    found, _ = find_outliers([("g", list(outcomes))], outcomes)
    assert [o.record for o in found] == ["x"]


def test_agreeing_records_small_groups_and_failed_fits_flag_nothing():
    honest = {"a": outcome(1.00), "b": outcome(1.01), "c": outcome(0.99)}
    pair = {"p": outcome(1.0), "q": outcome(2.0)}                       # cannot tell which
    failed = {"f1": outcome(1.0), "f2": outcome(1.0), "f3": outcome(5.0, status="failed")}
    found, _ = find_outliers([("h", list(honest)), ("p", list(pair)), ("f", list(failed))],
                             honest | pair | failed)
    assert found == []
