"""The legacy (SLOSH code) basis: Lomen's harmonic functions, Ritz-solved.

NASA CR-230 (Lomen), as updated by Dodge for the SwRI SLOSH code, expands the m = 1
potential in ``n_poly`` polynomial terms ``rho^(2n-1) P_(2n-1)^1(cos) cos(theta)`` (odd
solid harmonics about the sphere centre) and ``n_bessel`` terms
``J1(j_k r) exp(j_k (z - h)) cos(theta)`` with ``j_k = xi_k / r_s`` (``xi_k`` the zeros of
``J1'``, ``r_s`` the free-surface radius, ``h`` the liquid depth). Both families are
harmonic; the energy functional is minimised exactly as in the Ritz solver. With 10
functions the basis cannot represent the flow near the contact line above half full.

This is our reading of the basis from the issue's description; the original code's
quadrature and scaling are not public, so results differ from the published tables in
the last digits (see ``docs/tank-modes.md``).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh
from scipy.special import j1, jvp

from ._modes import RawModes
from ._ritz import solid_harmonics
from .geometry import Sphere, Tank, surface_rule

_XI = np.array([1.8411837813, 5.3314427735, 8.5363163663, 11.7060049025, 14.8635886339,
                18.0155278626, 21.1643698588, 24.3113268447])


def _basis(r: np.ndarray, z: np.ndarray, radius: float, depth: float, rs: float,
           n_poly: int, n_bessel: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Values U, U_r, U_z and U / r of the basis at points (r, z), shape (n, npts)."""
    x, y = r / radius, (z - radius) / radius
    q, qx, qy, u = solid_harmonics(x, y, 2 * n_poly)
    odd = slice(0, 2 * n_poly, 2)  # degrees 1, 3, 5, ...
    U = [u[odd]]
    Ur = [(q[odd] + x * qx[odd]) / radius]
    Uz = [x * qy[odd] / radius]
    Uo = [q[odd] / radius]
    k = _XI[:n_bessel, None] / rs
    e = np.exp(k * (z - depth))
    jr = j1(k * r)
    U.append(jr * e)
    Ur.append(k * jvp(1, k * r) * e)
    Uz.append(k * jr * e)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(r > 0, jr / np.where(r > 0, r, 1.0), 0.5 * k)
    Uo.append(ratio * e)
    return tuple(np.concatenate(v) for v in (U, Ur, Uz, Uo))  # type: ignore[return-value]


def solve(tank: Tank, depth: float, *, n_poly: int = 5, n_bessel: int = 5,
          n_modes: int = 2) -> RawModes:
    """Lateral modes in the Lomen basis (spheres only)."""
    if not isinstance(tank, Sphere):
        raise ValueError("the legacy Lomen basis is defined for `Sphere` tanks only; got "
                         f"{tank!r}. Use `method=\"exact\"`.")
    if not 1 <= n_modes <= n_poly + n_bessel:
        raise ValueError(f"`modes` must be at most {n_poly + n_bessel} for the legacy basis.")
    a_ = tank.radius
    rs = tank.wall_radius(depth)
    r, z, w = tank.section_rule(depth, 48, 64)
    U, Ur, Uz, Uo = _basis(r, z, a_, depth, rs, n_poly, n_bessel)
    wr = w * r
    K = (Ur * wr) @ Ur.T + (Uz * wr) @ Uz.T + (Uo * wr) @ Uo.T
    rf, wf, _ = surface_rule(tank, depth, 64)
    Uf = _basis(rf, np.full_like(rf, depth), a_, depth, rs, n_poly, n_bessel)[0]
    M = (Uf * wf * rf) @ Uf.T
    mu, vec = eigh(M, K)
    order = np.argsort(mu)[::-1][:n_modes]
    vec = vec[:, order]
    lam = 1.0 / mu[order]
    uf = Uf.T @ vec
    a = (wf * rf**2) @ uf
    b = (wf * rf) @ uf**2
    uw = _basis(np.array([rs]), np.array([depth]), a_, depth, rs, n_poly, n_bessel)[0].T @ vec
    moment = ((z * (Ur + Uo) - r * Uz) * wr).sum(axis=1) @ vec
    sgn = np.sign(a)
    sgn[sgn == 0] = 1.0
    return RawModes(lam=lam, a=a * sgn, b=b, u_wall=uw[0] * sgn, moment=moment * sgn,
                    size=n_poly + n_bessel)
