"""Independent reference simulator of the spinning slosh test rig (six-axis data).

Plain numpy + ``scipy.integrate.solve_ivp`` with HAND-WRITTEN equations in tank
coordinates; it deliberately does not import ``analogs``, ``derive`` or ``estimate``, so it
can check them (and make synthetic data for the six-channel fit).

Rig kinematics (tank axis along the spin axis)
----------------------------------------------
The tank frame is ``R = Rz(phi) Rx(theta) Rz(psi)`` relative to the inertial frame, with
``phi`` the nutation (precession) phase of the table axis about the vertical, ``theta`` the
cone half-angle and ``psi = sigma - phi`` (``sigma`` the table's spin angle). With constant
rates ``sigma = Omega_s t``, ``phi = 2 pi f_n t`` and ``theta = theta_n``; a spin-up ramps
the spin *rate* from 0 to ``Omega_s`` over ``spin_up`` s and a cone ramp the cone angle from 0
to ``theta_n`` over ``nutation_ramp`` s from ``nutation_start`` (both along the quintic
``s(x) = x^3 (10 - 15 x + 6 x^2)``, written out again below). In tank components, with
``s = (sin theta sin psi, sin theta cos psi, cos theta)`` the inertial vertical::

    omega = phi' s + theta' (cos psi, -sin psi, 0) + psi' e_z
    alpha = d omega / dt   (each component differentiated by hand in ``kinematics``)
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
  ``J (alpha . e + psi_r'') = -c_r psi_r'``; its angular momentum ``h = J (omega . e + psi_r') e``;
* rotary oscillator (Green et al.): a massless body ``B = R_x(a1) R_y(a2)`` relative to the
  tank with inertia ``diag(J, J, 0)`` in ``B``, torsional springs ``k`` and dampers ``c`` on
  ``a1`` (about the radial tank axis x) and ``a2`` (about the turned tangential axis y).
  In ``B`` components its angular velocity is ``w = R^T omega + (a1' cos a2, a2', a1' sin a2)``
  and (Euler, with ``w_r = (a1' cos a2, a2', a1' sin a2)`` the relative part)
  ``w' = e1 a1'' + e2 a2'' + R^T alpha - w_r x R^T omega + (-a1' a2' sin a2, 0, a1' a2' cos a2)``
  with ``e1 = (cos a2, 0, sin a2)``, ``e2 = (0, 1, 0)``; Kane's equations
  ``e_i . (I w' + w x I w) = -k a_i - c a_i'``.

Six-axis outputs: the force and the torque about ``O`` that the transducer applies to the
tank assembly, in tank components::

    F = sum_i m_i (a_i - g),     M = sum_i rho_i x m_i (a_i - g) + (-c_r psi_r' e + omega x h)
                                     + R (I w' + w x I w)

A *steady* start (:func:`steady_state`) puts every analog at its relative equilibrium under
the rig motion at the first time: zero relative rates and accelerations, solved with
``scipy.optimize.root`` on the hand-written accelerations (the conical pendulum; the rotor
turning with the tank).

Noise: white Gaussian, per channel, of standard deviation ``noise`` times the standard
deviation of the noise-free channel about its mean, plus an optional tone (a motor line) of
``tone[0]`` times that standard deviation at ``tone[1]`` Hz, plus an optional transducer
drift: an offset that grows linearly from 0 to ``drift`` times that standard deviation
over the record (its sign drawn per channel). The rig angles (``angles``:
``spin_angle``, ``nutation_phase``, ``cone_angle``) are returned as a test records them,
with white noise of ``angle_noise`` rad.

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
from scipy.optimize import root

CHANNELS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
STANDARD_GRAVITY = 9.80665


def _ramp(t, final, duration, start, rate):
    """Value, rate and acceleration of a quintic ramp of a level (``rate=False``) or of a
    rate (``rate=True``: an angle spun up), written out independently of ``derive``."""
    if duration == 0:
        zero = np.zeros_like(t)
        return (final + zero, zero, zero) if not rate else (final * t, final + zero, zero)
    x = np.clip((t - start) / duration, 0.0, 1.0)
    s = 10 * x**3 - 15 * x**4 + 6 * x**5
    ds = (30 * x**2 - 60 * x**3 + 30 * x**4) / duration
    dds = (60 * x - 180 * x**2 + 120 * x**3) / duration**2
    if not rate:
        return final * s, final * ds, final * dds
    integral = duration * (2.5 * x**4 - 3 * x**5 + x**6) + np.maximum(t - start - duration, 0)
    return final * integral, final * s, final * ds


@dataclass(frozen=True)
class Rig:
    """Spin rate (rad/s), radius and height of the tank origin (m), nutation half-angle
    (rad) and coning frequency (Hz), gravity (m/s^2, 0 for none), dry mass (kg); the spin-up
    time (s, 0: spinning at ``spin_rate`` from t = 0), the cone-angle ramp time (s, 0: the
    cone angle from t = 0) and its start (s, default: the end of the spin-up)."""

    spin_rate: float
    radius: float = 0.0
    height: float = 0.0
    nutation_angle: float = 0.0
    nutation_frequency: float = 0.0
    gravity: float = STANDARD_GRAVITY
    dry_mass: float = 0.0
    spin_up: float = 0.0
    nutation_ramp: float = 0.0
    nutation_start: float | None = None

    def angles(self, t):
        """``(sigma, phi, theta)``, each ``(value, rate, acceleration)`` arrays (rad)."""
        t = np.atleast_1d(np.asarray(t, float))
        start = self.spin_up if self.nutation_start is None else self.nutation_start
        sigma = _ramp(t, self.spin_rate, self.spin_up, 0.0, True)
        phi = _ramp(t, 2 * np.pi * self.nutation_frequency, 0.0, 0.0, True)
        theta = _ramp(t, self.nutation_angle, self.nutation_ramp,
                      start if self.nutation_ramp else 0.0, False)
        return sigma, phi, theta

    def kinematics(self, t):
        """``omega``, ``alpha``, ``a_O`` and ``g`` in tank components, each ``(3, n)``."""
        (sg, dsg, ddsg), (ph, dph, ddph), (th, dth, ddth) = self.angles(t)
        psi, dpsi, ddpsi = sg - ph, dsg - dph, ddsg - ddph
        st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(psi), np.cos(psi)
        vertical = np.array([st * sp, st * cp, ct])
        omega = np.array([dph * st * sp + dth * cp,
                          dph * st * cp - dth * sp,
                          dph * ct + dpsi])
        alpha = np.array([
            ddph * st * sp + dph * dth * ct * sp + dph * st * cp * dpsi + ddth * cp - dth * sp * dpsi,
            ddph * st * cp + dph * dth * ct * cp - dph * st * sp * dpsi - ddth * sp - dth * cp * dpsi,
            ddph * ct - dph * st * dth + ddpsi])
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


@dataclass(frozen=True)
class RotaryOscillator:
    """Green et al.'s rotary oscillator: inertia (kg m^2) about the radial (x) and the
    tangential (y) axes of its body, none about the third; torsional stiffness (N m/rad)
    and damping (N m s/rad) on both of its angles."""

    inertia: float
    stiffness: float
    damping: float = 0.0


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


def _oscillator(state, omega, alpha):
    """Tank <- body rotation ``R``, body angular velocity ``w``, the part of ``w'`` without
    the angle accelerations, and the partial angular velocities ``e1``, ``e2`` (one time)."""
    a1, a2, d1, d2 = state
    c1, s1, c2, s2 = np.cos(a1), np.sin(a1), np.cos(a2), np.sin(a2)
    R = np.array([[1, 0, 0], [0, c1, -s1], [0, s1, c1]]) @ np.array([[c2, 0, s2], [0, 1, 0],
                                                                    [-s2, 0, c2]])
    w_rel = np.array([d1 * c2, d2, d1 * s2])
    w_tank = R.T @ omega
    rest = R.T @ alpha - np.cross(w_rel, w_tank) + np.array([-d1 * d2 * s2, 0.0, d1 * d2 * c2])
    return R, w_tank + w_rel, rest, np.array([c2, 0.0, s2]), np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class _Analogs:
    pendulum: SphericalPendulum | None
    rotor: Rotor | None
    oscillator: RotaryOscillator | None

    @property
    def sizes(self):
        return (4 if self.pendulum else 0, 2 if self.rotor else 0, 4 if self.oscillator else 0)


def _accelerations(t, x, rig: Rig, an: _Analogs):
    """Pendulum (2), rotor (1) and oscillator (2) accelerations at one time."""
    omega, alpha, a_o, g = (v[:, 0] for v in rig.kinematics(t))
    n_p, n_r, _ = an.sizes
    out = []
    if an.pendulum is not None:
        p = an.pendulum
        a, b, ad, bd = x[0], x[1], x[2], x[3]
        rho, ra, rb, quad = _bob(p, a, b, ad, bd)
        v = ra * ad + rb * bd
        rest = a_o + quad + 2 * np.cross(omega, v) + np.cross(alpha, rho) \
            + np.cross(omega, np.cross(omega, rho)) - g
        m = p.mass
        M = m * np.array([[ra @ ra, ra @ rb], [rb @ ra, rb @ rb]])
        f = -m * np.array([ra @ rest, rb @ rest]) - p.damping * np.array([ad, bd]) \
            - p.stiffness * np.array([a, b])
        out += list(np.linalg.solve(M, f))
    if an.rotor is not None:
        r = an.rotor
        out.append(-r.damping * x[n_p + 1] / r.inertia - alpha @ r.unit)
    if an.oscillator is not None:
        o = an.oscillator
        y = x[n_p + n_r:]
        R, w, rest, e1, e2 = _oscillator(y, omega, alpha)
        inertia = np.diag([o.inertia, o.inertia, 0.0])
        M = np.array([[e1 @ inertia @ e1, e1 @ inertia @ e2], [e2 @ inertia @ e1, e2 @ inertia @ e2]])
        gyro = inertia @ rest + np.cross(w, inertia @ w)
        f = -np.array([e1 @ gyro, e2 @ gyro]) - o.stiffness * y[:2] - o.damping * y[2:]
        out += list(np.linalg.solve(M, f))
    return np.array(out)


def _rates(x, acc, an: _Analogs):
    """``x'`` from the state and the accelerations, block by block (positions, rates)."""
    d = np.zeros_like(x)
    offset = k = 0
    for size in an.sizes:
        half = size // 2
        d[offset:offset + half] = x[offset + half:offset + size]
        d[offset + half:offset + size] = acc[k:k + half]
        offset, k = offset + size, k + half
    return d


