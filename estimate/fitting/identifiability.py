"""What the data can and cannot determine: weak directions of the residual sensitivity
and the parameter groups they confound."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Identifiability", "analyse"]

#: A direction is weakly identified when its standard deviation, in units of the
#: parameters' own scales (relative), exceeds this.
WEAK_RELATIVE_STD = 0.02
#: Pairs of estimates correlated beyond this are reported as confounded.
CONFOUNDED_CORRELATION = 0.99
#: Parameters taking at least this share of a weak direction belong to its group.
GROUP_SHARE = 0.25


@dataclass(frozen=True)
class Identifiability:
    """Singular values of the scaled sensitivity (up to the residual scale), condition
    number and confounded groups.

    ``groups`` lists tuples of parameter names that move together along a weakly
    determined direction; ``evidence`` says for each why (relative standard deviation
    along the direction, or the correlation of a pair).
    """

    singular_values: np.ndarray
    condition_number: float
    groups: tuple[tuple[str, ...], ...]
    evidence: tuple[str, ...]

    @property
    def identifiable(self) -> bool:
        return not self.groups


def analyse(covariance: np.ndarray, scales: np.ndarray, names: tuple[str, ...],
            correlation: np.ndarray | None = None) -> Identifiability:
    """Analyse the covariance of the estimates (their units squared) with parameter
    ``scales``: its eigen-directions in relative units are the singular directions of the
    scaled residual sensitivity, the square roots of its eigenvalues the relative standard
    deviations along them.

    A group is reported when a direction has a relative standard deviation above
    :data:`WEAK_RELATIVE_STD`, or when two estimates correlate beyond
    :data:`CONFOUNDED_CORRELATION`.
    """
    if covariance.size == 0:
        return Identifiability(np.zeros(0), 1.0, (), ())
    rel = covariance / np.outer(scales, scales)
    lam, V = np.linalg.eigh(0.5 * (rel + rel.T))
    lam = np.clip(lam, 0.0, None)
    stds = np.sqrt(lam)  # ascending: the best-determined direction first
    with np.errstate(divide="ignore"):
        # singular values of the scaled sensitivity are proportional to 1 / std
        s = np.where(stds > 0, 1.0 / stds, np.inf)[::-1]
    finite = s[np.isfinite(s)]
    cond = float(finite.max() / finite.min()) if finite.size and np.all(np.isfinite(s)) \
        else float("inf")
    groups, evidence = [], []
    for i in range(stds.size):
        if stds[i] <= WEAK_RELATIVE_STD:
            continue
        v = V[:, i] ** 2
        members = tuple(names[j] for j in np.argsort(-v) if v[j] >= GROUP_SHARE)
        if len(members) > 1:
            text = f"relative standard deviation {stds[i]:.2g} along their joint direction"
            same = next((k for k, g in enumerate(groups) if set(g) == set(members)), None)
            if same is not None:  # the same estimates along a weaker direction: said once,
                evidence[same] = text  # with the weakest (stds ascend)
                continue
            groups.append(members)
            evidence.append(text)
    if correlation is not None:
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                pair = (names[i], names[j])
                if abs(correlation[i, j]) > CONFOUNDED_CORRELATION and not any(
                        set(pair) <= set(gr) for gr in groups):
                    groups.append(pair)
                    evidence.append(f"correlation {correlation[i, j]:+.4f}")
    return Identifiability(s, cond, tuple(groups), tuple(evidence))
