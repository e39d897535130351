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
    """Singular values of the scaled sensitivity, condition number and confounded groups.

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


def analyse(J: np.ndarray, scales: np.ndarray, names: tuple[str, ...], sigma2: float,
            correlation: np.ndarray | None = None) -> Identifiability:
    """Analyse the residual Jacobian ``J`` (residuals x parameters, unscaled units) with
    parameter ``scales`` and residual variance ``sigma2``.

    A group is reported when a singular direction of the scaled sensitivity has a relative
    standard deviation above :data:`WEAK_RELATIVE_STD`, or when two estimates correlate
    beyond :data:`CONFOUNDED_CORRELATION`.
    """
    Js = J * scales[None, :]
    if Js.size == 0:
        return Identifiability(np.zeros(0), 1.0, (), ())

    _, s, Vt = np.linalg.svd(Js, full_matrices=False)
    smax = s[0] if s.size else 1.0
    cond = float(smax / s[-1]) if s[-1] > 0 else float("inf")
    groups, stds = [], []
    for i in range(s.size):
        std = float(np.sqrt(sigma2) / s[i]) if s[i] > 0 else float("inf")
        if std <= WEAK_RELATIVE_STD:
            continue
        v = Vt[i] ** 2
        members = tuple(names[j] for j in np.argsort(-v) if v[j] >= GROUP_SHARE)
        if len(members) > 1:
            groups.append(members)
            stds.append(f"relative standard deviation {std:.2g} along their joint direction")
    if correlation is not None:
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                pair = (names[i], names[j])
                if abs(correlation[i, j]) > CONFOUNDED_CORRELATION and not any(
                        set(pair) <= set(gr) for gr in groups):
                    groups.append(pair)
                    stds.append(f"correlation {correlation[i, j]:+.4f}")
    return Identifiability(s, cond, tuple(groups), tuple(stds))
