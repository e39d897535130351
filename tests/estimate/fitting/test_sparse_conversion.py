"""NumPy and SciPy matrices become CasADi DMs with the same values and structure, and back."""

import casadi as ca
import numpy as np
import scipy.sparse as sps

from estimate.fitting._sparse import dense_dm, scipy_csc, sparse_dm


def test_dense_arrays_keep_their_values_in_column_major_order():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 5))
    for x in (a, a[:, ::2], a.T, rng.normal(size=7)):  # C, strided, Fortran, 1-D
        d = dense_dm(x)
        expected = x[:, None] if x.ndim == 1 else x
        assert d.shape == expected.shape and d.is_dense()
        np.testing.assert_array_equal(np.asarray(d), expected)


def test_sparse_matrices_keep_their_structure_including_stored_zeros():
    A = sps.random(40, 30, density=0.1, format="csr", random_state=1)
    A.data[::7] = 0.0  # stored zeros stay structural nonzeros
    D = sparse_dm(A)
    assert D.nnz() == A.nnz
    np.testing.assert_array_equal(np.asarray(D), A.toarray())
    back = scipy_csc(D)
    np.testing.assert_array_equal(back.toarray(), A.toarray())
    assert back.nnz == A.nnz
    assert ca.DM(D.sparsity(), 1.0).nnz() == A.nnz


def test_evaluate_gives_the_functions_values_as_numpy_and_scipy():
    """:func:`evaluate` (outputs written into NumPy through a function buffer) against
    CasADi's own DM evaluation: a dense matrix in its shape, a sparse one as CSC with its
    structural zeros, and a wrong input size named."""
    from estimate.fitting._sparse import evaluate

    x = ca.MX.sym("x", 3)
    pattern = ca.Sparsity.lower(3)
    sparse = ca.MX(pattern, ca.vertcat(x[0], 0 * x[1], x[2], x[0] * x[1], x[1], x[2] ** 2))
    dense = ca.horzcat(x, 2 * x)
    fn = ca.Function("f", [x], [dense, sparse])
    v = np.array([1.5, -2.0, 0.25])
    d, s = evaluate(fn, v, sparse=(1,))
    ref_d, ref_s = fn(v)
    assert d.shape == (3, 2)
    np.testing.assert_array_equal(d, np.asarray(ref_d))
    assert sps.issparse(s) and s.format == "csc" and s.nnz == pattern.nnz()  # zero kept
    np.testing.assert_array_equal(s.toarray(), np.asarray(ref_s))
    import pytest

    with pytest.raises(ValueError, match="input 0 has 2 values, expected 3"):
        evaluate(fn, v[:2])