def steady_state(t0: float, rig: Rig, *, pendulum=None, rotor=None, oscillator=None):
    """The relative equilibrium under the rig motion at ``t0``: every rate zero and every
    acceleration zero (``scipy.optimize.root`` on the hand-written accelerations, the
    pendulum started swung out by 0.5 rad so that it finds the outward conical equilibrium
    of a spinning tank). Raises when the rig motion at ``t0`` admits none (coning or a
    changing spin rate)."""
    an = _Analogs(pendulum, rotor, oscillator)
    n_p, n_r, n_o = an.sizes
    n = n_p + n_r + n_o
    # solved: the pendulum's and the oscillator's angles; the rotor turns with the tank
    idx = ([0, 1] if n_p else []) + ([n_p + n_r, n_p + n_r + 1] if n_o else [])
    rows = ([0, 1] if n_p else []) + ([-2, -1] if n_o else [])

    def residual(q):
        x = np.zeros(n)
        x[idx] = q
        return _accelerations(t0, x, rig, an)[rows]

    x0 = np.zeros(n)
    if idx:
        guess = np.r_[[0.5, 0.0] if n_p else [], [0.0, 0.0] if n_o else []]
        x0[idx] = root(residual, guess, tol=1e-14).x
    acc = _accelerations(t0, x0, rig, an)
    if not np.all(np.abs(acc) < 1e-9):
        raise RuntimeError(f"no relative equilibrium at t = {t0} s: accelerations {acc}")
    return x0


