"""The legacy (SLOSH code) solver: Lomen's trial functions, Dodge's analog formulas.

NASA CR-230 (Lomen), as updated by Dodge for the SwRI SLOSH code ("The New Dynamic
Behavior of Liquids in Moving Containers", 2000, pp. 60-64), writes the m = 1 potential
``phi = U(r, z) cos(theta)`` with, in coordinates scaled by the free-surface radius
``a`` (``R = r / a``, ``Z = (z - h) / a``, ``h`` the liquid depth):

* ``M = 5`` "shallow tank" functions ``U_n = R^(2n-1)`` (n = 1..M). They depend on ``r``
  only and, except ``R``, are **not harmonic**: the method is a Rayleigh-Ritz on the
  energy functional, not a harmonic expansion (reading them as solid harmonics
  ``rho^(2n-1) P_(2n-1)^1`` loses the seed's digits: 40 % fixed mass 0.477 kg, 80 %
  first frequency 0.006 Hz low);
* ``N - M = 5`` "deep tank" functions ``U = J1(xi_k R) exp(xi_k Z)``, ``xi_k`` the zeros of
  ``J1'`` (1.8412, 5.3314, ...), scaled by the free-surface radius, decaying from the
  free surface.

The eigenproblem ``A c = lambda B c`` has ``A_mn = int (U_m,r U_n,r + U_m,z U_n,z +
U_m U_n / r^2) r dr dz`` over the liquid's meridian section (the kinetic energy) and
``B_mn = int_0^a U_m U_n r dr`` over the free surface (the potential energy). We
integrate both to convergence with Gauss rules on the exact sphere (the seed's liquid
masses are the exact sphere's). SLOSH-ML's masked 200 x 200 Simpson rule moves results
by up to one printed digit, its 19-segment polygonal sphere by up to 13; the tables do
not pin the original quadrature beyond "accurate".

The analog quantities are Dodge's: slosh mass ``rho pi lambda a_n^2 / b_n``, length
``1 / lambda``, wave/bob ratio ``lambda U(a, h) a_n / b_n`` (as for the exact solvers) and
the **hinge height**

    ``H_n = L_n - h + 2 S_n / (lambda_n a_n)``,
    ``S_n = int_0^h z r_w(z) U_n(r_w(z), z) dz``  (along the wetted wall),

heights from the tank bottom. For an exact mode this is the moment of the wall pressure
(for a flat-bottom cylinder it gives the SP-106 bob height ``h - (2a/xi) tanh(xi h/2a)``);
with the truncated trial functions, which do not satisfy the wall condition, it moves
the hinge of a sphere off the centre: 0.1024/0.1043/0.1088 m (mode 1) and
0.0997/0.0995/0.0946 m (mode 2) at 60/70/80 %, the seed's 0.102/0.104/0.109 and
0.100/0.100/0.095. ``RawModes.moment`` carries it as ``2 S_n - h lambda_n a_n`` so that
:func:`analogs.tank.predict`'s ``moment / (lambda a) + 1 / lambda`` returns ``H_n`` and
its fixed-mass height uses Dodge's bob heights ``H_n - L_n``.

The open re-implementation SLOSH-ML (Georgia Tech LGST lab, ``functions/core.m``,
``phi.m``, ``Aint.m``, ``derivedparams.m``) follows the same pages; these conventions
were read there and checked against every number of the seed's Tables 1 and 8
(``docs/tank-modes.md``).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh
from scipy.special import j1, jvp

from ._modes import RawModes
from .geometry import Sphere, Tank, surface_rule

#: Zeros of ``J1'`` (NASA SP-106's xi_n).
_XI = np.array([1.8411837813406593, 5.3314427735250325, 8.5363163663462361,
                11.706004902592064, 14.863588633909034, 18.015527862681804,
                21.164369859188788, 24.311326857210776])


def _basis(r: np.ndarray, z: np.ndarray, a: float, depth: float, n_poly: int,
           n_bessel: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lomen's trial functions ``U`` and their derivatives ``U_r``, ``U_z`` at ``(r, z)``
    (m); shape ``(n_poly + n_bessel, npoints)``, ``U`` dimensionless."""
    x = r / a
    k = np.arange(1, 2 * n_poly, 2)[:, None]  # powers 1, 3, 5, ...
    u_p = x**k
    ur_p = k * x ** (k - 1) / a
    xi = _XI[:n_bessel, None]
    e = np.exp(xi * (z - depth) / a)
    u_b = j1(xi * x) * e
    ur_b = xi * jvp(1, xi * x) * e / a
    uz_b = xi * u_b / a
    return (np.concatenate([u_p, u_b]), np.concatenate([ur_p, ur_b]),
            np.concatenate([np.zeros_like(u_p), uz_b]))


