"""Transcriptions of the simulation inside the estimation NLP: multiple shooting and
direct collocation, chosen as objects (``MultipleShooting()``, ``Collocation(degree=3)``).

A transcription turns one case into decision variables (states at nodes), equality
constraints (continuity / collocation defects) and the states at the sample times, from
which the outputs are computed. Interval functions are built once and evaluated with
``map``, so building the NLP does not grow with the record length.

The inputs at the stage times of every interval are either data (a filtered measurement,
evaluated from the excitation) or an expression of decision variables: an estimated
carriage motion ``vec(U) = A c`` (:mod:`estimate.fitting.carriage`); multiple shooting then
also returns the constraint Jacobian with respect to ``c``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from derive import DerivedModel, Excitation, rk4_step
from derive import compiled as compile_fn
from derive.simulate import interval_inputs

from ._sparse import affine_parameters, scatter

__all__ = ["Transcription", "MultipleShooting", "Collocation", "Block", "InputCoefficients"]


@dataclass(frozen=True)
class Block:
    """One case transcribed: ``w`` its state variables (a column), ``w0`` their initial
    guess, ``g`` the equality constraints (= 0) and ``X`` the states at the samples
    (``nx x n``), all as functions of ``w`` and the parameter vector.

    ``jac_theta`` and ``jac_w``, when given, are the constraint Jacobian w.r.t. the scaled
    parameters and ``w``, assembled from per-interval blocks (cheaper than AD of ``g``);
    ``jac_c`` w.r.t. the coefficients of an estimated input (see :class:`InputCoefficients`).
    ``g_fast`` is ``g`` as IPOPT evaluates it with those blocks: possibly compiled, so
    without CasADi derivatives; ``g_jac`` is ``g`` from the same per-interval evaluation as
    the Jacobian blocks (returned with them at no extra cost).
    """

    w: ca.MX
    w0: np.ndarray
    g: ca.MX
    X: ca.MX
    jac_theta: ca.MX | None = None
    jac_w: ca.MX | None = None
    g_fast: ca.MX | None = None
    jac_c: ca.MX | None = None
    g_jac: ca.MX | None = None
    #: With nodes coarser than the samples (:mod:`estimate.fitting.condensed`), the
    #: states on the samples are expressions: their per-step sensitivities
    #: (:class:`~estimate.fitting.condensed.StepSensitivities`). ``None``: the columns of
    #: ``X`` are the variables ``w`` themselves (after a fixed first column).
    state_jacobian: object | None = None
    #: ``X`` as IPOPT evaluates it (from compiled steps, so without CasADi derivatives),
    #: when the states on the samples are expressions; ``None``: ``X``.
    X_fast: ca.MX | None = None
    #: The inputs at the samples (``nu x n``) as an expression of an estimated input's
    #: coefficients, when the transcription makes them; ``None``: the caller's.
    grid_inputs: ca.MX | None = None


@dataclass(frozen=True)
class InputCoefficients:
    """Stage inputs that are a linear function of decision variables: ``vec(U) = A c``.

    ``stage`` is ``A`` as a SciPy matrix (rows in the order of ``vec`` of the
    ``(rows, n - 1)`` stage inputs) and ``grid`` the same map to the inputs at the samples
    (``vec`` of ``(nu, n)``). The sparse CasADi ``A`` (:attr:`A`) is made only when a
    transcription asks for it: a long record's is large (a 30,001-sample record's stage
    matrix holds 1.6 million entries, 0.4 s to convert), and the condensed shooting
    (:mod:`estimate.fitting.condensed`) works from ``stage`` alone."""

    c: ca.MX
    stage: object
    rows: int
    grid: object = None
    _casadi: Callable[[], ca.DM] | None = field(default=None, compare=False, repr=False)
    #: Kept with the record (:meth:`CarriageInput.grid_cache`): what a transcription
    #: derives from ``stage`` and ``grid`` for one fit and may reuse in the next (the
    #: diagnosis assembles a record's NLP ten times).
    cache: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def A(self) -> ca.DM:
        """``stage`` as a sparse CasADi matrix."""
        if self._casadi is not None:
            return self._casadi()
        from ._sparse import sparse_dm

        return sparse_dm(self.stage)

    def stage_inputs(self) -> ca.MX:
        """The stage inputs ``(rows, n - 1)`` as an expression of ``c``."""
        return ca.reshape(ca.mtimes(self.A, self.c), self.rows, self.stage.shape[0] // self.rows)


class Transcription:
    """Base class of transcriptions."""

    def fractions(self) -> np.ndarray:
        """Times within an interval, as fractions of its length, where inputs are needed."""
        raise NotImplementedError

    def describe(self, times: list[np.ndarray]) -> str:
        """What was used on records with the sample times ``times`` (reports)."""
        return repr(self)

    def inputs(self, exc: Excitation | None, t: np.ndarray, nu: int) -> np.ndarray:
        """Input values needed per interval, shape ``(len(fractions) * nu, n - 1)``."""
        return interval_inputs(exc, t, self.fractions(), nu)

    def block(self, dm: DerivedModel, p: ca.MX, t: np.ndarray, U: ca.DM | ca.MX | None,
              x_guess: np.ndarray, x0: np.ndarray | None, theta: ca.MX | None = None,
              compiled: bool = False, coefficients: InputCoefficients | None = None) -> Block:
        """Transcribe one case; ``U`` are the stage inputs (:meth:`inputs`; ``None`` when
        they are ``coefficients``' expression); ``x_guess`` are states on ``t`` (``nx x n``); ``x0`` fixes
        the initial state (``None``: free). With ``theta`` (the scaled decision parameters,
        of which ``p`` is an affine function), a transcription may also return the
        constraint Jacobian blocks; ``compiled`` lets it compile per-interval functions."""
        raise NotImplementedError


def _states_with_fixed_start(nx: int, n: int, x_guess: np.ndarray, x0: np.ndarray | None):
    if x0 is None:
        W = ca.MX.sym("X", nx, n)
        return W, W, x_guess
    W = ca.MX.sym("X", nx, n - 1)
    return W, ca.horzcat(ca.DM(x0), W), x_guess[:, 1:]


@dataclass(frozen=True)
class MultipleShooting(Transcription):
    """States at the nodes are decision variables; continuity is enforced after
    ``substeps`` RK4 steps per sample interval (one step per 10 ms sample is as accurate as
    two for slosh frequencies below ~5 Hz).

    ``samples_per_interval`` sets the nodes: one every that many samples, the states in
    between simulated from the node (:mod:`estimate.fitting.condensed`); ``None`` (default)
    chooses from the sample rate (:func:`interval_samples`, intervals of ``interval_seconds``,
    default :data:`INTERVAL_SECONDS`); 1 puts a node at every sample.
    """

    substeps: int = 1
    samples_per_interval: int | None = None
    interval_seconds: float | None = None

    def __post_init__(self) -> None:
        k = self.samples_per_interval
        if k is not None and (not isinstance(k, (int, np.integer)) or k < 1):
            raise ValueError(f"MultipleShooting samples_per_interval must be a positive "
                             f"integer or None, got {k!r}")

    def fractions(self):
        return np.arange(2 * self.substeps + 1) / (2 * self.substeps)

    def describe(self, times: list[np.ndarray]) -> str:
        ks = sorted({self.interval_samples(np.asarray(t, float)) for t in times})
        k = ks[0] if len(ks) == 1 else tuple(ks)
        return f"MultipleShooting(substeps={self.substeps}, samples_per_interval={k})"

    def interval_samples(self, t: np.ndarray) -> int:
        """Samples per shooting interval on the sample times ``t``: the given
        ``samples_per_interval``, else :func:`interval_samples`."""
        k = self.samples_per_interval
        if k is None:
            return interval_samples(t, self.interval_seconds or INTERVAL_SECONDS)
        return max(1, min(int(k), (t.size - 1) // 2))

    def block(self, dm, p, t, U, x_guess, x0, theta=None, compiled=False, coefficients=None):
        n = t.size
        K = self.interval_samples(t) if dm.nx else 1
        if K > 1:
            from .condensed import condensed_block

            block = condensed_block(dm, self.substeps, K, p, t, U, x_guess, x0, theta,
                                    compiled, coefficients)
            if block is not None:
                return block
        if U is None:
            U = coefficients.stage_inputs()
        W, X, w0 = _states_with_fixed_start(dm.nx, n, x_guess, x0)
        step = rk4_step(dm, self.substeps)
        tk, hk = ca.DM(t[:-1]).T, ca.DM(np.diff(t)).T
        if theta is None or dm.nx == 0:
            xn = dm.mapped(("rk4_step", self.substeps), step, n - 1)(X[:, :-1], U, p, tk, hk)
            return Block(ca.vec(W), np.asarray(w0).ravel(order="F"), ca.vec(X[:, 1:] - xn), X)
        # p = p0 + S theta (affine); per-interval value and Jacobians in one function
        p0, S = affine_parameters(p, theta)
        fn = _step_jacobian(dm, self.substeps, theta.numel(), compiled)
        xn, JxT, JtT, JuT = dm.mapped(("rk4_jacobian", self.substeps, theta.numel(), compiled),
                                      fn, n - 1)(X[:, :-1], U, p0, ca.vec(S), theta, tk, hk)
        # g stays differentiable by CasADi (interpreted step); what IPOPT evaluates is
        # g_fast, from the compiled step when there is one (a third of the time)
        g = ca.vec(X[:, 1:] - dm.mapped(("rk4_step", self.substeps), step, n - 1)(
            X[:, :-1], U, p, tk, hk))
        g_fast = g
        if compiled:
            g_fast = ca.vec(X[:, 1:] - dm.mapped(
                ("rk4_step_compiled", self.substeps), _compiled_step(dm, self.substeps),
                n - 1)(X[:, :-1], U, p, tk, hk))
        jac_theta = -JtT.T  # rows of interval k stacked: (nx (n-1)) x ntheta
        jac_w = _bidiagonal(dm.nx, n, -JxT, fixed_start=x0 is not None)
        jac_c = None
        if coefficients is not None:
            # d g_k / d c = -(d Phi_k / d U_k) A_k: block-diagonal stage Jacobians times A
            nU = int(U.size1())
            jac_c = ca.mtimes(_block_diagonal(dm.nx, nU, n - 1, -JuT), coefficients.A)
        return Block(ca.vec(W), np.asarray(w0).ravel(order="F"), g, X, jac_theta, jac_w,
                     g_fast, jac_c, ca.vec(X[:, 1:] - xn))


#: Longest shooting interval chosen automatically [s], and most samples in it. Within
#: 20 ms a slosh mode below ~5 Hz turns by less than 40 degrees, so the interval's states
#: stay nearly linear in its node and the Gauss-Newton steps as good as with a node per
#: sample.
INTERVAL_SECONDS = 0.02
INTERVAL_SAMPLES_MAX = 16


def interval_samples(t: np.ndarray, seconds: float = INTERVAL_SECONDS) -> int:
    """Samples per shooting interval for sample times ``t``: as many as fit in ``seconds``
    (at most :data:`INTERVAL_SAMPLES_MAX`, and at least two intervals per record)."""
    if t.size < 5:
        return 1
    dt = float(np.median(np.diff(t)))
    k = int(np.floor(seconds / dt + 1e-9)) if dt > 0 else 1
    return max(1, min(k, INTERVAL_SAMPLES_MAX, (t.size - 1) // 2))


def _compiled_step(dm: DerivedModel, substeps: int) -> ca.Function:
    """:func:`derive.rk4_step` compiled to C (once per model and substeps)."""
    return dm.memo(("rk4_step_compiled", substeps), lambda: compile_fn(rk4_step(dm, substeps)))


def _step_jacobian(dm: DerivedModel, substeps: int, ntheta: int, compiled: bool) -> ca.Function:
    """``(x, U, p0, vec(S), theta, t, h) -> (x_next, (dx_next/dx)^T, (dx_next/dtheta)^T,
    (dx_next/dU)^T)`` with ``p = p0 + S theta``; blocks are transposed so that mapped outputs
    stack by rows. Built (and compiled) once per model, substeps and number of estimates."""
    key = ("rk4_jacobian", substeps, ntheta, compiled, 2)

    def build() -> ca.Function:
        step = rk4_step(dm, substeps)
        npar = len(dm.parameter_names)
        x = ca.SX.sym("x", dm.nx)
        U = ca.SX.sym("U", step.size1_in(1))
        p0 = ca.SX.sym("p0", npar)
        th = ca.SX.sym("theta", ntheta)
        Sv = ca.SX.sym("S", npar * ntheta)
        t, h = ca.SX.sym("t"), ca.SX.sym("h")
        xn = step(x, U, p0 + ca.mtimes(ca.reshape(Sv, npar, ntheta), th), t, h)
        fn = ca.Function("rk4_jacobian", [x, U, p0, Sv, th, t, h],
                         [xn, ca.jacobian(xn, x).T, ca.jacobian(xn, th).T,
                          ca.jacobian(xn, U).T])
        if compiled:
            fn = compile_fn(fn)
        return fn

    return dm.memo(key, build)


def _bidiagonal(nx: int, n: int, negJ: ca.MX, *, fixed_start: bool) -> ca.MX:
    """Sparse Jacobian of ``vec(X[:, 1:] - Phi(X[:, :-1]))`` w.r.t. the state variables.

    ``negJ`` holds ``-(dPhi_k/dx)^T`` side by side (``nx x nx (n-1)``). Interval ``k``'s rows
    have ``I`` at ``X_{k+1}`` and ``-dPhi_k/dx`` at ``X_k`` (absent for a fixed ``X_0``).
    """
    offset = -1 if fixed_start else 0  # column block of X_k among the variables
    nvar = (n - 1 if fixed_start else n) * nx
    k = np.arange(n - 1)
    i = np.arange(nx)
    # identity at X_{k+1}: rows k nx + i, columns (k + 1 + offset) nx + i, constant 1 (src -1)
    r_id = (k[:, None] * nx + i[None, :]).ravel()
    c_id = ((k[:, None] + 1 + offset) * nx + i[None, :]).ravel()
    # -dPhi_k/dx at X_k for k + offset >= 0: entry (i, c) is entry (c, i) of transposed block k
    kk = k[k + offset >= 0]
    ii, cc = np.meshgrid(i, i, indexing="ij")
    r_j = (kk[:, None] * nx + ii.ravel()[None, :]).ravel()
    c_j = ((kk[:, None] + offset) * nx + cc.ravel()[None, :]).ravel()
    s_j = (kk[:, None] * nx * nx + (ii * nx + cc).ravel()[None, :]).ravel()
    values = ca.vertcat(ca.vec(negJ), ca.MX(1.0))  # the last entry: the constant 1
    src = np.concatenate([np.full(r_id.size, values.numel() - 1), s_j])
    return scatter(values, ((n - 1) * nx, nvar), np.concatenate([r_id, r_j]),
                   np.concatenate([c_id, c_j]), src)


def _block_diagonal(nx: int, nU: int, blocks: int, negJuT: ca.MX) -> ca.MX:
    """``(nx blocks) x (nU blocks)`` block-diagonal matrix whose block ``k`` is the
    transpose of columns ``k nx .. (k + 1) nx`` of ``negJuT`` (``nU x nx blocks``)."""
    # the transpose has the blocks of negJuT column by column: its nonzeros, in
    # compressed-column order, are vec(negJuT) as it is (no index list to build)
    pattern = ca.kron(ca.DM(ca.Sparsity.diag(blocks), 1.0), ca.DM.ones(nU, nx)).sparsity()
    return ca.MX(pattern, ca.vec(negJuT)).T


@dataclass(frozen=True)
class Collocation(Transcription):
    """Direct collocation with ``degree`` Radau (default) or Legendre points per sample
    interval. Radau degree 3 shows no numerical damping at slosh frequencies; degree 2
    does (about -0.3 % damping ratio)."""

    degree: int = 3
    scheme: str = "radau"

    def __post_init__(self) -> None:
        if self.scheme not in ("radau", "legendre"):
            raise ValueError(f"Collocation scheme must be 'radau' or 'legendre', got {self.scheme!r}")
        if not 1 <= self.degree <= 9:
            raise ValueError(f"Collocation degree must be 1..9, got {self.degree!r}")

    def _coefficients(self):
        tau = np.array([0.0] + ca.collocation_points(self.degree, self.scheme))
        d = self.degree
        C = np.zeros((d + 1, d + 1))  # C[j, r]: derivative of basis j at tau_r
        D = np.zeros(d + 1)  # basis values at tau = 1
        for j in range(d + 1):
            coeff = np.poly1d([1.0])
            for r in range(d + 1):
                if r != j:
                    coeff *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
            D[j] = coeff(1.0)
            deriv = np.polyder(coeff)
            for r in range(d + 1):
                C[j, r] = deriv(tau[r])
        return tau, C, D

    def fractions(self):
        tau, _, _ = self._coefficients()
        return tau[1:]

    def block(self, dm, p, t, U, x_guess, x0, theta=None, compiled=False, coefficients=None):
        n, nx, d = t.size, dm.nx, self.degree
        tau, C, D = self._coefficients()
        if U is None:
            U = coefficients.stage_inputs()
        W, X, w0x = _states_with_fixed_start(nx, n, x_guess, x0)
        xk = ca.SX.sym("xk", nx)
        xc = ca.SX.sym("xc", nx, d)
        uk = ca.SX.sym("u", dm.nu * d)
        ps = ca.SX.sym("p", p.numel())
        tk = ca.SX.sym("t")
        h = ca.SX.sym("h")
        pts = ca.horzcat(xk, xc)
        defects = []
        for r in range(1, d + 1):
            xp = sum(C[j, r] * pts[:, j] for j in range(d + 1))
            f = dm.rhs(pts[:, r], uk[(r - 1) * dm.nu:r * dm.nu], ps, tk + tau[r] * h)
            defects.append(xp - h * f)
        x_end = sum(D[j] * pts[:, j] for j in range(d + 1))
        interval = ca.Function("collocation_interval", [xk, ca.vec(xc), uk, ps, tk, h],
                               [ca.vertcat(*defects), x_end])
        XC = ca.MX.sym("XC", nx * d, n - 1)
        defect, xe = interval.map(n - 1)(X[:, :-1], XC, U, p, ca.DM(t[:-1]).T,
                                         ca.DM(np.diff(t)).T)
        g = ca.vertcat(ca.vec(defect), ca.vec(X[:, 1:] - xe))
        # guess of the collocation states: linear interpolation between sample states
        xg = np.asarray(x_guess)
        guess = np.concatenate([(xg[:, :-1] * (1 - tr) + xg[:, 1:] * tr) for tr in tau[1:]], axis=0)
        w = ca.vertcat(ca.vec(W), ca.vec(XC))
        return Block(w, np.concatenate([np.asarray(w0x).ravel(order="F"), guess.ravel(order="F")]), g, X)
