"""Axisymmetric high-order finite elements for the lateral (m = 1) sloshing modes.

Independent of the Ritz solver: the weak form

    int (U_r V_r + U_z V_z + U V / r^2) r dr dz = lambda int_F U V r dr

is discretised with continuous tensor-product Lagrange elements of degree ``p`` (nodes
at Gauss-Lobatto points) on the same horizontal-slice map of the meridian section that the
quadrature uses, ``r = t r_w(s), z = z_w(s)``. The mesh is graded geometrically towards
the wall (``t = 1``) and the free surface (top of the last slice): the contact line is a
corner where the modes are singular (exponent ``pi / alpha`` for a contact angle
``alpha`` > 90 degrees, i.e. spheres above half full), and a geometric mesh with a high
degree recovers fast convergence there. ``U = 0`` on the axis. Interior unknowns are
condensed onto the free surface (a discrete Dirichlet-to-Neumann map) and the small dense
problem is solved with LAPACK.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import splu

from ._modes import RawModes
from .geometry import Tank

__all__ = ["solve"]


def _gll(p: int) -> np.ndarray:
    """Gauss-Lobatto-Legendre nodes on [-1, 1]."""
    c = np.zeros(p + 1)
    c[-1] = 1.0
    inner = np.polynomial.legendre.legroots(np.polynomial.legendre.legder(c))
    return np.concatenate([[-1.0], np.sort(inner), [1.0]])


def _lagrange(nodes: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lagrange basis on ``nodes`` and its derivative at ``x``: shape (len(x), len(nodes))."""
    n = nodes.size
    val = np.ones((x.size, n))
    der = np.zeros((x.size, n))
    for i in range(n):
        others = [j for j in range(n) if j != i]
        denom = np.prod(nodes[i] - nodes[others])
        for j in others:
            val[:, i] *= (x - nodes[j])
        val[:, i] /= denom
        for k in others:
            term = np.ones_like(x)
            for j in others:
                if j != k:
                    term = term * (x - nodes[j])
            der[:, i] += term
        der[:, i] /= denom
    return val, der


def _graded(a: float, b: float, layers: int, ratio: float, uniform: int) -> np.ndarray:
    """Breakpoints on [a, b]: ``uniform`` equal elements, then ``layers`` geometric ones
    shrinking by ``ratio`` towards ``b``."""
    if layers == 0:
        return np.linspace(a, b, uniform + 1)
    split = b - (b - a) * ratio
    right = b - (b - a) * ratio ** np.arange(2, layers + 1)
    return np.concatenate([np.linspace(a, split, uniform + 1), right, [b]])


