"""SciPy sparse matrices as CasADi matrices."""

from __future__ import annotations

import casadi as ca
import scipy.sparse as sps

__all__ = ["sparse_dm"]


def sparse_dm(A: sps.spmatrix) -> ca.DM:
    """``A`` as a CasADi DM with the same sparsity, built from its CSC arrays (several
    times faster than CasADi's generic conversion of a SciPy matrix)."""
    C = sps.csc_matrix(A)
    C.sort_indices()
    sp = ca.Sparsity(C.shape[0], C.shape[1], C.indptr.tolist(), C.indices.tolist())
    return ca.DM(sp, C.data)
