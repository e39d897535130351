"""A CasADi function evaluated once per point: IPOPT asks for the objective's gradient,
the constraint Jacobian and the Gauss-Newton Hessian at the same iterate, three functions
that all need the residual and constraint Jacobians. Wrapped in :class:`OncePerPoint`, the
Jacobians are computed at the first request and served from memory for the others
(a condensed 30 s six-axis fit: the sensitivity propagation, ~100 ms, ran three times
per iteration)."""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["OncePerPoint"]


class OncePerPoint(ca.Callback):
    """``fn`` (one input, a column) as a CasADi callback that keeps its outputs for the
    last input it saw. It evaluates ``fn`` through a :meth:`casadi.Function.buffer`, whose
    work vector is allocated at the first evaluation and kept until :meth:`release`: a
    fresh call allocates it every time (72 MB for a 30,001-sample fit, about 60 ms of page
    faults per iterate). The Python object must outlive every function that calls it."""

    def __init__(self, name: str, fn: ca.Function) -> None:
        ca.Callback.__init__(self)
        if fn.n_in() != 1 or fn.size2_in(0) != 1:
            raise ValueError("OncePerPoint wraps a function of one column input")
        self._fn = fn
        self._point = np.zeros(fn.nnz_in(0))
        self._outputs: list[np.ndarray] = []
        self._fresh = False
        self._buffer = self._evaluate = None
        self.construct(name, {})

    def release(self) -> None:
        """Free the buffer and the kept outputs (the next evaluation makes them again):
        after the solve, so the covariance does not find them still allocated."""
        self._buffer = self._evaluate = None
        self._outputs = []
        self._fresh = False

    def _allocate(self) -> None:
        fn = self._fn
        self._outputs = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
        self._buffer, self._evaluate = fn.buffer()
        self._buffer.set_arg(0, memoryview(self._point))  # read in place at every call
        for i, out in enumerate(self._outputs):
            self._buffer.set_res(i, memoryview(out))

    def get_n_in(self) -> int:
        return 1

    def get_n_out(self) -> int:
        return self._fn.n_out()

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        return self._fn.sparsity_in(0)

    def get_sparsity_out(self, i: int) -> ca.Sparsity:
        return self._fn.sparsity_out(i)

    def has_jacobian(self) -> bool:
        return False

    def has_eval_buffer(self) -> bool:
        return True

    def eval_buffer(self, arg, res) -> int:
        w = np.zeros(self._point.size) if arg[0] is None else np.frombuffer(arg[0], float)
        if not (self._fresh and np.array_equal(w, self._point)):
            if self._buffer is None:
                self._allocate()
            self._point[:] = w
            self._evaluate()
            self._fresh = True
        for out, r in zip(self._outputs, res):
            if r is not None:
                np.frombuffer(r, float)[:] = out
        return 0
