"""Rayleigh-Ritz with harmonic polynomials (solid harmonics ``rho^k P_k^1 cos(theta)``).

Every basis function is harmonic, so only the wall condition (natural in the energy
functional) and the free-surface condition are approximated. The generalized
eigenproblem ``K c = lambda M c`` with ``K = int_V grad phi_i . grad phi_j`` and
``M = int_F phi_i phi_j`` is solved in a basis orthonormalised in energy by an SVD of the
weighted gradient samples, which keeps high degrees usable on thin or deep domains.
The harmonics are expanded about the centre of the free surface and scaled by the
largest distance from it to the wetted wall.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh, svd

from ._modes import RawModes
from .geometry import Tank, surface_rule


def solid_harmonics(x: np.ndarray, y: np.ndarray, degree: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """m = 1 solid harmonics ``S_k = rho^k P_k^1`` (k = 1..degree) as ``S_k = x q_k``.

    ``x`` is the (scaled) radius, ``y`` the (scaled) axial coordinate. Returns ``q``,
    ``dq/dx``, ``dq/dy`` with shape ``(degree, npoints)`` and, for convenience, ``U = x q``.
    Recurrence ``k S_{k+1} = (2k+1) y S_k - (k+1) rho^2 S_{k-1}`` (Condon-Shortley sign
    dropped), applied to ``q = S / x``.
    """
    n = x.size
    q = np.zeros((degree + 1, n))
    qx = np.zeros_like(q)
    qy = np.zeros_like(q)
    rho2 = x * x + y * y
    q[1] = 1.0
    for k in range(1, degree):
        q[k + 1] = ((2 * k + 1) * y * q[k] - (k + 1) * rho2 * q[k - 1]) / k
        qx[k + 1] = ((2 * k + 1) * y * qx[k]
                     - (k + 1) * (2.0 * x * q[k - 1] + rho2 * qx[k - 1])) / k
        qy[k + 1] = ((2 * k + 1) * (q[k] + y * qy[k])
                     - (k + 1) * (2.0 * y * q[k - 1] + rho2 * qy[k - 1])) / k
    return q[1:], qx[1:], qy[1:], x * q[1:]


def _centre_scale(tank: Tank, depth: float, centre: float | None) -> tuple[float, float]:
    """Expansion centre on the axis (m) and length scale (m): the largest distance from
    the centre to the wetted boundary, so that the scaled domain lies in the unit ball."""
    zc = 0.5 * depth if centre is None else centre
    _, z, _ = tank.section_rule(depth, 2, 64)
    zz = np.concatenate([z, [0.0, depth]])
    rr = np.array([tank.wall_radius(float(v)) for v in zz])
    return zc, float(np.max(np.hypot(rr, zz - zc)))


def solve(tank: Tank, depth: float, *, degree: int = 36, n_modes: int = 4,
          rcond: float = 1e-12, centre: float | None = None) -> RawModes:
    """Lateral sloshing modes by Ritz with solid harmonics of degree 1..``degree``."""
    zc, ell = _centre_scale(tank, depth, centre)
    nt, ns = degree + 4, degree + 8
    r, z, w = tank.section_rule(depth, nt, ns)
    x, y = r / ell, (z - zc) / ell
    q, qx, qy, u = solid_harmonics(x, y, degree)
    ur = (q + x * qx) / ell
    uz = x * qy / ell
    sw = np.sqrt(w * r)
    a_mat = np.concatenate([(ur * sw).T, (uz * sw).T, (q / ell * sw).T])  # U/r = q/ell
    norms = np.linalg.norm(a_mat, axis=0)
    a_mat /= norms
    _, sig, vt = svd(a_mat, full_matrices=False, lapack_driver="gesdd")
    keep = sig > rcond * sig[0]
    coef = (vt[keep].T / sig[keep]) / norms[:, None]  # K-orthonormal combinations

    rf, wf, rs = surface_rule(tank, depth, degree + 6)
    qf, _, _, uf = solid_harmonics(rf / ell, np.full_like(rf, (depth - zc) / ell), degree)
    uf_red = uf.T @ coef
    m_red = (uf_red * (wf * rf)[:, None]).T @ uf_red
    mu, vec = eigh(m_red)
    order = np.argsort(mu)[::-1][:n_modes]
    mu, vec = mu[order], vec[:, order]
    c = coef @ vec  # coefficients of the solid harmonics, energy-normalised modes

    lam = 1.0 / mu
    uf_modes = uf.T @ c
    a = (wf * rf**2) @ uf_modes
    b = (wf * rf) @ uf_modes**2
    _, _, _, uw = solid_harmonics(np.array([rs / ell]), np.array([(depth - zc) / ell]), degree)
    u_wall = (uw.T @ c)[0]
    integrand = (z * (ur + q / ell) - r * uz) * (r * w)
    moment = integrand.sum(axis=1) @ c
    # a fixed sign convention: positive a
    sgn = np.sign(a)
    sgn[sgn == 0] = 1.0
    return RawModes(lam=lam, a=a * sgn, b=b, u_wall=u_wall * sgn, moment=moment * sgn,
                    size=int(keep.sum()))
