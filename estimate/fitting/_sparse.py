"""Sparse CasADi matrices: from SciPy matrices, and scattered from the outputs of mapped
per-interval functions."""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sps

__all__ = ["sparse_dm", "dense_dm", "scipy_csc", "scatter", "affine_parameters",
           "evaluate"]


def sparse_dm(A: sps.spmatrix) -> ca.DM:
    """``A`` as a CasADi DM with the same sparsity, built from memoryviews of its CSC
    arrays (several times faster than CasADi's generic conversion of a SciPy matrix; a
    memoryview converts in 90-115 ns per entry, a Python list in 135-190 and a NumPy
    array in 175 or more)."""
    C = sps.csc_matrix(A)
    C.sort_indices()
    sp = ca.Sparsity(C.shape[0], C.shape[1], memoryview(C.indptr.astype(np.int64)),
                     memoryview(C.indices.astype(np.int64)))
    return ca.DM(sp, memoryview(np.ascontiguousarray(C.data, float)))


def dense_dm(a) -> ca.DM:
    """A NumPy array (1-D: a column) as a dense CasADi DM, from a memoryview of its
    column-major values (twice as fast as ``ca.DM(a)``: :func:`sparse_dm`)."""
    a = np.asarray(a, float)
    if a.ndim == 1:
        a = a[:, None]
    return ca.DM(ca.Sparsity.dense(*a.shape), memoryview(a.ravel(order="F")))


def scipy_csc(M: ca.DM) -> sps.csc_matrix:
    """A CasADi DM as a SciPy CSC matrix with the same sparsity (structural zeros kept),
    from its compressed-column arrays (about twice as fast as ``DM.sparse()``)."""
    sp = M.sparsity()
    return sps.csc_matrix((np.array(M.nonzeros(), float), np.array(sp.row(), np.int64),
                           np.array(sp.colind(), np.int64)), shape=(M.size1(), M.size2()))


def scatter(values: ca.MX, shape: tuple[int, int], rows: np.ndarray, cols: np.ndarray,
            src: np.ndarray) -> ca.MX:
    """Sparse ``shape`` matrix with entry ``(rows[i], cols[i]) = values[src[i]]``."""
    sp, mapping = ca.Sparsity.triplet(shape[0], shape[1], np.asarray(rows).tolist(),
                                      np.asarray(cols).tolist(), True)
    nz = np.empty(sp.nnz(), dtype=int)
    nz[np.asarray(mapping, dtype=int)] = src
    return ca.MX(sp, values[nz.tolist()])


def affine_parameters(p: ca.MX, theta: ca.MX) -> tuple[ca.DM, ca.DM]:
    """``(p0, S)`` with ``p = p0 + S theta`` for a parameter vector affine in ``theta``."""
    S = ca.evalf(ca.jacobian(p, theta))
    p0 = ca.evalf(ca.substitute(p, theta, ca.DM.zeros(theta.numel())))
    return p0, S


def evaluate(fn: ca.Function, *args, sparse: tuple[int, ...] = ()) -> list:
    """``fn(*args)`` with NumPy results: the outputs numbered in ``sparse`` as SciPy CSC
    matrices (structural zeros kept), the others as dense arrays of their shapes. The
    outputs are written straight into NumPy arrays (a function buffer): converting a
    30,001-sample fit's DM residual Jacobian to SciPy, and reading its nonzeros to check
    them, took 0.3 s."""
    buf, trigger = fn.buffer()
    ins = [np.ascontiguousarray(np.asarray(a, float).ravel(order="F")) for a in args]
    for i, a in enumerate(ins):
        if a.size != fn.nnz_in(i):
            raise ValueError(f"{fn.name()}: input {i} has {a.size} values, expected "
                             f"{fn.nnz_in(i)}")
        buf.set_arg(i, memoryview(a))
    outs = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
    for i, o in enumerate(outs):
        buf.set_res(i, memoryview(o))
    trigger()
    result = []
    for i, o in enumerate(outs):
        sp = fn.sparsity_out(i)
        M = sps.csc_matrix((o, np.array(sp.row(), np.int64), np.array(sp.colind(), np.int64)),
                           shape=(sp.size1(), sp.size2())) if i in sparse or not sp.is_dense() \
            else None
        if i in sparse:
            result.append(M)
        elif M is None:
            result.append(o.reshape(sp.size1(), sp.size2(), order="F"))
        else:
            result.append(M.toarray())
    return result
