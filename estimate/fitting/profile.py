"""Profile-likelihood intervals: refit with one parameter held at trial values."""

from __future__ import annotations

import math

from scipy.optimize import brentq
from scipy.stats import chi2

from analogs.errors import UnknownNameError

from .nlp import fit
from .result import FitResult

__all__ = ["profile_interval"]


def profile_interval(result: FitResult, name: str, level: float = 0.95, *,
                     max_steps: int = 8) -> tuple[float, float]:
    """Profile-likelihood interval of the shared estimate ``name`` of the fit ``result``, at
    the confidence ``level`` (default 0.95), each side bracketed in at most ``max_steps``
    steps.

    The profile ``S(v) = min objective with name = v`` (the weighted least-squares objective
    of the fit, carriage motion included) is compared with ``S_hat + s^2 chi2_1(level)``
    (``s^2`` the residual variance of the fit). Every point is a full
    refit, warm-started at the estimates; each side is bracketed in steps of two standard
    errors and solved with Brent's method. Unlike the Wald interval it follows the
    nonlinearity of the model; like it, it assumes independent residuals.
    """
    problem = result.problem
    i = result.names.index(name) if name in result.names else None
    if i is None:
        raise UnknownNameError(f"{name!r} was not estimated; estimated: {', '.join(result.names)}")
    est = problem.estimated[i]
    threshold = result.objective + result.residual_variance * chi2.ppf(level, 1)
    start = {n: v for n, v in zip(result.names, result.values) if n != name}

    def excess(v: float) -> float:
        sub = problem.holding(name, v).with_initial(start)
        return fit(sub, progress=False).objective - threshold

    v_hat = float(result.values[i])
    se = float(result.stderr[i])
    if not math.isfinite(se):  # at a bound: the spread the data allow away from it
        se = float(result.bound_stderr[i]) if result.bound_stderr is not None else math.nan
    step = (2 * se if math.isfinite(se) else 0.0) or 0.01 * abs(v_hat) or est.scale * 0.01
    ends = []
    for sign in (-1, 1):
        inner, outer = v_hat, v_hat
        found = False
        for _ in range(max_steps):
            outer = inner + sign * step
            if outer <= est.lower or outer >= est.upper:
                outer = est.lower if sign < 0 else est.upper
                found = math.isfinite(outer) and excess(outer) > 0
                break
            if excess(outer) > 0:
                found = True
                break
            inner = outer
        if not found:
            ends.append(est.lower if sign < 0 else est.upper)
            continue
        ends.append(brentq(excess, min(inner, outer), max(inner, outer), xtol=1e-3 * step))
    return ends[0], ends[1]
