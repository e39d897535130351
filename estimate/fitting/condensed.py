"""Multiple shooting on a grid coarser than the samples: one shooting interval per ``K``
samples, the states at the samples inside an interval simulated from its node.

With a node at every sample (``K = 1``) a long record's NLP carries ``nx`` variables and
``nx`` continuity constraints per sample, and IPOPT's KKT systems grow with them. Here the
nodes are every ``K``-th sample and each interval runs its ``K`` RK4 steps from its node
(the same steps on the same sample grid: the same discrete model and the same optimum).
The steps carry forward sensitivities of the states w.r.t. the node, the parameters and
the few carriage coefficients the interval depends on; they give the constraint Jacobian
(node to node) and the states' Jacobian (sample by sample), which the residual Jacobian
chains with the outputs' (:mod:`estimate.fitting.terms`). A 30,001-sample fit's KKT has
121,000 rows with a node per sample, 13,000 with one every 10.

The last interval is padded to ``K`` steps with steps of zero length (an RK4 step of
``h = 0`` returns its state), so step ``j`` of every interval is one mapped evaluation.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from derive import DerivedModel, rk4_step
from derive import compiled as compile_fn

from ._sparse import affine_parameters, dense_dm, scatter

__all__ = ["condensed_block", "padded_grid", "residual_jacobian", "StepSensitivities"]


#: Most carriage coefficients one interval's inputs may depend on (a B-spline's are a
#: few per interval; an input whose coefficients are not local is shot from every sample).
WINDOW_MAX = 64


def padded_grid(t: np.ndarray, K: int) -> tuple[int, np.ndarray, np.ndarray]:
    """``(m, tk, hk)``: the number of intervals of ``K`` sample steps covering ``t``, and
    the start time and length of each of their ``m K`` steps (zero-length past the end)."""
    n = t.size
    m = -(-(n - 1) // K)
    steps = m * K
    tk = np.full(steps, float(t[-1]))
    hk = np.zeros(steps)
    tk[: n - 1] = t[:-1]
    hk[: n - 1] = np.diff(t)
    return m, tk, hk


def _sensitivity_symbols(dm: DerivedModel, ntheta: int, width: int):
    """The symbolic inputs both per-step functions share: ``p0, vec(S), theta`` (and
    ``p = p0 + S theta``) and a state's sensitivities ``Sx, St, Sc`` to the node, the
    estimates and a window of ``width`` coefficients."""
    npar, nx = len(dm.parameter_names), dm.nx
    p0 = ca.SX.sym("p0", npar)
    Sv = ca.SX.sym("S", npar * ntheta)
    th = ca.SX.sym("theta", ntheta)
    p = p0 + ca.mtimes(ca.reshape(Sv, npar, ntheta), th)
    return (p0, Sv, th), p, (ca.SX.sym("Sx", nx, nx), ca.SX.sym("St", nx, ntheta),
                             ca.SX.sym("Sc", nx, width))


def used_stage_inputs(dm: DerivedModel, substeps: int) -> tuple[int, ...]:
    """The stage inputs (rows of an RK4 step's ``U``) the step depends on: the lateral
    rig's pendulums take the carriage's acceleration, not its position and velocity, so
    two thirds of the stage inputs need no basis (all of them when it depends on none)."""
    def build() -> tuple[int, ...]:
        step = rk4_step(dm, substeps)
        used = tuple(sorted(set(step.sparsity_jac(1, 0).get_col())))
        return used or tuple(range(step.size1_in(1)))

    return dm.memo(("used_stage_inputs", substeps), build)


def _step_inputs(nU: int, width: int, used: tuple[int, ...]
                 ) -> tuple[list[ca.SX], ca.SX]:
    """A step's input symbols and its ``nU`` stage inputs: ``[U]`` (data), or ``[B, c]``
    with ``U[used] = B c`` (an interval's basis over its window of ``width``
    coefficients, for the ``used`` stage inputs; the others zero)."""
    if not width:
        U = ca.SX.sym("U", nU)
        return [U], U
    B, c = ca.SX.sym("B", len(used), width), ca.SX.sym("c", width)
    Bc = ca.mtimes(B, c)
    U = ca.SX.zeros(nU)
    for r, i in enumerate(used):
        U[i] = Bc[r]
    return [B, c], U


def _step(dm: DerivedModel, substeps: int, width: int, compiled: bool) -> ca.Function:
    """One RK4 step ``(x, inputs..., p, t, h) -> x+`` (:func:`_step_inputs`), compiled
    when asked (then without CasADi derivatives). Built once per model, substeps and
    width."""
    if not width:  # the plain RK4 step, shared with the other transcriptions
        from .transcription import _compiled_step

        return _compiled_step(dm, substeps) if compiled else rk4_step(dm, substeps)

    def build() -> ca.Function:
        step = rk4_step(dm, substeps)
        x = ca.SX.sym("x", dm.nx)
        ins, U = _step_inputs(step.size1_in(1), width, used_stage_inputs(dm, substeps))
        p = ca.SX.sym("p", step.size1_in(2))
        t, h = ca.SX.sym("t"), ca.SX.sym("h")
        fn = ca.Function("condensed_step", [x, *ins, p, t, h], [step(x, U, p, t, h)])
        return compile_fn(fn) if compiled else fn

    return dm.memo(("condensed_step", substeps, width, compiled), build)


def _propagation(dm: DerivedModel, substeps: int, ntheta: int, width: int,
                 compiled: bool) -> ca.Function:
    """One RK4 step carrying forward sensitivities: ``(x, inputs..., p0, vec(S), theta,
    t, h, Sx, St, Sc) -> (x+, Sx+, St+, Sc+)`` (inputs: :func:`_step_inputs`) with
    ``p = p0 + S theta``, ``Sx+ = A Sx``, ``St+ = A St + dx+/dtheta``,
    ``Sc+ = A Sc + dx+/dc`` (``A = dx+/dx``): the states' derivatives w.r.t. the
    interval's node, the scaled parameters and a window of ``width`` coefficients of an
    estimated input (``U = B c``; no ``Sc`` columns when the inputs are data). Built (and
    compiled) once per model, substeps, estimates and width."""
    key = ("condensed_propagation", substeps, ntheta, width, compiled)

    def build() -> ca.Function:
        step = rk4_step(dm, substeps)
        nx = dm.nx
        x = ca.SX.sym("x", nx)
        ins, U = _step_inputs(step.size1_in(1), width, used_stage_inputs(dm, substeps))
        t, h = ca.SX.sym("t"), ca.SX.sym("h")
        (p0, Sv, th), p, (Sx, St, Sc) = _sensitivity_symbols(dm, ntheta, width)
        xn = step(x, U, p, t, h)
        A = ca.jacobian(xn, x)
        outs = [xn, ca.densify(ca.mtimes(A, Sx)),
                ca.densify(ca.mtimes(A, St) + ca.jacobian(xn, th)),
                ca.densify(ca.mtimes(A, Sc) + ca.jacobian(xn, ins[1])) if width
                else ca.SX(nx, 0)]
        fn = ca.Function("condensed_propagation", [x, *ins, p0, Sv, th, t, h, Sx, St, Sc],
                         outs)
        if compiled:
            fn = compile_fn(fn)
        return fn

    return dm.memo(key, build)


def condensed_block(dm: DerivedModel, substeps: int, K: int, p: ca.MX, t: np.ndarray,
                    U: ca.DM | ca.MX, x_guess: np.ndarray, x0: np.ndarray | None,
                    theta: ca.MX | None, compiled: bool, coefficients):
    """The :class:`~estimate.fitting.transcription.Block` of one case with a node every
    ``K`` samples (arguments as :meth:`MultipleShooting.block`), or ``None`` when an
    estimated input's intervals depend on more than :data:`WINDOW_MAX` coefficients.

    Step ``j`` of every interval is one mapped evaluation (``K`` of them in all), so the
    expression graph and the compiled code do not grow with ``K`` or the record."""
    from .transcription import Block, _bidiagonal

    n, nx = t.size, dm.nx
    m, tk, hk = padded_grid(t, K)
    win = grid_inputs = None
    if coefficients is not None:
        # the stage inputs of step j of interval k: its window's basis times the window's
        # coefficients, inside the step functions (the sparse stage matrix is never made
        # a CasADi constant, nor the inputs an intermediate)
        nU = coefficients.rows
        used = used_stage_inputs(dm, substeps)
        key = ("condensed windows", m, nU, K, used)
        if key not in coefficients.cache:
            coefficients.cache[key] = _Windows.of(coefficients.stage, m, nU, K, used)
        win = coefficients.cache[key]
        if win.width > WINDOW_MAX:
            return None  # inputs not local in their coefficients: a node per sample instead
        Cw = win.window_coefficients(coefficients.c)
        inputs = [(win.basis[j], Cw) for j in range(K)]
    else:
        nU = int(U.size1())
        pad = m * K - (n - 1)
        Up = ca.horzcat(U, ca.DM.zeros(nU, pad)) if pad else U
        # step j of every interval: nU x m (MX: one constant for the three runs)
        inputs = [(ca.MX(Up[:, j::K]),) for j in range(K)]
    width = 0 if win is None else win.width
    # step j of every interval: start times and lengths (1 x m)
    tj = [ca.MX(dense_dm(tk[j::K]).T) for j in range(K)]
    hj = [ca.MX(dense_dm(hk[j::K]).T) for j in range(K)]
    nodes = np.arange(m) * K
    fixed = x0 is not None
    W = ca.MX.sym("X", nx, m - 1 if fixed else m)
    N = ca.horzcat(ca.DM(x0), W) if fixed else W  # node states, one column per interval
    w0 = np.asarray(x_guess)[:, nodes[1:] if fixed else nodes]

    def run(compiled_step: bool) -> list[ca.MX]:  # the states after each step, nx x m each
        step_map = dm.mapped(("condensed_step", substeps, width, compiled_step),
                             _step(dm, substeps, width, compiled_step), m)
        xs, x = [], N
        for j in range(K):
            x = step_map(x, *inputs[j], p, tj[j], hj[j])
            xs.append(x)
        return xs

    # sample s = k K + j + 1 is entry k of step j: its place among the steps' states
    # stacked (one gather, not a vertcat of K matrices and a reshape)
    s_ = np.arange(1, n)
    order = (((s_ - 1) % K)[:, None] * nx * m + ((s_ - 1) // K)[:, None] * nx
             + np.arange(nx)[None, :]).ravel().tolist()

    def states(xs: list[ca.MX]) -> ca.MX:  # nx x n on the samples
        stacked = ca.vertcat(*[ca.vec(x) for x in xs])
        return ca.horzcat(N[:, 0], ca.reshape(stacked[order], nx, n - 1))

    if win is not None and coefficients.grid is not None:
        if win.grid is None:
            win.grid = win.grid_bases(coefficients.grid, dm.nu, K, n)
        intervals, first = win.grid
        # samples k K + 1 .. k K + K of interval k in one product: nu K x m, which
        # reshaped to nu x K m has the samples in order (an interpreted product: the
        # measurement terms of the inputs are differentiated through it)
        later = ca.reshape(win.product(dm, intervals, Cw), dm.nu, K * m)
        grid_inputs = ca.horzcat(ca.mtimes(first, Cw[:, 0]), later[:, : n - 1])

    def continuity(last: ca.MX) -> ca.MX:  # node k + 1 = the end of interval k
        return ca.vec(N[:, 1:] - last[:, : m - 1])

    xs = run(False)
    X, g = states(xs), continuity(xs[-1])
    if theta is None:
        return Block(ca.vec(W), w0.ravel(order="F"), g, X, grid_inputs=grid_inputs)
    g_fast, X_fast = g, X
    if compiled:  # what IPOPT evaluates: compiled steps (no CasADi derivatives)
        xs_fast = run(True)
        g_fast, X_fast = continuity(xs_fast[-1]), states(xs_fast)
    ntheta_all = theta.numel()
    p0, S, cols, theta = _dynamic_parameters(p, theta)
    ntheta = len(cols)
    prop = dm.mapped(("condensed_propagation", substeps, ntheta, width, compiled),
                     _propagation(dm, substeps, ntheta, width, compiled), m)
    x = N
    Sx = ca.DM(np.tile(np.eye(nx), (1, m)))
    St = ca.DM.zeros(nx, ntheta * m)
    Sc = ca.DM.zeros(nx, width * m)
    xj, Sxs, Sts, Scs = [], [], [], []
    for j in range(K):
        x, Sx, St, Sc = prop(x, *inputs[j], p0, ca.vec(S), theta, tj[j], hj[j], Sx, St, Sc)
        xj.append(x)
        Sxs.append(Sx)
        Sts.append(St)
        Scs.append(Sc)
    # constraints: node to node, like one-step shooting on the nodes
    jac_theta = -_rows_of_blocks(St, nx, ntheta, m - 1, cols, ntheta_all)
    jac_w = _bidiagonal(nx, m, -_transposed_blocks(Sx, nx, nx, m - 1), fixed_start=fixed)
    jac_c = None
    if win is not None:
        # row k nx + i, column start_k + j: entry (i, k width + j) of the last step's Sc
        kk, ii, jj = win.entries(m - 1, nx)
        jac_c = scatter(-ca.vec(Sc), (nx * (m - 1), win.n_coefficients), kk * nx + ii,
                        win.start[kk] + jj, (kk * width + jj) * nx + ii)
    sens = StepSensitivities(K, m, n, fixed, N, tuple(xj), tuple(Sxs), tuple(Sts),
                             tuple(Scs), win, cols, p0, S, theta)
    return Block(ca.vec(W), w0.ravel(order="F"), g, X, jac_theta, jac_w, g_fast, jac_c,
                 continuity(xj[-1]), state_jacobian=sens, X_fast=X_fast,
                 grid_inputs=grid_inputs)


def _dynamic_parameters(p: ca.MX, theta: ca.MX):
    """``(p0, S, columns, theta[columns])`` with ``p = p0 + S theta[columns]``: only the
    estimates that enter the model's parameters (a transducer offset, drift or stream lag
    does not enter the dynamics, and forward sensitivities to it would be zeros carried
    at full cost: the six-axis fit's 19 estimates hold 7 such)."""
    p0, S = affine_parameters(p, theta)
    Sn = np.asarray(ca.DM(S))
    cols = np.flatnonzero(np.any(Sn != 0, axis=0))
    return p0, ca.DM(Sn[:, cols]), cols, theta[cols.tolist()]


def _rows_of_blocks(M: ca.MX, rows: int, cols: int, blocks: int, columns: np.ndarray,
                    width: int) -> ca.MX:
    """The first ``blocks`` of the ``rows x cols`` blocks side by side in ``M``, stacked
    vertically, its columns placed at ``columns`` of ``width``."""
    k, r, c = np.meshgrid(np.arange(blocks), np.arange(rows), np.arange(cols), indexing="ij")
    return scatter(ca.vec(M), (rows * blocks, width), (k * rows + r).ravel(),
                   np.asarray(columns)[c.ravel()], ((k * cols + c) * rows + r).ravel())


def _transposed_blocks(M: ca.MX, rows: int, cols: int, blocks: int) -> ca.MX:
    """The first ``blocks`` of the ``rows x cols`` blocks side by side in ``M``, each
    transposed, side by side (``cols x rows blocks``)."""
    k, r, c = np.meshgrid(np.arange(blocks), np.arange(rows), np.arange(cols), indexing="ij")
    return scatter(ca.vec(M), (cols, rows * blocks), c.ravel(), (k * rows + r).ravel(),
                   ((k * cols + c) * rows + r).ravel())


class _Windows:
    """The coefficients of an estimated input that each interval's stage inputs depend
    on: a window of ``width`` consecutive coefficients from ``start[k]`` (the same width
    for every interval, so one mapped function serves them), the inputs' dense basis over
    it (``basis[j]``: step ``j``'s ``nU x width`` blocks of every interval side by side),
    and ``first``/``last``, the window columns each interval really uses."""

    def __init__(self, start, width, first, last, basis, n_coefficients):
        self.start, self.width, self.first, self.last = start, width, first, last
        self.basis, self.n_coefficients = basis, n_coefficients
        #: The grid inputs' bases (:meth:`grid_bases`), when the block made them.
        self.grid = None

    def window_coefficients(self, c: ca.MX) -> ca.MX:
        """``width x m``: column ``k`` holds the coefficients of interval ``k``'s window."""
        idx = self.start[None, :] + np.arange(self.width)[:, None]
        return ca.reshape(c[idx.ravel(order="F").tolist()], self.width, self.start.size)

    def product(self, dm: DerivedModel, basis: ca.MX, Cw: ca.MX) -> ca.MX:
        """Every interval's ``rows x width`` block of ``basis`` (side by side) times its
        window's coefficients (a column of ``Cw``): ``rows x m``."""
        rows, m = int(basis.size1()), self.start.size
        key = ("window_product", rows, self.width)
        fn = dm.memo(key, lambda: _window_product(rows, self.width))
        return dm.mapped(key, fn, m)(basis, Cw)

    @classmethod
    def of(cls, A, m: int, nU: int, K: int, used: tuple[int, ...] | None = None
           ) -> "_Windows":
        """Windows of the ``m`` intervals of ``K`` steps of ``nU`` stage inputs each,
        ``vec(U) = A c`` (``A`` CasADi or SciPy; its rows past its end: the padded steps,
        zero), with bases for the ``used`` stage inputs (default all)."""
        used = tuple(range(nU)) if used is None else tuple(used)
        C, row = _rows(A)
        nc, per = C.shape[1], nU * K  # stage-input rows per interval
        # keep the rows of the used stage inputs: row r = k per + j nU + i
        position = np.full(nU, -1, dtype=np.int64)
        position[list(used)] = np.arange(len(used))
        pos = position[row % nU]
        if len(used) < nU:
            keep = pos >= 0
            C = C[np.flatnonzero(np.isin(np.arange(C.shape[0]) % nU, used))]
            row, pos = row[keep], pos[keep]
        nu_ = len(used)
        lo = np.zeros(m, dtype=np.int64)
        hi = np.zeros(m, dtype=np.int64)
        # each row's first and last column (sorted within rows), then each interval's
        full = np.flatnonzero(np.diff(C.indptr))
        if full.size:
            k = row[C.indptr[full]] // per
            present, first = np.unique(k, return_index=True)  # rows ascending: k sorted
            lo[present] = np.minimum.reduceat(C.indices[C.indptr[full]], first)
            hi[present] = np.maximum.reduceat(C.indices[C.indptr[full + 1] - 1], first)
        # a multiple of 4: fewer distinct compiled functions over records (zero columns)
        width = int(min(nc, -(-int((hi - lo).max() + 1) // 4) * 4))
        start = np.clip(lo, 0, nc - width)
        # per step j: the (nu_ x width) bases of every interval side by side; entry of
        # row r = k per + j nU + i (used stage input i at position pos) and column c at
        # (((j nu_ + pos) m + k) width + c - start[k])
        k = row // per
        flat = (row - k * per) // nU * nu_ + pos
        flat *= m
        flat += k
        flat *= width
        flat += C.indices
        flat -= start[k]
        L = np.zeros((K, nu_, m, width))
        L.ravel()[flat] = C.data
        # MX constants: the block passes them to three mapped runs (simulation, compiled
        # simulation, sensitivities), and a DM argument would be copied into each
        basis = [ca.MX(dense_dm(L[j].reshape(nu_, m * width))) for j in range(K)]
        return cls(start, width, lo - start, hi - start, basis, nc)

    def grid_bases(self, A_grid, nu: int, K: int, n: int) -> tuple[ca.MX, ca.DM]:
        """The grid inputs' bases over the windows: per interval ``k``, the
        ``nu K x width`` block of its samples ``k K + 1 .. k K + K`` (side by side; rows
        ``j nu .. (j + 1) nu`` are sample ``k K + j + 1``'s), one constant the block's
        expressions share; and sample 0's (interval 0's window). A grid input outside its
        interval's window is an error (the windows are the stage inputs', whose first and
        last stage times are the samples)."""
        C, row = _rows(A_grid)  # row s nu + i: input i at sample s
        m, width = self.start.size, self.width
        late = row >= nu  # samples after the first: sample k K + j + 1 is interval k's
        k = np.where(late, (row - nu) // (K * nu), 0)
        c = C.indices - self.start[k]
        if np.any((c < 0) | (c >= width)):
            raise ValueError("a grid input depends on a carriage coefficient outside its "
                             "interval's window")
        # row j nu + i = row - nu - k K nu of interval k's block, column c of its window
        L = np.zeros((K * nu, m, width))
        rl, kl = row[late], k[late]
        L.ravel()[((rl - nu - kl * K * nu) * m + kl) * width + c[late]] = C.data[late]
        first = np.zeros((nu, width))
        first[row[~late], c[~late]] = C.data[~late]
        return ca.MX(dense_dm(L.reshape(K * nu, m * width))), dense_dm(first)

    def entries(self, intervals: int, per: int):
        """``(k, i, j)`` index arrays over intervals ``k < intervals``, ``i < per`` and the
        window columns ``j`` interval ``k`` uses."""
        K_, I_, J_ = np.meshgrid(np.arange(intervals), np.arange(per), np.arange(self.width),
                                 indexing="ij")
        keep = (J_ >= self.first[K_]) & (J_ <= self.last[K_])
        return K_[keep], I_[keep], J_[keep]


def _window_product(rows: int, width: int) -> ca.Function:
    """``(B, c) -> B c`` of a ``rows x width`` matrix and a ``width`` column."""
    B, c = ca.SX.sym("B", rows, width), ca.SX.sym("c", width)
    return ca.Function("window_product", [B, c], [ca.mtimes(B, c)])


def _rows(A):
    """A CasADi or SciPy sparse matrix as SciPy CSR with sorted column indices, and the
    row of each entry."""
    import scipy.sparse as sps

    from ._sparse import scipy_csc

    C = sps.csr_matrix(A if sps.issparse(A) else scipy_csc(A))
    if not C.has_sorted_indices:
        C = C.sorted_indices()
    row = np.repeat(np.arange(C.shape[0], dtype=np.int64), np.diff(C.indptr))
    return C, row


@dataclass(frozen=True)
class StepSensitivities:
    """What a condensed block carries to the residual Jacobian: its layout (``K`` steps
    per interval, ``m`` intervals, ``n`` samples, whether node 0 is fixed), the nodes
    ``N`` (``nx x m``), and per step ``j`` of every interval (blocks side by side, one per
    interval) the states after it and their sensitivities to the node (``nx x nx``), the
    scaled parameters (``nx x ntheta``) and the window of carriage coefficients
    (``nx x width``; :class:`_Windows`, ``None`` when the inputs are data)."""

    K: int
    m: int
    n: int
    fixed: bool
    N: ca.MX
    states: tuple
    Sx: tuple
    St: tuple
    Sc: tuple
    windows: "_Windows | None"
    #: The estimates the sensitivities ``St`` are taken to (those entering the model's
    #: parameters), as indices among all of them, and the model's parameters as
    #: ``p0 + S theta`` of those estimates (:func:`_dynamic_parameters`).
    theta_columns: np.ndarray
    p0: ca.DM
    S: ca.DM
    theta: ca.MX


def _output_sensitivity(dm: DerivedModel, channels: tuple[str, ...], ntheta: int,
                        width: int, compiled: bool) -> ca.Function:
    """``(x, u, Bg, p0, vec(S), theta, t, Sx, St, Sc, w) -> (dy/dnode, dy/dtheta, dy/dc)``
    of the measured outputs ``y(x, u, p, t)`` (one row per channel) at a state with
    sensitivities ``Sx, St, Sc`` and grid inputs ``u = Bg c`` over the window, row ``i``
    times ``w[i]`` (the residual's factor: no scaling of the mapped outputs after)."""
    key = ("condensed_output", channels, ntheta, width, compiled, "weighted")

    def build() -> ca.Function:
        from derive import OUTPUT_NAMES

        x = ca.SX.sym("x", dm.nx)
        u = ca.SX.sym("u", dm.nu)
        Bg = ca.SX.sym("Bg", dm.nu, width)
        t = ca.SX.sym("t")
        (p0, Sv, th), p, (Sx, St, Sc) = _sensitivity_symbols(dm, ntheta, width)
        out = dm.outputs(x, u, p, t)
        y = ca.vertcat(*[out[OUTPUT_NAMES.index(c)] for c in channels])
        Hx = ca.jacobian(y, x)
        w = ca.SX.sym("w", len(channels))
        outs = [ca.mtimes(Hx, Sx), ca.mtimes(Hx, St) + ca.jacobian(y, th),
                ca.mtimes(Hx, Sc) + ca.jtimes(y, u, Bg) if width
                else ca.SX(len(channels), 0)]
        outs = [ca.densify(o * ca.repmat(w, 1, o.size2())) for o in outs]
        fn = ca.Function("condensed_output", [x, u, Bg, p0, Sv, th, t, Sx, St, Sc, w], outs)
        if compiled:
            fn = compile_fn(fn)
        return fn

    return dm.memo(key, build)


def residual_jacobian(dm: DerivedModel, channels: tuple[str, ...], sens: StepSensitivities,
                      Ug: ca.MX | ca.DM, ntheta_all: int, t: np.ndarray, factor: np.ndarray,
                      compiled: bool) -> tuple[ca.MX, ca.MX, ca.MX | None]:
    """``(d e/d theta, d e/d w, d e/d c)`` of ``e = vec(Y) * factor`` w.r.t. the
    ``ntheta_all`` scaled estimates, the block's nodes and the carriage coefficients
    (``Y`` the measured outputs, samples x channels, channel-major as
    :func:`estimate.fitting.residual_jacobian.force_residual_jacobian`) on a condensed
    block: each sample's output Jacobian composed with its state's sensitivities inside
    one compiled per-sample function (no sparse products at evaluation). When the inputs
    are estimated, their bases over the windows are the block's (``sens.windows.grid``)."""
    K, m, n, nx, nu, nch = sens.K, sens.m, sens.n, dm.nx, dm.nu, len(channels)
    win = sens.windows
    width = 0 if win is None else win.width
    p0, S, columns, theta = sens.p0, sens.S, sens.theta_columns, sens.theta
    ntheta = len(columns)
    fn = _output_sensitivity(dm, channels, ntheta, width, compiled)
    fmap = dm.mapped(("condensed_output", channels, ntheta, width, compiled), fn, m)
    pad = m * K + 1 - n
    Ugp = ca.horzcat(Ug, ca.DM.zeros(nu, pad)) if pad else Ug
    tp = np.r_[t, np.full(pad, t[-1])]
    if win is not None and win.grid is None:
        raise ValueError("the condensed block of an estimated input made no grid bases "
                         "(InputCoefficients.grid missing)")
    bases = None if win is None else win.grid  # all steps' (nu K x width m), sample 0's
    # the residual's factors by channel (rows) and sample (columns), the padded samples 0
    factor = np.asarray(factor, float)
    weights = np.zeros((nch, m * K + 1))
    weights[:, :n] = factor.reshape(nch, n)
    outs = []
    for j in range(K):
        Bg = ca.DM(nu, 0) if win is None else bases[0][j * nu:(j + 1) * nu, :]
        outs.append(fmap(sens.states[j], Ugp[:, j + 1::K], Bg, p0, ca.vec(S), theta,
                         ca.DM(tp[j + 1::K]).T, sens.Sx[j], sens.St[j], sens.Sc[j],
                         dense_dm(weights[:, j + 1::K])))
    # sample 0: at node 0, whose sensitivities are the identity and zeros
    Bg0 = ca.DM(nu, 0) if win is None else bases[1]
    outs.append(fn(sens.N[:, 0], Ug[:, 0], Bg0, p0, ca.vec(S), theta, float(t[0]),
                   ca.DM.eye(nx), ca.DM.zeros(nx, ntheta), ca.DM.zeros(nx, width),
                   dense_dm(weights[:, 0])))
    # sample s = k K + j + 1 of step j, interval k (padded samples s >= n dropped); the
    # last entry of every block list is sample 0's (interval 0, "step -1")

    def block(idx: int, width_b: int, col_of, keep_col=None):
        rows, cols, src, off = [], [], [], 0
        for j in range(K + 1):
            count = m if j < K else 1
            k_, ch_, c_ = np.meshgrid(np.arange(count), np.arange(nch), np.arange(width_b),
                                      indexing="ij")
            smp = k_ * K + j + 1 if j < K else np.zeros_like(k_)
            keep = smp < n
            if keep_col is not None:
                keep &= keep_col(k_, c_)
            rows.append((ch_ * n + smp)[keep])
            cols.append(col_of(k_, c_)[keep])
            src.append((off + (k_ * width_b + c_) * nch + ch_)[keep])
            off += count * width_b * nch
        rows, cols, src = np.concatenate(rows), np.concatenate(cols), np.concatenate(src)
        return rows, cols, src, ca.vertcat(*[ca.vec(o[idx]) for o in outs])

    rows, cols, src, v = block(1, ntheta, lambda k_, c_: columns[c_])
    J_theta = scatter(v, (nch * n, ntheta_all), rows, cols, src)
    offn = -1 if sens.fixed else 0
    nvar = nx * (m + offn)
    rows, cols, src, v = block(0, nx, lambda k_, c_: (k_ + offn) * nx + c_,
                               lambda k_, c_: k_ + offn >= 0)
    J_states = scatter(v, (nch * n, nvar), rows, cols, src)
    J_c = None
    if win is not None:
        rows, cols, src, v = block(2, width, lambda k_, c_: win.start[k_] + c_,
                                   lambda k_, c_: (c_ >= win.first[k_]) & (c_ <= win.last[k_]))
        J_c = scatter(v, (nch * n, win.n_coefficients), rows, cols, src)
    return J_theta, J_states, J_c