def _depth_rule(depth: float, a: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss rule on ``[0, depth]`` (m), panels graded towards the free surface
    where the fastest deep-tank function decays over ``a / xi_5``."""
    edges = [depth]
    step = a / _XI[4]
    while edges[-1] - step > 0.0:
        edges.append(edges[-1] - step)
        step *= 3.0
    edges.append(0.0)
    x, w = np.polynomial.legendre.leggauss(n)
    zs, ws = [], []
    for hi, lo in zip(edges[:-1], edges[1:]):
        zs.append(0.5 * (hi + lo) + 0.5 * (hi - lo) * x)
        ws.append(0.5 * (hi - lo) * w)
    return np.concatenate(zs), np.concatenate(ws)


def solve(tank: Tank, depth: float, *, n_poly: int = 5, n_bessel: int = 5,
          n_modes: int = 2, n_quad: int = 24) -> RawModes:
    """Lateral modes in Lomen's trial functions (spheres only), Dodge's hinge heights.

    ``n_quad`` Gauss points per direction and depth panel; the default integrates to
    round-off (the tables' digits do not change from 16 points up).
    """
    if not isinstance(tank, Sphere):
        raise ValueError("the legacy Lomen basis is defined for `Sphere` tanks only; got "
                         f"{tank!r}. Use `method=\"exact\"`.")
    if not 1 <= n_bessel <= _XI.size:
        raise ValueError(f"`n_bessel` must be from 1 to {_XI.size}; got {n_bessel!r}.")
    if not 1 <= n_modes <= n_poly + n_bessel:
        raise ValueError(f"`modes` must be at most {n_poly + n_bessel} for the legacy basis.")
    rad = tank.radius
    a = tank.wall_radius(depth)

    # meridian section: z panels (exact sphere r_w(z)), Gauss in r on [0, r_w(z)]
    zq, wz = _depth_rule(depth, a, n_quad)
    rw = np.sqrt(np.clip(zq * (2.0 * rad - zq), 0.0, None))
    xr, wr = np.polynomial.legendre.leggauss(n_quad)
    t, wt = 0.5 * (xr + 1.0), 0.5 * wr
    r = np.outer(rw, t).ravel()
    z = np.repeat(zq, t.size)
    w = np.outer(wz * rw, wt).ravel()
    U, Ur, Uz = _basis(r, z, a, depth, n_poly, n_bessel)
    A = (Ur * w * r) @ Ur.T + (Uz * w * r) @ Uz.T + (U * (w / r)) @ U.T

    rf, wf, _ = surface_rule(tank, depth, 64)
    Uf = _basis(rf, np.full_like(rf, depth), a, depth, n_poly, n_bessel)[0]
    B = (Uf * wf * rf) @ Uf.T

    # equilibrate (r^9 spans 1e6 near full), then A c = lambda B c as B c = mu A c
    s = 1.0 / np.sqrt(np.diag(A))
    try:
        mu, vec = eigh(B * np.outer(s, s), A * np.outer(s, s))
    except np.linalg.LinAlgError:
        raise ValueError(f"the legacy basis with `n_poly={n_poly}` is numerically singular "
                         f"(powers up to r^{2 * n_poly - 1}); the SLOSH code uses "
                         "`n_poly=5`.") from None
    order = np.argsort(mu)[::-1][:n_modes]
    vec = vec[:, order] * s[:, None]
    lam = 1.0 / mu[order]

    uf = Uf.T @ vec
    a_n = (wf * rf**2) @ uf
    b_n = (wf * rf) @ uf**2
    u_wall = (_basis(np.array([a]), np.array([depth]), a, depth, n_poly, n_bessel)[0].T
              @ vec)[0]
    Uw = _basis(rw, zq, a, depth, n_poly, n_bessel)[0]
    s_n = (wz * zq * rw) @ (Uw.T @ vec)
    moment = 2.0 * s_n - depth * lam * a_n  # Dodge's hinge, see the module docstring
    sgn = np.sign(a_n)
    sgn[sgn == 0] = 1.0
    return RawModes(lam=lam, a=a_n * sgn, b=b_n, u_wall=u_wall * sgn, moment=moment * sgn,
                    size=n_poly + n_bessel)
