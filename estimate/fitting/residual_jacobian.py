"""The Jacobian of a case's force residuals, assembled from per-sample blocks.

The Gauss-Newton Hessian ``J^T J`` and the covariance need ``d e / d w`` of the weighted,
scaled force residuals (and of the displacement residuals of an estimated carriage motion).
CasADi's symbolic ``jacobian`` of the whole residual expression costs a few tenths of a
second per fit (the graph holds the mapped outputs and the carriage spline); here the
derivatives of the measured outputs are one small SX function evaluated with ``map`` and
the sparse matrix is built from its outputs by index arithmetic, like the constraint
Jacobian of :mod:`estimate.fitting.transcription`.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from derive import OUTPUT_NAMES, DerivedModel
from derive import compiled as compile_fn

from ._sparse import affine_parameters, scatter

__all__ = ["output_jacobian", "force_residual_jacobian"]


def output_jacobian(dm: DerivedModel, channels: tuple[str, ...], ntheta: int,
                    compiled: bool) -> ca.Function:
    """``(x, u, p0, vec(S), theta, t) -> (dy/dx, dy/du, dy/dtheta)`` of the measured
    outputs ``y`` (one row per channel) with ``p = p0 + S theta``. Built (and compiled)
    once per model, channels and number of estimates."""
    key = ("output_jacobian", channels, ntheta, compiled)

    def build() -> ca.Function:
        npar = len(dm.parameter_names)
        x = ca.SX.sym("x", dm.nx)
        u = ca.SX.sym("u", dm.nu)
        p0 = ca.SX.sym("p0", npar)
        Sv = ca.SX.sym("S", npar * ntheta)
        th = ca.SX.sym("theta", ntheta)
        t = ca.SX.sym("t")
        out = dm.outputs(x, u, p0 + ca.mtimes(ca.reshape(Sv, npar, ntheta), th), t)
        y = ca.vertcat(*[out[OUTPUT_NAMES.index(c)] for c in channels])
        fn = ca.Function("output_jacobian", [x, u, p0, Sv, th, t],
                         [ca.jacobian(y, x), ca.jacobian(y, u), ca.jacobian(y, th)])
        if compiled:
            fn = compile_fn(fn)
        return fn

    return dm.memo(key, build)


def force_residual_jacobian(dm: DerivedModel, channels: tuple[str, ...], X: ca.MX,
                            Ug: ca.MX | ca.DM, p: ca.MX, theta: ca.MX, t: np.ndarray,
                            factor: np.ndarray, fixed_start: bool, compiled: bool,
                            A_grid: ca.DM | None = None) -> tuple[ca.MX, ca.MX, ca.MX | None]:
    """Blocks of ``d e / d (theta, states, coefficients)`` for ``e = vec(Y) * factor``.

    ``Y`` (samples x channels) are the measured outputs of the states ``X`` (``nx x n``,
    whose columns are the state variables ``vec(X)`` of a multiple-shooting block, without
    the first column when the start is fixed) and of the grid inputs ``Ug``; ``factor``
    (``channels * n``, channel-major) holds each row's weight over its channel scale.
    With ``A_grid`` (``vec(Ug) = A_grid c``) the third block is ``d e / d c``.
    Returns ``(J_theta, J_states, J_c)``.
    """
    n, nx, nu, nch = t.size, dm.nx, dm.nu, len(channels)
    ntheta = theta.numel()
    p0, S = affine_parameters(p, theta)
    fn = output_jacobian(dm, channels, ntheta, compiled)
    Jx, Ju, Jt = dm.mapped(("output_jacobian", channels, ntheta, compiled), fn, n)(
        X, Ug, p0, ca.vec(S), theta, ca.DM(t).T)
    k = np.arange(n)
    ch = np.arange(nch)

    def entries(width: int, col_of, keep=None):
        # row ch n + k, column col_of(k, j); vec index of the mapped (nch x width n) block
        kk = k if keep is None else k[keep]
        K, C, J = np.meshgrid(kk, ch, np.arange(width), indexing="ij")
        rows = (C * n + K).ravel()
        src = ((K * width + J) * nch + C).ravel()
        return rows, col_of(K, J).ravel(), src

    factor = np.asarray(factor, float)

    def scaled(values: ca.MX, width: int) -> ca.MX:
        # vec entry v of a mapped (nch x width n) block is (channel v % nch, sample
        # v // (nch width)): multiply it by that row's factor
        v = np.arange(nch * width * n)
        return ca.vec(values) * ca.DM(factor[(v % nch) * n + v // (nch * width)])

    rows, cols, src = entries(ntheta, lambda K, J: J)
    J_theta = scatter(scaled(Jt, ntheta), (nch * n, ntheta), rows, cols, src)
    off = -1 if fixed_start else 0
    nvar = (n + off) * nx
    rows, cols, src = entries(nx, lambda K, J: (K + off) * nx + J, keep=k + off >= 0)
    J_states = scatter(scaled(Jx, nx), (nch * n, nvar), rows, cols, src)
    J_c = None
    if A_grid is not None:
        rows, cols, src = entries(nu, lambda K, J: K * nu + J)
        J_u = scatter(scaled(Ju, nu), (nch * n, nu * n), rows, cols, src)
        J_c = ca.mtimes(J_u, A_grid)
    return J_theta, J_states, J_c
