"""Factorisations of the KKT matrices of the fit's equality-constrained least squares:
``[[H, G^T], [G, 0]]`` over the states, multipliers and carriage coefficients of a shooting
problem (:class:`estimate.fitting.covariance.ReducedKKT` eliminates them with one)."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

__all__ = ["factorise", "DENSE_COLUMN_FACTOR", "DENSE_COLUMN_MIN", "QUASI_DEFINITE_DELTA",
           "REFINEMENT_STEPS", "REFINED_RESIDUAL"]


#: A column of a KKT matrix with more than this many times the median column's nonzeros,
#: and at least DENSE_COLUMN_MIN, is eliminated last, through a dense Schur complement, in
#: the fallback factorisation (:func:`_lu_with_dense_columns`).
DENSE_COLUMN_FACTOR = 20.0
DENSE_COLUMN_MIN = 1000
#: The quasi-definite regularisation of the scaled KKT matrix (+ on the primal block, - on
#: the constraints'), relative to its unit row maxima: small enough that iterative
#: refinement against the unregularised matrix converges on these ill-conditioned systems
#: (1e-11 left a residual 10 times SuperLU's on a 30,001-sample fit; 1e-12 to 1e-14 did not).
QUASI_DEFINITE_DELTA = 1e-13
#: Refinement steps, and the residual relative to the right-hand side above which the
#: fallback is used instead (a well-conditioned KKT refines to 1e-14).
REFINEMENT_STEPS = 3
REFINED_RESIDUAL = 1e-8


def factorise(K: sps.csc_matrix, n_primal: int | None = None):
    """A function ``B -> K^-1 B`` for a KKT matrix ``K = [[H, G^T], [G, 0]]`` whose first
    ``n_primal`` rows are the primal block (default: all).

    The matrix is scaled symmetrically (unit row maxima) and made quasi-definite (
    :data:`QUASI_DEFINITE_DELTA`), so a symmetric fill-reducing order (SuperLU's minimum
    degree on ``A + A^T``) factors it without pivoting; solves are refined against the
    unregularised matrix. The chain structure of a shooting problem (states, multipliers
    and the carriage spline's coefficients, each coupled to the samples of its support)
    then fills linearly in the record's length: a 30,001-sample fit's KKT (121,000 rows)
    factors in 0.7 s with 2.4 million entries, where SuperLU's column order with partial
    pivoting filled 77 million and took 9 s. A solve whose refined residual is not small
    (:data:`REFINED_RESIDUAL`) falls back to :func:`_lu_with_dense_columns`."""
    K = sps.csc_matrix(K)
    n = K.shape[0]
    n_primal = n if n_primal is None else n_primal
    d = np.asarray(abs(K).max(axis=1).todense()).ravel()
    scale = 1.0 / np.sqrt(np.where(d > 0, d, 1.0))
    D = sps.diags(scale)
    Ks = (D @ K @ D).tocsc()
    delta = np.r_[np.full(n_primal, QUASI_DEFINITE_DELTA), np.full(n - n_primal, -QUASI_DEFINITE_DELTA)]
    try:
        lu = spla.splu((Ks + sps.diags(delta)).tocsc(), permc_spec="MMD_AT_PLUS_A",
                       diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:
        return _lu_with_dense_columns(K)
    fallback = []

    def solve(R: np.ndarray) -> np.ndarray:
        if fallback:
            return fallback[0](R)
        R = np.asarray(R, float)
        Rs = R * (scale[:, None] if R.ndim == 2 else scale)
        y = lu.solve(Rs)
        for _ in range(REFINEMENT_STEPS):
            y = y + lu.solve(Rs - Ks @ y)
        # the residual relative to the right-hand side: on an ill-conditioned KKT a small
        # backward error still allows a wrong solution (a held-out record's: residual 96
        # for a right-hand side of 1, the entries 1e8), which the fallback solves
        residual = np.abs(Rs - Ks @ y).max(initial=0.0) / max(np.abs(Rs).max(initial=0.0),
                                                               1e-300)
        if not residual <= REFINED_RESIDUAL:
            fallback.append(_lu_with_dense_columns(K))
            return fallback[0](R)
        return y * (scale[:, None] if R.ndim == 2 else scale)

    return solve


def _lu_with_dense_columns(K: sps.csc_matrix):
    """A function ``B -> K^-1 B`` for a KKT matrix ``K``:
    SuperLU's LU with partial pivoting, columns ordered by COLAMD. (Measured against
    CasADi's LDL^T of a regularised ``K`` with iterative refinement: 0.08 vs 0.12 s for one
    pendulum, 0.24 vs 0.59 s for two, 3001 samples each: the refinement on the saddle point
    often did not converge.)

    Columns far denser than the rest (:data:`DENSE_COLUMN_FACTOR`: the carriage spline's
    coefficients where the knots are 0.25 s apart, each coupled to hundreds of samples'
    states) are kept out of the sparse LU and eliminated through their dense Schur
    complement: on a 13.6 s, 500 Hz transport record (27,291 rows, 91 such columns) the LU
    of the whole matrix filled 47 million entries and took 4.4 s, the banded rest and the
    91 x 91 complement 0.2 s, with a smaller residual."""
    K = sps.csc_matrix(K)
    counts = np.diff(K.indptr)
    dense = counts > max(DENSE_COLUMN_FACTOR * max(float(np.median(counts)), 1.0),
                         DENSE_COLUMN_MIN)
    if not dense.any() or dense.all():
        return spla.splu(K, permc_spec="COLAMD").solve
    a, b = np.flatnonzero(~dense), np.flatnonzero(dense)
    Kr = K.tocsr()
    lu = spla.splu(Kr[a][:, a].tocsc(), permc_spec="COLAMD")
    C = Kr[a][:, b].toarray()
    Ct = Kr[b][:, a]
    AiC = lu.solve(C)
    S = Kr[b][:, b].toarray() - Ct @ AiC
    try:
        S_lu = sla.lu_factor(S)
    except (ValueError, np.linalg.LinAlgError):
        return spla.splu(K, permc_spec="COLAMD").solve

    def solve(R: np.ndarray) -> np.ndarray:
        R = np.asarray(R, float)
        R2 = R[:, None] if R.ndim == 1 else R
        y = lu.solve(np.ascontiguousarray(R2[a]))
        xb = sla.lu_solve(S_lu, R2[b] - Ct @ y)
        x = np.empty_like(R2)
        x[a], x[b] = y - AiC @ xb, xb
        return x[:, 0] if R.ndim == 1 else x

    return solve
