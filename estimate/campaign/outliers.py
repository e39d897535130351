"""Records that disagree with their group beyond their uncertainties.

Each record's estimates (shared parameters and derived quantities) are compared with the
inverse-variance combination of the *other* records of its group:
``z = (x - x_others) / sqrt(se^2 + se_others^2)``. Leaving the record out keeps an outlier
from pulling the reference towards itself; removing the worst record before looking again
(iteratively) keeps it from making its neighbours look wrong.

The threshold is Bonferroni's for a 5 % family-wise error over every comparison of the
campaign (records x quantities): ``z* = Phi^-1(1 - 0.05 / (2 m))``, 3.3 standard errors
for the 48 comparisons of a 12-record campaign with four quantities each. A group needs
three or more converged records: with two, which one is wrong cannot be told.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from scipy.stats import norm

__all__ = ["FAMILY_ERROR", "MIN_RECORDS", "Outlier", "find_outliers"]

#: Family-wise probability of flagging a record of an honest campaign.
FAMILY_ERROR = 0.05
#: Records (converged) a group needs before its records are compared.
MIN_RECORDS = 3


@dataclass(frozen=True)
class Outlier:
    """The ``record`` flagged against its ``group``, with one of its ``reasons`` per quantity
    beyond ``z*``."""

    record: str
    group: str
    reasons: tuple[str, ...]


def _estimates(outcome: Mapping[str, Any]) -> dict[str, tuple[float, float]]:
    out = {}
    for table in ("parameters", "derived"):
        for name, (v, se, *_rest) in outcome.get(table, {}).items():
            if math.isfinite(v) and math.isfinite(se) and se > 0:
                out[name] = (v, se)
    return out


def _z_scores(members: Mapping[str, dict[str, tuple[float, float]]], record: str
              ) -> dict[str, tuple[float, float, float]]:
    """Per quantity: ``(z, x, combined others)`` of ``record`` against the others."""
    out = {}
    for q, (x, se) in members[record].items():
        others = [m[q] for r, m in members.items() if r != record and q in m]
        if len(others) < MIN_RECORDS - 1:
            continue
        w = [1 / s**2 for _, s in others]
        mean = sum(wi * v for wi, (v, _) in zip(w, others)) / sum(w)
        out[q] = ((x - mean) / math.sqrt(se**2 + 1 / sum(w)), x, mean)
    return out


def find_outliers(groups: Sequence[tuple[str, Sequence[str]]],
                  outcomes: Mapping[str, Mapping[str, Any]]) -> tuple[list[Outlier], float]:
    """Flag outliers in every group.

    Parameters
    ----------
    groups : sequence of (str, sequence of str)
        Group names and their record ids.
    outcomes : mapping
        Fit outcome of each record id (:func:`estimate.campaign.tasks.run_task`); records
        that did not converge are not compared.

    Returns
    -------
    outliers : list of Outlier
        In group order, worst first within a group.
    threshold : float
        The ``z*`` used (standard errors).
    """
    tables = {}
    for name, ids in groups:
        members = {r: _estimates(outcomes[r]) for r in ids
                   if r in outcomes and outcomes[r].get("status") == "ok"}
        if len(members) >= MIN_RECORDS:
            tables[name] = members
    m = sum(len(_z_scores(members, r)) for members in tables.values() for r in members)
    threshold = float(norm.ppf(1 - FAMILY_ERROR / (2 * max(m, 1))))
    found = []
    for name, members in tables.items():
        members = dict(members)
        while len(members) >= MIN_RECORDS:
            scores = {r: _z_scores(members, r) for r in members}
            worst = max(sorted(scores), key=lambda r: max((abs(z) for z, _, _ in
                                                           scores[r].values()), default=0.0))
            beyond = {q: s for q, s in scores[worst].items() if abs(s[0]) > threshold}
            if not beyond:
                break
            found.append(Outlier(worst, name, tuple(
                f"{q} = {x:.5g} against {mean:.5g} from the other records ({z:+.1f} standard "
                "errors)" for q, (z, x, mean) in sorted(beyond.items(), key=lambda i: -abs(i[1][0])))))
            del members[worst]
    return found, threshold
