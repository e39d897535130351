"""Independent reference simulator of the spinning slosh test rig (six-axis data).

Plain numpy + ``scipy.integrate.solve_ivp`` with HAND-WRITTEN equations in tank
coordinates; it deliberately does not import ``analogs``, ``derive`` or ``estimate``, so it
can check them (and make synthetic data for the six-channel fit).

Rig kinematics (tank axis along the spin axis)
----------------------------------------------
The tank frame is ``R = Rz(phi) Rx(theta_n) Rz(psi)`` relative to the inertial frame, with
``phi = 2 pi f_n t`` (coning of the table axis about the vertical) and
``psi = (Omega_s - 2 pi f_n) t``. In tank components, with ``s = (sin theta_n sin psi,
sin theta_n cos psi, cos theta_n)`` the inertial vertical::

    omega = phi' s + psi' e_z,     alpha = phi' psi' (sin theta_n cos psi, -sin theta_n sin psi, 0)
    O = (r, 0, h)  (constant in the tank frame; the nutation pivot is fixed)
    a_O = alpha x O + omega x (omega x O),     g = -g s

Analogs (positions from the tank origin ``O``, tank components)
--------------------------------------------------------------
* dry mass ``m_d`` at ``O``; a point fixed mass ``m_f`` at ``(0, 0, h_f)``;
* spherical pendulum: bob ``m`` at ``rho = (0, 0, h_p) + L u``, ``u = (sin a cos b, sin b,
  -cos a cos b)``; its absolute acceleration
  ``a = a_O + rho'' + 2 omega x rho' + alpha x rho + omega x (omega x rho)`` and, for each of
  ``q = a, b``: ``m (a - g) . d rho/dq + c q' + k q = 0`` (hinge damper ``c``, spring ``k``);
* rotor: inertia ``J`` about the tank-fixed unit axis ``e``, relative angle ``psi_r``:
  ``J (alpha . e + psi_r'') = -c_r psi_r'``; its angular momentum ``h = J (omega . e + psi_r') e``.

Six-axis outputs: the force and the torque about ``O`` that the transducer applies to the
tank assembly, in tank components::

    F = sum_i m_i (a_i - g),     M = sum_i rho_i x m_i (a_i - g) + (-c_r psi_r' e + omega x h)

Noise: white Gaussian, per channel, of standard deviation ``noise`` times the standard
deviation of the noise-free channel about its mean.

Example
-------
>>> import numpy as np
>>> from reference_spinning import Rig, SphericalPendulum, Rotor, simulate_spinning
>>> out = simulate_spinning(np.linspace(0, 2, 201), Rig(spin_rate=6.0, radius=0.4),
...                         pendulum=SphericalPendulum(1.0, 0.1, 0.15), rotor=Rotor(0.01, 0.02))
>>> sorted(k for k in out if k.startswith("torque"))
['torque_x', 'torque_y', 'torque_z']
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

CHANNELS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class Rig:
    """Spin rate (rad/s), radius and height of the tank origin (m), nutation half-angle
    (rad) and coning frequency (Hz), gravity (m/s^2, 0 for none), dry mass (kg)."""

    spin_rate: float
    radius: float = 0.0
    height: float = 0.0
    nutation_angle: float = 0.0
    nutation_frequency: float = 0.0
    gravity: float = STANDARD_GRAVITY
    dry_mass: float = 0.0

    def kinematics(self, t):
        """``omega``, ``alpha``, ``a_O`` and ``g`` in tank components, each ``(3, n)``."""
        t = np.atleast_1d(np.asarray(t, float))
        dphi = 2 * np.pi * self.nutation_frequency
        dpsi = self.spin_rate - dphi
        psi = dpsi * t
        st, ct = np.sin(self.nutation_angle), np.cos(self.nutation_angle)
        vertical = np.array([st * np.sin(psi), st * np.cos(psi), np.full_like(t, ct)])
        omega = dphi * vertical + np.array([0.0, 0.0, dpsi])[:, None]
        alpha = dphi * dpsi * np.array([st * np.cos(psi), -st * np.sin(psi), np.zeros_like(t)])
        origin = np.array([self.radius, 0.0, self.height])[:, None]
        a_o = _cross(alpha, origin) + _cross(omega, _cross(omega, origin))
        return omega, alpha, a_o, -self.gravity * vertical


@dataclass(frozen=True)
class SphericalPendulum:
    """Bob mass (kg), length (m), hinge height (m), hinge damping (N m s/rad), stiffness
    (N m/rad)."""

    mass: float
    length: float
    hinge_height: float
    damping: float = 0.0
    stiffness: float = 0.0


@dataclass(frozen=True)
class Rotor:
    """Inertia (kg m^2) about a tank axis (``"x"``, ``"y"`` or ``"z"``), viscous coupling
    (N m s/rad)."""

    inertia: float
    damping: float
    axis: str = "x"

    @property
    def unit(self) -> np.ndarray:
        return np.eye(3)["xyz".index(self.axis)]


def _cross(a, b):
    return np.cross(a, b, axis=0)


def _bob(p: SphericalPendulum, a, b, ad, bd):
    """Position, its partial derivatives and the velocity-squared part of rho''."""
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    L = p.length
    rho = np.array([L * sa * cb, L * sb, p.hinge_height - L * ca * cb])
    ra = L * np.array([ca * cb, 0 * a, sa * cb])
    rb = L * np.array([-sa * sb, cb, ca * sb])
    raa = L * np.array([-sa * cb, 0 * a, ca * cb])
    rab = L * np.array([-ca * sb, 0 * a, -sa * sb])
    rbb = L * np.array([-sa * cb, -sb, ca * cb])
    quad = raa * ad**2 + 2 * rab * ad * bd + rbb * bd**2
    return rho, ra, rb, quad


def _accelerations(t, x, rig: Rig, p: SphericalPendulum | None, r: Rotor | None):
    omega, alpha, a_o, g = (v[:, 0] for v in rig.kinematics(t))
    out = np.zeros(0)
    if p is not None:
        a, b, ad, bd = x[0], x[1], x[2], x[3]
        rho, ra, rb, quad = _bob(p, a, b, ad, bd)
        v = ra * ad + rb * bd
        rest = a_o + quad + 2 * np.cross(omega, v) + np.cross(alpha, rho) \
            + np.cross(omega, np.cross(omega, rho)) - g
        m = p.mass
        M = m * np.array([[ra @ ra, ra @ rb], [rb @ ra, rb @ rb]])
        f = -m * np.array([ra @ rest, rb @ rest]) - p.damping * np.array([ad, bd]) \
            - p.stiffness * np.array([a, b])
        out = np.linalg.solve(M, f)
    if r is not None:
        psid = x[-1]
        out = np.r_[out, -r.damping * psid / r.inertia - alpha @ r.unit]
    return out


def simulate_spinning(t, rig: Rig, *, pendulum: SphericalPendulum | None = None,
                      rotor: Rotor | None = None, fixed_mass: float = 0.0,
                      fixed_height: float = 0.0, x0=None, noise: float = 0.0, seed: int = 0,
                      rtol: float = 1e-11, atol: float = 1e-13) -> dict[str, np.ndarray]:
    """Six-axis outputs on the grid ``t`` (s), from rest in the tank unless ``x0`` gives
    ``(alpha, beta, alpha_dot, beta_dot)`` for the pendulum and ``(psi, psi_dot)`` for the
    rotor (in that order). Returns ``time``, the six channels, ``states`` and ``clean``
    (the noise-free channels)."""
    t = np.asarray(t, float)
    n_p = 4 if pendulum is not None else 0
    n_r = 2 if rotor is not None else 0
    x0 = np.zeros(n_p + n_r) if x0 is None else np.asarray(x0, float)

    def rhs(tt, x):
        acc = _accelerations(tt, x, rig, pendulum, rotor)
        d = np.zeros_like(x)
        if n_p:
            d[:2] = x[2:4]
            d[2:4] = acc[:2]
        if n_r:
            d[n_p] = x[n_p + 1]
            d[n_p + 1] = acc[-1]
        return d

    sol = solve_ivp(rhs, (t[0], t[-1]), x0, method="DOP853", t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:  # pragma: no cover - a reference that fails must say so
        raise RuntimeError(sol.message)
    X = sol.y
    omega, alpha, a_o, g = rig.kinematics(t)
    force = rig.dry_mass * (a_o - g)
    torque = np.zeros_like(force)
    if fixed_mass:
        rf = np.array([0.0, 0.0, fixed_height])[:, None]
        ff = fixed_mass * (a_o + _cross(alpha, rf) + _cross(omega, _cross(omega, rf)) - g)
        force, torque = force + ff, torque + _cross(rf, ff)
    if n_p:
        a, b, ad, bd = X[:4]
        rho, ra, rb, quad = _bob(pendulum, a, b, ad, bd)
        acc = np.array([_accelerations(tt, xx, rig, pendulum, rotor)[:2]
                        for tt, xx in zip(t, X.T)]).T
        v = ra * ad + rb * bd
        a_bob = (a_o + ra * acc[0] + rb * acc[1] + quad + 2 * _cross(omega, v)
                 + _cross(alpha, rho) + _cross(omega, _cross(omega, rho)))
        fb = pendulum.mass * (a_bob - g)
        force, torque = force + fb, torque + _cross(rho, fb)
    if n_r:
        e = rotor.unit[:, None]
        psid = X[n_p + 1]
        h = rotor.inertia * ((omega * e).sum(axis=0) + psid) * e
        torque = torque - rotor.damping * psid * e + _cross(omega, h)
    clean = dict(zip(CHANNELS, (*force, *torque)))
    rng = np.random.default_rng(seed)
    out = {"time": t, "states": X.T.copy(), "clean": clean}
    for name, y in clean.items():
        out[name] = y + noise * np.std(y) * rng.standard_normal(y.size) if noise else y.copy()
    return out
