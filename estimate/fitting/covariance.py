"""Uncertainty of the estimates.

The Gauss-Newton covariance of an equality-constrained least-squares problem: with ``e``
the residuals (each divided by its scale), ``g(w) = 0`` the transcription's constraints and
``w`` all decision variables (parameters, states, carriage coefficients, free initial
states), the covariance of the parameters is ``s^2`` times their block of the inverse of
the KKT matrix ``[[J_e^T J_e, J_g^T], [J_g, 0]]``: the inverse of the information reduced to
the constraint manifold, with states eliminated and nuisance variables (carriage motion,
free initial states) marginalised. ``s^2 = |e|^2 / (n - k)`` is the residual variance (``k``
counts every estimated quantity). One sparse LDL^T factorisation, a solve per parameter.

The residual sensitivity to the parameters alone (states follow through the constraints,
nuisance variables held) is kept for the identifiability check and the diagnosis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .identifiability import Identifiability, analyse

__all__ = ["Uncertainty", "reduced_jacobian", "uncertainty"]


def reduced_jacobian(jac_residuals: sps.spmatrix, jac_constraints: sps.spmatrix, ntheta: int,
                     scales: np.ndarray, held: list[int] = ()) -> np.ndarray:
    """Total derivative of the residuals w.r.t. the (unscaled) estimates, the states
    following through ``g(theta, z) = 0``: ``dz/dtheta = -g_z^-1 g_theta`` and
    ``dr/dtheta = r_theta + r_z dz/dtheta``; the columns ``held`` (nuisance variables) are
    neither parameters nor states."""
    Jr = sps.csc_matrix(jac_residuals)
    Jg = sps.csc_matrix(jac_constraints)
    pcols = list(range(ntheta))
    zcols = np.setdiff1d(np.arange(Jr.shape[1]), pcols + list(held))
    R_p = Jr[:, pcols].toarray()
    if Jg.shape[0]:
        dz = -spla.splu(Jg[:, zcols].tocsc()).solve(Jg[:, pcols].toarray())
        J = R_p + Jr[:, zcols] @ dz
    else:
        J = R_p
    return np.asarray(J) / scales[None, :]


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of the estimates (their units squared), standard errors, correlations,
    the residual variance ``sigma2`` and the identifiability analysis."""

    covariance: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    sigma2: float
    identifiability: Identifiability
    warnings: tuple[str, ...]


def uncertainty(jac_residuals: sps.spmatrix, jac_constraints: sps.spmatrix,
                residuals: np.ndarray, n_observations: int, ntheta: int, scales: np.ndarray,
                names: tuple[str, ...]) -> Uncertainty:
    """The Gauss-Newton covariance of the first ``ntheta`` decision variables (scaled by
    ``scales``) from the sparse residual and constraint Jacobians at the optimum."""
    Je = sps.csc_matrix(jac_residuals)
    Jg = sps.csc_matrix(jac_constraints)
    nw, ng = Je.shape[1], Jg.shape[0]
    k = nw - ng  # estimated quantities: variables the constraints leave free
    sigma2 = float(residuals @ residuals) / max(n_observations - k, 1)
    H = (Je.T @ Je).tocsc()
    warnings = []
    X = _kkt_block(H, Jg, ntheta)
    if X is None:
        # directions the data do not determine: a ridge far below the information makes
        # the system solvable and gives them huge (not meaningless finite) variances
        ridge = 1e-10 * float(H.diagonal().max() or 1.0)
        X = _kkt_block((H + ridge * sps.identity(nw, format="csc")).tocsc(), Jg, ntheta)
        warnings.append("the residual sensitivity is singular: the data do not determine some "
                        "directions of the parameters (see the identifiability check)")
        if X is None:
            X = np.full((ntheta, ntheta), np.inf)
    X = 0.5 * (X + X.T)
    cov = sigma2 * X * np.outer(scales, scales)
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.clip(np.nan_to_num(cov / np.outer(d, d)), -1.0, 1.0)
    ident = analyse(cov, scales, names, corr)
    return Uncertainty(cov, d, corr, sigma2, ident, tuple(warnings))


def _kkt_block(H: sps.csc_matrix, Jg: sps.csc_matrix, ntheta: int) -> np.ndarray | None:
    """The first ``ntheta`` rows and columns of ``[[H, Jg^T], [Jg, 0]]^-1``, or ``None``
    when the matrix is singular.

    The matrix is made quasi-definite by ``+delta I`` and ``-eps I`` diagonal blocks far
    below its entries (1e-15 relative), which CasADi's sparse LDL^T factorises without
    pivoting; one step of iterative refinement on the unregularised matrix removes their
    effect, and a residual that stays large falls back to SuperLU's pivoted LU."""
    import casadi as ca

    from ._sparse import sparse_dm

    nw, ng = H.shape[0], Jg.shape[0]
    kkt = sps.bmat([[H, Jg.T], [Jg, None]], format="csc") if ng else H
    rhs = np.zeros((nw + ng, ntheta))
    rhs[np.arange(ntheta), np.arange(ntheta)] = 1.0
    scale = float(abs(H).max()) or 1.0
    reg = sps.diags(np.concatenate([np.full(nw, 1e-15 * scale), np.full(ng, -1e-15)]))
    K = sparse_dm((kkt + reg).tocsc())
    X = None
    try:
        solver = ca.Linsol("kkt", "ldl", K.sparsity())
        X = np.asarray(solver.solve(K, ca.DM(rhs)))
        X = X + np.asarray(solver.solve(K, ca.DM(rhs - kkt @ X)))  # refinement
        if not np.all(np.isfinite(X)) or np.max(np.abs(rhs - kkt @ X)) > 1e-8:
            X = None
    except RuntimeError:
        X = None
    if X is None:
        try:
            X = spla.splu(kkt).solve(rhs)
        except RuntimeError:
            return None
    X = X[:ntheta]
    if not np.all(np.isfinite(X)) or np.any(np.diag(X) < 0):
        return None
    return X
