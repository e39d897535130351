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
    last input it saw. The Python object must outlive every function that calls it."""

    def __init__(self, name: str, fn: ca.Function) -> None:
        ca.Callback.__init__(self)
        if fn.n_in() != 1 or fn.size2_in(0) != 1:
            raise ValueError("OncePerPoint wraps a function of one column input")
        self._fn = fn
        self._point: np.ndarray | None = None
        self._outputs: list | None = None
        self.construct(name, {})

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

    def eval(self, args):
        w = np.asarray(args[0].nonzeros(), float)
        if self._point is None or not np.array_equal(w, self._point):
            self._outputs = self._fn.call([args[0]])
            self._point = w
        return list(self._outputs)