def simulate_spinning(t, rig: Rig, *, pendulum: SphericalPendulum | None = None,
                      rotor: Rotor | None = None, oscillator: RotaryOscillator | None = None,
                      fixed_mass: float = 0.0, fixed_height: float = 0.0, x0=None,
                      steady: bool = False, noise: float = 0.0, tone=None,
                      drift: float = 0.0, angle_noise: float = 0.0, seed: int = 0, rtol: float = 1e-11,
                      atol: float = 1e-13) -> dict[str, np.ndarray]:
    """Six-axis outputs on the grid ``t`` (s), from rest in the tank unless ``steady``
    (:func:`steady_state` at ``t[0]``) or ``x0`` gives ``(alpha, beta, alpha_dot,
    beta_dot)`` for the pendulum, ``(psi, psi_dot)`` for the rotor and ``(a1, a2, a1_dot,
    a2_dot)`` for the oscillator (in that order). Returns ``time``, the six channels,
    ``states``, ``clean`` (the noise-free channels) and ``angles`` (the rig angles as
    recorded, rad)."""
    t = np.asarray(t, float)
    an = _Analogs(pendulum, rotor, oscillator)
    n_p, n_r, n_o = an.sizes
    if steady:
        x0 = steady_state(float(t[0]), rig, pendulum=pendulum, rotor=rotor, oscillator=oscillator)
    x0 = np.zeros(n_p + n_r + n_o) if x0 is None else np.asarray(x0, float)

    def rhs(tt, x):
        return _rates(x, _accelerations(tt, x, rig, an), an)

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
    acc = np.array([_accelerations(tt, xx, rig, an) for tt, xx in zip(t, X.T)]).T
    if n_p:
        a, b, ad, bd = X[:4]
        rho, ra, rb, quad = _bob(pendulum, a, b, ad, bd)
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
    if n_o:
        inertia = np.diag([oscillator.inertia, oscillator.inertia, 0.0])
        for i in range(t.size):
            R, w, rest, e1, e2 = _oscillator(X[n_p + n_r:, i], omega[:, i], alpha[:, i])
            dw = e1 * acc[-2, i] + e2 * acc[-1, i] + rest
            torque[:, i] += R @ (inertia @ dw + np.cross(w, inertia @ w))
    clean = dict(zip(CHANNELS, (*force, *torque)))
    rng = np.random.default_rng(seed)
    out = {"time": t, "states": X.T.copy(), "clean": clean}
    for name, y in clean.items():
        scale = np.std(y)
        out[name] = y + noise * scale * rng.standard_normal(y.size) if noise else y.copy()
        if tone is not None:
            out[name] = out[name] + tone[0] * scale * np.sin(2 * np.pi * tone[1] * t
                                                             + rng.uniform(0, 2 * np.pi))
        if drift:
            ramp = (t - t[0]) / (t[-1] - t[0])
            out[name] = out[name] + rng.choice((-1.0, 1.0)) * drift * scale * ramp
    names = ("spin_angle", "nutation_phase", "cone_angle")
    out["angles"] = {k: v[0] + angle_noise * rng.standard_normal(t.size)
                     for k, v in zip(names, rig.angles(t))}
    return out
