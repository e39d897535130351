"""The estimated carriage motion's representation (:mod:`estimate.fitting.carriage`): a
quintic B-spline on uniform or graded knots (:class:`CarriageSpline`), the spline with its
start coefficients and noise levels (:class:`CarriageInput`) and the excitation it drives
(:class:`SplineExcitation`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps
from scipy.interpolate import BSpline

from derive import Excitation

__all__ = ["CarriageInput", "CarriageSpline", "SplineExcitation"]


@dataclass(frozen=True)
class CarriageSpline:
    """A uniform B-spline of ``degree`` on ``knots`` (s); the spline is valid (full support)
    on ``[knots[degree], knots[-degree - 1]]``, which covers the record."""

    knots: np.ndarray = field(repr=False)
    degree: int = 5

    @classmethod
    def covering(cls, t0: float, t1: float, spacing: float, degree: int = 5) -> "CarriageSpline":
        """Uniform knots at most ``spacing`` apart whose spline is valid exactly on
        ``[t0, t1]`` (a knot on each end, so no basis function barely touches the record)."""
        m = max(int(np.ceil((t1 - t0) / spacing - 1e-9)), 1)
        knots = t0 + (t1 - t0) * np.arange(-degree, m + degree + 1) / m
        knots[degree], knots[m + degree] = t0, t1  # exact ends: no round-off outside
        return cls(knots, degree)

    @classmethod
    def graded(cls, t0: float, t1: float, spacing: float, moving: tuple[float, float],
               rest_spacing: float, degree: int = 5) -> "CarriageSpline":
        """Knots ``spacing`` apart while the carriage moves (``moving``, s) and at most
        ``rest_spacing`` apart where it rests, the spacing growing by at most half from one
        knot to the next; a knot on each end of ``[t0, t1]``."""
        a, b = max(moving[0], t0), min(moving[1], t1)
        if b - a >= t1 - t0 - 2 * spacing or rest_spacing <= spacing:
            return cls.covering(t0, t1, spacing, degree)
        inner = a + (b - a) * np.arange(max(int(np.ceil((b - a) / spacing)), 1) + 1) \
            / max(int(np.ceil((b - a) / spacing)), 1)
        right = _grown(b, t1, spacing, rest_spacing)
        left = a - (_grown(0.0, a - t0, spacing, rest_spacing))[::-1]
        inside = np.unique(np.r_[t0, left, inner, right, t1])
        inside = inside[(inside >= t0) & (inside <= t1)]
        keep = np.r_[True, np.diff(inside) > 0.5 * spacing]  # no knots closer than that
        inside = inside[keep]
        inside[-1] = t1
        h0, h1 = inside[1] - inside[0], inside[-1] - inside[-2]
        knots = np.r_[t0 - h0 * np.arange(degree, 0, -1), inside,
                      t1 + h1 * np.arange(1, degree + 1)]
        return cls(knots, degree)

    @property
    def spacing(self) -> float:
        """The smallest knot spacing (s)."""
        return float(np.min(np.diff(self.knots)))

    @property
    def n_coefficients(self) -> int:
        return self.knots.size - self.degree - 1

    def design(self, times: np.ndarray, derivative: int = 0) -> sps.csr_matrix:
        """``(len(times), n_coefficients)`` matrix mapping coefficients to the spline's
        ``derivative``-th time derivative at ``times`` (m, m/s, m/s^2)."""
        k, d, tau = self.degree, derivative, self.knots
        basis = BSpline.design_matrix(np.asarray(times, float), tau[d:tau.size - d], k - d)
        D = sps.identity(self.n_coefficients, format="csr")
        for j in range(d):
            m = self.n_coefficients - j
            # the derivative of a B-spline of degree q on knots tau is one of degree q - 1 on
            # tau[1:-1] with coefficients q (c[i+1] - c[i]) / (tau[i+q+1] - tau[i+1])
            q, knots = k - j, tau[j:tau.size - j]
            scale = q / (knots[q + 1:q + m] - knots[1:m])
            Dj = sps.diags([-scale, scale], [0, 1], shape=(m - 1, m))
            D = Dj @ D
        return (basis @ D).tocsr()

    def inputs_matrix(self, times: np.ndarray) -> sps.csr_matrix:
        """Matrix mapping coefficients to ``[x, xd, xdd]`` at every time, time by time
        (rows ``3 i``, ``3 i + 1``, ``3 i + 2``), the order of a column-major ``(3, n)``."""
        blocks = [self.design(times, d) for d in range(3)]
        n = len(times)
        order = np.arange(3 * n).reshape(3, n).T.ravel()  # interleave x, xd, xdd per time
        return sps.vstack(blocks, format="csr")[order]



def _grown(start: float, stop: float, spacing: float, largest: float) -> np.ndarray:
    """Knots from ``start`` towards ``stop`` (excluded unless reached), the spacing growing
    from ``spacing`` by half a step at a time up to ``largest``; the last interval stretched
    or merged so that ``stop`` is a knot."""
    out, h, x = [], spacing, start
    while x + h < stop - 1e-12:
        h = min(1.5 * h, largest)
        x += h
        out.append(x)
    if out and stop - out[-1] < 0.5 * h:
        out.pop()
    return np.array(out + [stop])


@dataclass(frozen=True)
class CarriageInput:
    """What the NLP needs to estimate one case's carriage motion.

    The estimated coefficients are those of ``spline`` mapped by ``basis`` (``None``: the
    identity); a record that starts at rest uses a basis whose splines all have zero
    velocity and acceleration at the first sample, so rest needs no constraint.

    Attributes
    ----------
    spline : CarriageSpline
        The representation of the displacement.
    basis : scipy.sparse matrix or None
        ``(spline.n_coefficients, n_coefficients)``: spline coefficients from estimated ones.
    coefficients : numpy.ndarray
        Start values (m): the least-squares spline through the measured displacement.
    displacement_noise : float
        Standard deviation of the noise on the recorded displacement (m): its white level
        above the signal band, or its quiet segments' level when larger.
    displacement : numpy.ndarray
        The recorded displacement without tones above the signal band (m), as fitted.
    displacement_tones : tuple of (float, float)
        The tones removed: frequency (Hz) and amplitude (m).
    at_rest : bool
        The record starts quiet: the carriage velocity and acceleration are 0 at ``t[0]``.
    coloured_noise : bool
        The displacement's noise is not white: the least-squares spline misses the record
        by more than :data:`~estimate.fitting.carriage.COLOURED_FACTOR` times the white
        level above the band (a displacement integrated from an accelerometer: its noise
        grows towards low frequencies), so ``displacement_noise`` is that misfit's standard deviation
        (``n - coefficients`` degrees of freedom).
    """

    spline: CarriageSpline
    basis: sps.spmatrix | None = field(repr=False)
    coefficients: np.ndarray = field(repr=False)
    displacement_noise: float
    displacement: np.ndarray = field(repr=False)
    displacement_tones: tuple[tuple[float, float], ...]
    at_rest: bool
    coloured_noise: bool = False
    _memo: dict = field(default_factory=dict, compare=False, repr=False)
    _shift_memo: dict = field(default_factory=dict, compare=False, repr=False)

    def taylor_designs(self, times: np.ndarray, order: int) -> tuple:
        """``design(times, d) / d!`` for ``d = 0..order`` as SciPy CSR matrices: the Taylor
        series of the spline shifted in time (a stream lag). Kept with this object."""
        import math

        t = np.asarray(times, float)
        key = ("scipy", t.tobytes(), order)
        if key not in self._shift_memo:
            self._shift_memo.clear()
            self._shift_memo[key] = tuple(self.design(t, d) / math.factorial(d)
                                          for d in range(order + 1))
        return self._shift_memo[key]

    def shift_design(self, times: np.ndarray, order: int) -> tuple:
        """:meth:`taylor_designs` on one sparsity (their union) as ``(pattern, V)``: column
        ``d`` of the dense ``nnz x (order + 1)`` matrix ``V`` (a CasADi MX constant) holds
        design ``d``'s values on the pattern's nonzeros, so the shifted design
        ``sum_d lag^d D_d`` has the nonzeros ``V [1, lag, ..., lag^order]``: one product
        where the sparse matrices took ``2 order`` (and converting them took twice as
        long). Kept with this object."""
        import casadi as ca

        from ._sparse import dense_dm

        t = np.asarray(times, float)
        key = ("shift", t.tobytes(), order)
        if key not in self._shift_memo:
            designs = [sps.csc_matrix(D) for D in self.taylor_designs(t, order)]
            for D in designs:  # converted copies: the kept designs stay as they are
                D.sum_duplicates()
            rows, cols = designs[0].shape
            ones = [sps.csc_matrix((np.ones(D.nnz), D.indices, D.indptr), D.shape)
                    for D in designs]
            union = sum(ones[1:], ones[0])  # the patterns' union (no entry cancels)
            union.sort_indices()

            def keys(D):  # column-major positions, ascending (sorted CSC)
                return np.repeat(np.arange(cols, dtype=np.int64) * rows,
                                 np.diff(D.indptr)) + D.indices

            where = keys(union)
            V = np.zeros((where.size, len(designs)))
            for d, D in enumerate(designs):
                V[np.searchsorted(where, keys(D)), d] = D.data
            pattern = ca.Sparsity(rows, cols, memoryview(union.indptr.astype(np.int64)),
                                  memoryview(union.indices.astype(np.int64)))
            # an MX constant: the shifted design and its velocity share one copy
            self._shift_memo[key] = (pattern, ca.MX(dense_dm(V)))
        return self._shift_memo[key]

    @property
    def n_coefficients(self) -> int:
        return self.spline.n_coefficients if self.basis is None else self.basis.shape[1]

    def design(self, times: np.ndarray, derivative: int = 0) -> sps.csr_matrix:
        """Estimated coefficients to the ``derivative``-th derivative at ``times``."""
        B = self.spline.design(times, derivative)
        return B if self.basis is None else (B @ self.basis).tocsr()

    def inputs_matrix(self, times: np.ndarray) -> sps.csr_matrix:
        """Estimated coefficients to ``[x, xd, xdd]`` time by time (see
        :meth:`CarriageSpline.inputs_matrix`)."""
        A = self.spline.inputs_matrix(times)
        return A if self.basis is None else (A @ self.basis).tocsr()

    def casadi_matrices(self, times: np.ndarray, fractions: np.ndarray):
        """``(A_stage, A_grid, B0)`` as sparse CasADi matrices: :meth:`inputs_matrix` at
        the stage times ``times[k] + fractions * (times[k+1] - times[k])`` and at ``times``,
        and :meth:`design` at ``times``."""
        return tuple(self.casadi_matrix(times, fractions, which)
                     for which in ("stage", "grid", "displacement"))

    def casadi_matrix(self, times: np.ndarray, fractions: np.ndarray, which: str):
        """One of :meth:`casadi_matrices` (``"stage"``, ``"grid"`` or ``"displacement"``),
        converted at the first request and kept with this object (every fit of the record
        reuses it: the diagnosis fits many models to it). The condensed shooting needs
        none but the displacement's, whose 30,001-sample conversion takes 0.04 s, the
        stage matrix's 0.4 s."""
        from ._sparse import sparse_dm

        memo = self._grid(times, fractions)
        if which not in memo:
            S_stage, S_grid = memo["scipy"]
            memo[which] = sparse_dm({"stage": S_stage, "grid": S_grid,
                                     "displacement": S_grid[::3]}[which])
        return memo[which]

    def scipy_matrices(self, times: np.ndarray, fractions: np.ndarray):
        """``(A_stage, A_grid)`` of :meth:`casadi_matrices` as SciPy CSR matrices. Kept
        with this object."""
        return self._grid(times, fractions)["scipy"]

    def grid_cache(self, times: np.ndarray, fractions: np.ndarray) -> dict:
        """What is kept for the sample grid ``times`` and stage ``fractions`` (only the
        last grid's things are kept: they are large): these matrices, and what a
        transcription derives from them and may reuse in another fit of the record."""
        return self._grid(times, fractions)

    def _grid(self, times: np.ndarray, fractions: np.ndarray) -> dict:
        """The matrices of one sample grid (only the last grid's are kept: they are
        large)."""
        t = np.asarray(times, float)
        fr = np.asarray(fractions, float)
        key = (t.tobytes(), fr.tobytes())
        if self._memo.get("key") != key:
            stage_times = (t[:-1, None] + np.diff(t)[:, None] * fr[None, :]).ravel()
            self._memo.clear()
            S_stage = self.inputs_matrix(stage_times).tocsr()
            if fr[0] == 0.0 and fr[-1] == 1.0:
                # the grid times are stage times (each interval's first, and the last
                # interval's end): rows of the stage matrix
                m, n = fr.size, t.size
                k, i = np.arange(n)[:, None], np.arange(3)[None, :]
                rows = np.where(k < n - 1, 3 * m * k + i, 3 * m * (n - 2) + 3 * (m - 1) + i)
                S_grid = S_stage[rows.ravel()]
            else:
                S_grid = self.inputs_matrix(t).tocsr()
            self._memo.update(key=key, scipy=(S_stage, S_grid))
        return self._memo

    def values(self, coefficients: np.ndarray, times: np.ndarray) -> np.ndarray:
        """``(3, len(times))``: displacement (m), velocity (m/s), acceleration (m/s^2)."""
        c = np.asarray(coefficients, float)
        spline = BSpline(self.spline.knots, c if self.basis is None else self.basis @ c,
                         self.spline.degree)
        t = np.asarray(times, float)
        return np.vstack([spline(t, nu=d) for d in range(3)])

    def excitation(self, coefficients: np.ndarray) -> "SplineExcitation":
        """The carriage motion of ``coefficients`` as a rig excitation."""
        return SplineExcitation(self, np.asarray(coefficients, float))


@dataclass(frozen=True)
class SplineExcitation(Excitation):
    """An estimated carriage motion (:class:`CarriageInput` and its coefficients) as the
    rig excitation: the spline's exact displacement (m), velocity (m/s) and acceleration
    (m/s^2) at any time of the record."""

    carriage: CarriageInput = field(repr=False)
    coefficients: np.ndarray = field(repr=False)

    def values(self, t: np.ndarray) -> np.ndarray:
        return self.carriage.values(self.coefficients, t)


def _rest_basis(spline: CarriageSpline, t0: float) -> sps.csr_matrix:
    """Basis of the splines with zero velocity and acceleration at ``t0``: the first two
    coefficients follow from the others, ``c01 = -C01^-1 C_rest c_rest``."""
    C = sps.vstack([spline.design([t0], 1), spline.design([t0], 2)]).toarray()
    n = spline.n_coefficients
    head = -np.linalg.solve(C[:, :2], C[:, 2:])
    return sps.vstack([sps.csr_matrix(head), sps.identity(n - 2, format="csr")]).tocsr()
