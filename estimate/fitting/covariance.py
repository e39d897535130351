"""Uncertainty of the estimates: the residual sensitivity reduced to the parameters, and
the Gauss-Newton covariance, correlations and identifiability it gives."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .identifiability import Identifiability, analyse

__all__ = ["Uncertainty", "reduced_jacobian", "gauss_newton"]


def reduced_jacobian(jac_residuals: ca.DM, jac_constraints: ca.DM, ntheta: int,
                     scales: np.ndarray, extra: list[int] = ()) -> np.ndarray:
    """Total derivative of the residuals w.r.t. the (unscaled) estimates.

    The states ``z`` depend on the parameters through the constraints ``g(theta, z) = 0``:
    ``dz/dtheta = -g_z^-1 g_theta`` and ``dr/dtheta = r_theta + r_z dz/dtheta`` (sparse
    solve). Free initial states (columns ``extra`` of the decision vector) count as
    parameters; their columns follow the estimates' in the returned Jacobian.
    """
    import scipy.sparse.linalg as spla

    Jr = jac_residuals.sparse().tocsc()
    Jg = jac_constraints.sparse().tocsc()
    pcols = list(range(ntheta)) + list(extra)
    zcols = np.setdiff1d(np.arange(Jr.shape[1]), pcols)
    R_p = Jr[:, pcols].toarray()
    if Jg.shape[0]:
        dz = -spla.splu(Jg[:, zcols].tocsc()).solve(Jg[:, pcols].toarray())
        J = R_p + Jr[:, zcols] @ dz
    else:
        J = R_p
    col_scale = np.concatenate([scales, np.ones(len(extra))])
    return np.asarray(J) / col_scale[None, :]


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of the estimates (their units squared), standard errors, correlations,
    the residual variance ``sigma2`` and the identifiability analysis."""

    covariance: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    sigma2: float
    identifiability: Identifiability
    sensitivity: np.ndarray
    warnings: tuple[str, ...]


def gauss_newton(J: np.ndarray, residuals: np.ndarray, n: int, ntheta: int,
                 scales: np.ndarray, names: tuple[str, ...]) -> Uncertainty:
    """``sigma2 (J^T J)^-1`` with ``sigma2 = |r|^2 / (n - k)``; columns of ``J`` beyond
    ``ntheta`` (free initial states) are marginalised out."""
    k = J.shape[1]
    sigma2 = float(residuals @ residuals) / max(n - k, 1)
    JtJ = J.T @ J
    warnings = []
    try:
        cov = sigma2 * np.linalg.inv(JtJ)
        if not np.all(np.isfinite(cov)):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        cov = sigma2 * np.linalg.pinv(JtJ)
        warnings.append("the residual sensitivity is singular: covariance from a pseudo-inverse")
    cov = cov[:ntheta, :ntheta]
    J = J[:, :ntheta]
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.clip(np.nan_to_num(cov / np.outer(d, d)), -1.0, 1.0)
    ident = analyse(J, scales, names, sigma2, corr)
    return Uncertainty(cov, d, corr, sigma2, ident, J, tuple(warnings))
