"""Uncertainty of the estimates.

The Gauss-Newton covariance of an equality-constrained least-squares problem: with ``e``
the residuals (each divided by its scale), ``g(w) = 0`` the transcription's constraints and
``w`` all decision variables (parameters, states, carriage coefficients, free initial
states), the covariance of the parameters is ``s^2`` times their block of the inverse of
the KKT matrix ``[[J_e^T J_e, J_g^T], [J_g, 0]]``: the inverse of the information reduced to
the constraint manifold, with states eliminated and nuisance variables (carriage motion,
free initial states) marginalised. ``s^2 = |e|^2 / (n - k)`` is the residual variance (``k``
counts every estimated quantity). One sparse LU factorisation, a solve per parameter.

Beside it, a covariance robust to heteroscedastic and autocorrelated residuals
(:func:`robust_covariance`): a sandwich ``S^-1 Omega S^-1``. A coloured noise, a force
filtered before fitting or a model that misses a small effect leave residuals correlated over
many samples and larger where the model errs; the Gauss-Newton covariance then under-states
the spread of the estimates. The long-run middle ``Omega`` is split in two: the lag-0 middle
of every residual, times, per parameter, the widening that the Newey-West (Bartlett kernel,
Andrews' 1991 bandwidth) long-run covariance of the measured channels' scores gives over their
lag-0 covariance, never below 1. The plain Newey-West middle is not used because the estimated
carriage motion (hundreds of nuisance coefficients) takes a share of the residuals that it
reads as precision: 0.67 times the Gauss-Newton standard error of the pendulum length on the
bundled example, whose residuals are white. Nor can residuals show the noise the estimated
carriage motion absorbed inside its band, where a sine record's information is: no
parameter's variance is left below that of the sandwich on the channels' noise spectra
(:mod:`estimate.fitting.spectral_sandwich`).

The residual sensitivity to the parameters alone (states follow through the constraints,
nuisance variables held) is kept for the identifiability check and the diagnosis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .identifiability import Identifiability, analyse
from .kkt import factorise
from .spectral_sandwich import spectral_middle

__all__ = ["Uncertainty", "reduced_jacobian", "robust_covariance", "uncertainty"]


def reduced_jacobian(jac_residuals: sps.spmatrix, jac_constraints: sps.spmatrix, ntheta: int,
                     scales: np.ndarray, held: list[int] = ()) -> np.ndarray:
    """Total derivative of the residuals w.r.t. the (unscaled) estimates, the states
    following through ``g(theta, z) = 0``: ``dz/dtheta = -g_z^-1 g_theta`` and
    ``dr/dtheta = r_theta + r_z dz/dtheta``; the columns ``held`` (nuisance variables) are
    neither parameters nor states."""
    Jr = sps.csc_matrix(jac_residuals)
    Jg = sps.csc_matrix(jac_constraints)
    pcols = list(range(ntheta))
    zcols = np.setdiff1d(np.arange(Jr.shape[1]), pcols + list(held))
    R_p = Jr[:, pcols].toarray()
    if Jg.shape[0]:
        dz = -spla.splu(Jg[:, zcols].tocsc()).solve(Jg[:, pcols].toarray())
        J = R_p + Jr[:, zcols] @ dz
    else:
        J = R_p
    return np.asarray(J) / scales[None, :]


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of the estimates (their units squared), standard errors, correlations,
    the residual variance ``sigma2`` and the identifiability analysis.

    Parameters held at an active bound (``held`` of :func:`uncertainty`) have no Wald
    standard error: their rows and columns of ``covariance`` are zero (they stay at the
    bound), their ``stderr`` and correlations are NaN and they are left out of the
    identifiability analysis; ``bound_stderr`` gives, for them only, the standard deviation
    of the estimate the data would allow if the bound were lifted (the others re-estimated),
    NaN when the data do not determine it.

    The truth may lie off the bound, inside: the covariance conditional on the bound then
    states the others too precisely (a spring held at 0 makes a pendulum length take up the
    spring's share of the frequency, with the length's conditional interval 70 standard
    errors from the truth). ``bound_reach[:, h]`` is how far the others' estimates move
    when the held estimate ``h`` moves one ``bound_stderr`` off its bound in the positive
    direction (its own row: that standard deviation), the others re-estimated: the joint
    regression of the estimates on the held ones in the covariance without the bounds. The
    intervals reach that far along it (:mod:`estimate.fitting.intervals`).
    """

    covariance: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    sigma2: float
    identifiability: Identifiability
    warnings: tuple[str, ...]
    bound_stderr: np.ndarray | None = None
    #: The covariance robust to autocorrelated residuals (:func:`robust_covariance`), held
    #: parameters' rows and columns zero; ``None`` when the residuals' times were not given.
    robust: np.ndarray | None = None
    #: The Newey-West bandwidth (lags, samples) of each case's scores.
    bandwidths: tuple[int, ...] = ()
    bound_reach: np.ndarray | None = None