def solve(tank: Tank, depth: float, *, degree: int = 8, layers: int = 8, ratio: float = 0.2,
          n_modes: int = 4) -> RawModes:
    """Lateral sloshing modes by graded ``degree``-p finite elements."""
    p = degree
    ref = _gll(p)
    xq, wq = np.polynomial.legendre.leggauss(p + 3)
    lv, ld = _lagrange(ref, xq)

    t_br = _graded(0.0, 1.0, layers, ratio, 2)
    slices = [sl for sl in tank.wall_slices() if sl.z0 < depth]
    s_elems = []  # (slice, sa, sb)
    for k, sl in enumerate(slices):
        s0, s1 = sl.param_range()
        last = k == len(slices) - 1 or slices[k + 1].z0 >= depth
        if sl.z1 > depth or last:
            s1 = sl.param_at(min(depth, sl.z1))
            br = _graded(s0, s1, layers, ratio, 3)
        else:
            br = np.linspace(s0, s1, 3)
        s_elems += [(sl, br[i], br[i + 1]) for i in range(br.size - 1)]
        if last:
            break
    n_et, n_es = t_br.size - 1, len(s_elems)
    n_t, n_s = n_et * p + 1, n_es * p + 1

    # quadrature points per element
    ht = np.diff(t_br)
    tq = t_br[:-1, None] + 0.5 * ht[:, None] * (xq + 1.0)  # (n_et, nq)
    wt = 0.5 * ht[:, None] * wq
    sq, ws, rw, zw, drw, dzw, hs = [], [], [], [], [], [], []
    for sl, sa, sb in s_elems:
        s = sa + 0.5 * (sb - sa) * (xq + 1.0)
        r_, z_, dr_, dz_ = sl.point(s)
        sq.append(s)
        ws.append(0.5 * (sb - sa) * wq)
        rw.append(r_)
        zw.append(z_)
        drw.append(dr_)
        dzw.append(dz_)
        hs.append(sb - sa)
    ws, rw, zw, drw, dzw, hs = map(np.array, (ws, rw, zw, drw, dzw, hs))

    # metric on the (et, es, qt, qs) grid
    T = tq[:, None, :, None]
    RW, ZW, DR, DZ = (v[None, :, None, :] for v in (rw, zw, drw, dzw))
    W = wt[:, None, :, None] * ws[None, :, None, :]
    r = T * RW
    det = RW * DZ
    alpha = 1.0 / RW
    beta = 1.0 / DZ
    gamma = -T * DR / (RW * DZ)
    wr = W * r * det
    c_tt = wr * (alpha**2 + gamma**2)
    c_ts = wr * gamma * beta
    c_ss = wr * beta**2
    c_00 = W * det / r  # U V / r^2 * r det
    # reference-derivative scale factors
    sx_t = (2.0 / ht)[:, None, None, None]
    sx_s = (2.0 / hs)[None, :, None, None]

    ein = "abxy,xi,yj,xk,yl->abijkl"

    def kt(c, X, Y, X2, Y2):
        return np.einsum(ein, c, X, Y, X2, Y2, optimize=True)

    K = (kt(c_tt * sx_t**2, ld, lv, ld, lv)
         + kt(c_ts * sx_t * sx_s, ld, lv, lv, ld)
         + kt(c_ts * sx_t * sx_s, lv, ld, ld, lv)
         + kt(c_ss * sx_s**2, lv, ld, lv, ld)
         + kt(c_00, lv, lv, lv, lv))
    # the moment functional  int (z (U_r + U/r) - r U_z) r det
    zz = ZW + 0.0 * T
    g_t = W * r * det * (zz * alpha - r * gamma) * sx_t
    g_s = W * r * det * (-r * beta) * sx_s
    g_0 = W * r * det * zz / r
    G = (np.einsum("abxy,xi,yj->abij", g_t, ld, lv) + np.einsum("abxy,xi,yj->abij", g_s, lv, ld)
         + np.einsum("abxy,xi,yj->abij", g_0, lv, lv))

    it = np.arange(n_et)[:, None] * p + np.arange(p + 1)[None, :]  # (n_et, p+1)
    js = np.arange(n_es)[:, None] * p + np.arange(p + 1)[None, :]
    dof = it[:, None, :, None] * n_s + js[None, :, None, :]  # (et, es, i, j)
    rows = np.broadcast_to(dof[..., :, :, None, None], K.shape).ravel()
    cols = np.broadcast_to(dof[..., None, None, :, :], K.shape).ravel()
    n = n_t * n_s
    Kg = coo_matrix((K.ravel(), (rows, cols)), shape=(n, n)).tocsr()
    Gg = np.bincount(dof.ravel(), weights=G.ravel(), minlength=n)

    # free-surface mass  int U V r dr  with r = t r_s
    r_s = float(tank.wall_radius(depth))
    mt = np.einsum("ex,xi,xk->eik", wt * tq * r_s**2, lv, lv)
    at = np.einsum("ex,xi->ei", wt * tq**2 * r_s**3, lv)
    Ms = np.zeros((n_t, n_t))
    As = np.zeros(n_t)
    for e in range(n_et):
        Ms[np.ix_(it[e], it[e])] += mt[e]
        As[it[e]] += at[e]

    node_t = np.arange(n_t)
    node_s = np.arange(n_s)
    pole = slices[0].point(np.array(slices[0].param_range()[0]))[0] == 0.0
    fixed = np.zeros((n_t, n_s), dtype=bool)
    fixed[0, :] = True
    if pole:
        fixed[:, 0] = True
    surf = np.zeros((n_t, n_s), dtype=bool)
    surf[:, -1] = True
    surf &= ~fixed
    interior = ~fixed & ~surf
    S_idx = (node_t[:, None] * n_s + node_s[None, :])[surf]
    I_idx = (node_t[:, None] * n_s + node_s[None, :])[interior]
    t_surf = node_t[surf[:, -1]]

    Kii = Kg[I_idx][:, I_idx].tocsc()
    Kis = Kg[I_idx][:, S_idx].toarray()
    Kss = Kg[S_idx][:, S_idx].toarray()
    lu = splu(Kii)
    X = lu.solve(Kis)
    schur = Kss - Kis.T @ X
    schur = 0.5 * (schur + schur.T)
    Mss = Ms[np.ix_(t_surf, t_surf)]
    lam, vec = eigh(schur, Mss, subset_by_index=[0, n_modes - 1])
    u_int = -X @ vec
    a = As[t_surf] @ vec
    b = np.einsum("ik,ij,jk->k", vec, Mss, vec)
    u_wall = vec[-1]
    moment = Gg[S_idx] @ vec + Gg[I_idx] @ u_int
    sgn = np.sign(a)
    sgn[sgn == 0] = 1.0
    return RawModes(lam=lam, a=a * sgn, b=b, u_wall=u_wall * sgn, moment=moment * sgn,
                    size=int(S_idx.size + I_idx.size))