def uncertainty(jac_residuals: sps.spmatrix, jac_constraints: sps.spmatrix,
                residuals: np.ndarray, n_observations: int, ntheta: int, scales: np.ndarray,
                names: tuple[str, ...], held: tuple[int, ...] = (),
                samples: "list[np.ndarray] | None" = None,
                bands: "list[float] | None" = None) -> Uncertainty:
    """The Gauss-Newton covariance of the first ``ntheta`` decision variables (scaled by
    ``scales``) from the sparse residual and constraint Jacobians at the optimum; the
    parameters ``held`` (indices, at an active bound) are held there (see
    :class:`Uncertainty`). ``samples``, per case, gives the sample index of each of its
    residuals (cases in the order of the residuals, each case's residuals contiguous): with
    it, the robust covariance is computed too (:func:`robust_covariance`; ``bands`` as
    :func:`~estimate.fitting.spectral_sandwich.spectral_middle`'s)."""
    Je = sps.csc_matrix(jac_residuals)
    Jg = sps.csc_matrix(jac_constraints)
    nw, ng = Je.shape[1], Jg.shape[0]
    k = nw - ng  # estimated quantities: variables the constraints leave free
    sigma2 = float(residuals @ residuals) / max(n_observations - k, 1)
    def undetermined(why: str) -> Uncertainty:
        nan = np.full((ntheta, ntheta), np.nan)
        return Uncertainty(nan, np.full(ntheta, np.nan), nan.copy(), sigma2,
                           Identifiability(np.zeros(0), float("inf"), (), ()),
                           (f"the fit ended where {why} (it diverged): no covariance",),
                           np.full(ntheta, np.nan))

    if not (np.isfinite(Je.data).all() and np.isfinite(Jg.data).all() and np.isfinite(sigma2)):
        # a fit that diverged (IPOPT's Invalid_Number_Detected: a 60 s spinning-rig record
        # whose simulation overflowed) ends where its sensitivities are not numbers
        return undetermined("the model's sensitivities are not finite")
    try:
        kkt = ReducedKKT(Je, Jg, ntheta)
    except (RuntimeError, np.linalg.LinAlgError):
        # SuperLU's "Factor is exactly singular": the states' KKT block at a point where
        # the fit was last finite (a spinning-rig rotor fit whose simulation overflowed)
        return undetermined("the states' KKT block is singular")
    S = kkt.information
    if not np.all(np.isfinite(S)):
        return undetermined("the parameters' information is not finite")
    free = np.setdiff1d(np.arange(ntheta), np.asarray(held, int))
    # a prior of relative standard deviation 1e3 on every (scaled) parameter: nothing for
    # what the data determine, a huge finite variance for a direction they do not
    X, singular = _inverse(S[np.ix_(free, free)])
    warnings = []
    if singular:
        warnings.append("the residual sensitivity is singular: the data do not determine some "
                        "directions of the parameters (see the identifiability check)")
    cov = np.zeros((ntheta, ntheta))
    cov[np.ix_(free, free)] = sigma2 * X * np.outer(scales[free], scales[free])
    d = np.full(ntheta, np.nan)
    d[free] = np.sqrt(np.clip(np.diag(cov)[free], 0, None))
    corr = np.full((ntheta, ntheta), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        sub = cov[np.ix_(free, free)] / np.outer(d[free], d[free])
    corr[np.ix_(free, free)] = np.clip(np.nan_to_num(sub, nan=0.0, posinf=0.0, neginf=0.0),
                                       -1.0, 1.0)
    ident = analyse(cov[np.ix_(free, free)], scales[free], tuple(names[i] for i in free),
                    corr[np.ix_(free, free)])
    bound_se = np.full(ntheta, np.nan)
    reach = None
    if len(free) < ntheta:
        Xall, _ = _inverse(S)
        h = np.asarray(held, int)
        spread = np.sqrt(sigma2 * np.diag(Xall)[h]) * scales[h]
        determined = np.diag(Xall)[h] < 1 / (10 * _PRIOR_INFORMATION)
        bound_se[h[determined]] = spread[determined]
        # undetermined ones reach by the prior's spread: far, unless nothing correlates
        slope = Xall[:, h] @ np.linalg.inv(Xall[np.ix_(h, h)])  # scaled d theta / d theta_h
        reach = np.zeros((ntheta, ntheta))
        reach[:, h] = slope * np.outer(scales, spread / scales[h])
    robust, lags = None, ()
    if samples is not None:
        Xs = np.zeros((ntheta, ntheta))  # held parameters: zero rows and columns
        Xs[np.ix_(free, free)] = X
        robust, lags = robust_covariance(Xs, kkt.effective_jacobian(), residuals, samples,
                                         n_observations / max(n_observations - k, 1),
                                         step=lambda w: kkt.Je @ kkt.step(w), bands=bands)
        robust = robust * np.outer(scales, scales)
    return Uncertainty(cov, d, corr, sigma2, ident, tuple(warnings), bound_se, robust, lags,
                       reach)


def robust_covariance(information_inverse: np.ndarray, effective_jacobian: np.ndarray,
                      residuals: np.ndarray, samples: list[np.ndarray], dof_factor: float = 1.0,
                      step=None, bands: list[float] | None = None
                      ) -> tuple[np.ndarray, tuple[int, ...]]:
    """The covariance of the (scaled) parameters robust to heteroscedastic and autocorrelated
    residuals, and the Newey-West bandwidth of each case.

    ``information_inverse`` is ``S^-1``; ``effective_jacobian`` the residuals' sensitivity
    to the parameters, everything else following (:meth:`ReducedKKT.effective_jacobian`);
    ``samples``, per case, the sample index of each of its residual rows (-1: not a measured
    channel's row, e.g. the displacement's); ``dof_factor`` ``n / (n - k)``, as the
    Gauss-Newton variance counts the estimated quantities.

    The sandwich ``S^-1 Omega_0 S^-1`` over every residual (``Omega_0 = sum J_i^T J_i e_i^2``,
    heteroscedasticity-consistent) is widened, parameter by parameter, by how much the
    autocorrelation of the measured channels' scores ``s_t = sum_rows(t) J_row e_row`` widens
    their sandwich: the ratio of its Newey-West long-run middle (Bartlett kernel, Andrews'
    bandwidth) to its lag-0 middle, never below 1 (the estimated carriage motion takes part
    of the residual, which leaves the scores slightly anticorrelated without making the
    estimates any better).

    With ``step`` (the change of the residuals by the Gauss-Newton step from residuals
    ``w``), no parameter's variance is left below that of the sandwich on the channels'
    noise spectra (:mod:`estimate.fitting.spectral_sandwich`): the residuals do not hold the
    noise the estimated carriage motion absorbed, in the band where the information is."""
    J, e = effective_jacobian, residuals
    X = information_inverse
    lag0_all = (J * e[:, None] ** 2).T @ J
    long_run, lag0, lags = _long_run_scores(J, e, samples)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.diag(X @ long_run @ X) / np.diag(X @ lag0 @ X)
    widen = np.sqrt(np.where(np.isfinite(ratio), np.maximum(ratio, 1.0), 1.0))
    cov = dof_factor * (X @ lag0_all @ X) * np.outer(widen, widen)
    if step is not None:
        spectral = np.diag(X @ spectral_middle(J, e, samples, step, bands) @ X)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = spectral / np.diag(cov)
        more = np.sqrt(np.where(np.isfinite(r), np.maximum(r, 1.0), 1.0))
        cov = cov * np.outer(more, more)
    return cov, lags


def _long_run_scores(J: np.ndarray, e: np.ndarray, samples: list[np.ndarray]
                     ) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """Newey-West long-run and lag-0 covariances of the scores ``s_t`` (rows of one sample
    time summed; rows with sample index -1 left out), per case, summed over cases."""
    p = J.shape[1]
    long_run, lag0 = np.zeros((p, p)), np.zeros((p, p))
    lags = []
    start = 0
    for idx in samples:
        idx = np.asarray(idx, int)
        rows = slice(start, start + idx.size)
        start += idx.size
        use = idx >= 0
        scores = np.zeros((int(idx.max()) + 1 if np.any(use) else 0, p))
        np.add.at(scores, idx[use], J[rows][use] * e[rows][use, None])
        L = _andrews_bandwidth(scores)
        lags.append(L)
        long_run += _bartlett(scores, L)
        lag0 += scores.T @ scores
    return 0.5 * (long_run + long_run.T), lag0, tuple(lags)


def _bartlett(s: np.ndarray, lags: int) -> np.ndarray:
    """``sum_{|l| <= lags} (1 - |l| / (lags + 1)) Gamma_l`` of the score series ``s``."""
    out = s.T @ s
    for lag in range(1, min(lags, s.shape[0] - 1) + 1):
        g = s[lag:].T @ s[:-lag]
        out += (1.0 - lag / (lags + 1)) * (g + g.T)
    return out


def _andrews_bandwidth(s: np.ndarray) -> int:
    """Andrews' (1991) plug-in bandwidth of the Bartlett kernel from AR(1) fits to each
    score series: ``1.1447 (alpha T)^(1/3)``, at most a quarter of the series."""
    T = s.shape[0]
    if T < 8:
        return 0
    num = den = 0.0
    for a in s.T:
        a = a - a.mean()
        d = float(a[:-1] @ a[:-1])
        if not 0 < d < np.inf:
            continue
        a = a / np.sqrt(d / a.size)  # every score weighs alike (Andrews' unit weights)
        rho = float(np.clip(a[1:] @ a[:-1] / (a[:-1] @ a[:-1]), -0.97, 0.97))
        var = float(np.mean((a[1:] - rho * a[:-1]) ** 2))
        num += 4 * rho**2 * var**2 / ((1 - rho) ** 6 * (1 + rho) ** 2)
        den += var**2 / (1 - rho) ** 4
    if den <= 0:
        return 0
    return int(min(np.ceil(1.1447 * (num / den * T) ** (1 / 3)), T // 4))


def _inverse(S: np.ndarray) -> tuple[np.ndarray, bool]:
    """Inverse of the (scaled) information with the prior floor, and whether it is
    singular without it."""
    if S.size == 0:
        return np.zeros((0, 0)), False
    lam, V = np.linalg.eigh(0.5 * (S + S.T))
    singular = bool(lam.min() <= _PRIOR_INFORMATION * max(lam.max(), 1.0) * 1e-3)
    return (V / np.maximum(lam, _PRIOR_INFORMATION)) @ V.T, singular


#: Information floor of each scaled parameter's direction (relative variance 1e6 at most):
#: a weak prior that is nothing for what the data determine, and a huge finite variance
#: for a direction they do not.
_PRIOR_INFORMATION = 1e-6


class ReducedKKT:
    """The Gauss-Newton KKT matrix ``[[H, Jg^T], [Jg, 0]]`` (``H = Je^T Je``) of an
    equality-constrained least-squares problem, reduced onto its first ``ntheta`` variables
    (the parameters): every other variable (states, carriage coefficients, free initial
    states) is eliminated with one sparse factorisation of its own KKT block ``K0``.

    ``information`` is the Schur complement ``H_tt - B^T K0^-1 B`` (the parameters'
    Gauss-Newton information with the rest marginalised), ``inverse_information`` its
    inverse (eigenvalues floored by a weak prior); :meth:`step` solves the whole system."""

    def __init__(self, Je: sps.spmatrix, Jg: sps.spmatrix, ntheta: int) -> None:
        Je, Jg = sps.csc_matrix(Je), sps.csc_matrix(Jg)
        H = (Je.T @ Je).tocsc()
        p = ntheta
        self.ntheta, self.nw, self.ng = p, H.shape[0], Jg.shape[0]
        self.Je, self.Jg = Je, Jg
        self.Htt = H[:p, :p].toarray()
        Hrr, Hrt = H[p:, p:], H[p:, :p]
        Gr, Gt = Jg[:, p:], Jg[:, :p]
        self.n_primal = Hrr.shape[0]
        if self.n_primal + self.ng == 0:
            self._solve, self.B, self.Y = None, np.zeros((0, p)), np.zeros((0, p))
        else:
            K0 = sps.bmat([[Hrr, Gr.T], [Gr, None]], format="csc") if self.ng else Hrr
            self.B = sps.vstack([Hrt, Gt]).toarray() if self.ng else Hrt.toarray()
            self._solve = factorise(K0, self.n_primal)
            self.Y = self._solve(self.B)
        S = self.Htt - self.B.T @ self.Y
        self.information = 0.5 * (S + S.T)
        if not np.all(np.isfinite(self.information)):
            # overflowed (a point where the fit was last finite): :func:`uncertainty` says
            # so; eigh would raise
            self.singular, self.inverse_information = True, np.full_like(S, np.nan)
            return
        lam, V = np.linalg.eigh(self.information)
        self.singular = bool(lam.min() <= _PRIOR_INFORMATION * max(lam.max(), 1.0) * 1e-3)
        self.inverse_information = (V / np.maximum(lam, _PRIOR_INFORMATION)) @ V.T

    def effective_jacobian(self) -> np.ndarray:
        """``(residuals, ntheta)``: the residuals' sensitivity to the (scaled) parameters
        with the states following through the constraints and the nuisance variables
        re-optimised; its Gram matrix is :attr:`information`."""
        Je = self.Je
        Jt = Je[:, :self.ntheta].toarray()
        if self.n_primal == 0:
            return Jt
        return Jt - np.asarray(Je[:, self.ntheta:] @ self.Y[:self.n_primal])

    def gradient(self, residuals: np.ndarray, constraints: np.ndarray | None = None) -> np.ndarray:
        """The reduced steepest-descent direction of the parameters, ``-dS/dtheta / 2`` with
        every other variable following (states through the linearised constraints, nuisance
        variables re-optimised): with :attr:`information` ``S``, the Gauss-Newton step of
        the parameters is ``S^-1 b`` and it lowers the objective by ``b^T S^-1 b``."""
        g = np.zeros(self.ng) if constraints is None else np.asarray(constraints, float)
        b = -(self.Je.T @ residuals)
        b_t, b_r = b[:self.ntheta], np.r_[b[self.ntheta:], -g]
        y = self._solve(b_r[:, None])[:, 0] if self._solve is not None else b_r
        return b_t - self.B.T @ y

    def step(self, residuals: np.ndarray, constraints: np.ndarray | None = None) -> np.ndarray:
        """The Gauss-Newton step ``dw`` of all variables from a point with ``residuals`` ``e``
        and constraint values ``g``: minimises ``|e + Je dw|^2`` subject to
        ``g + Jg dw = 0``."""
        g = np.zeros(self.ng) if constraints is None else np.asarray(constraints, float)
        b = -(self.Je.T @ residuals)
        b_t, b_r = b[:self.ntheta], np.r_[b[self.ntheta:], -g]
        y = self._solve(b_r[:, None])[:, 0] if self._solve is not None else b_r
        x_t = self.inverse_information @ (b_t - self.B.T @ y)
        x_r = y - self.Y @ x_t
        return np.r_[x_t, x_r[:self.n_primal]]


def parameter_information(Je: sps.spmatrix, Jg: sps.spmatrix, ntheta: int) -> np.ndarray:
    """Gauss-Newton information of the first ``ntheta`` variables (see :class:`ReducedKKT`)."""
    return ReducedKKT(Je, Jg, ntheta).information
