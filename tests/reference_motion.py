"""Independent reference simulator of a tank moved by a prescribed 3-D motion (six-axis data).

Plain numpy + ``scipy.integrate.solve_ivp`` with HAND-WRITTEN equations in tank coordinates;
it deliberately imports nothing from ``analogs``, ``derive`` or ``estimate`` (nor from the
other reference simulators), so it can check them and make synthetic records for them.

Frames and motion
-----------------
The lab frame ``N`` is inertial, ``N.z`` up, gravity ``-g N.z``. The tank frame ``T`` has its
origin ``O`` on the tank axis at the tank bottom and ``T.z`` along the tank axis. Its pose is
prescribed by six signals, each with analytic first and second time derivatives:

* the translation ``(x, y, z)`` (m): the position of ``O`` in lab components (zero at rest);
* the attitude ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad): z-y-x Tait-Bryan angles, any size
  (away from pitch = +/-90 deg), so that a vector's lab components are ``R`` times its tank
  components; at zero angles ``T = N``.

In tank components the angular velocity and acceleration are (``phi, theta, psi`` = roll,
pitch, yaw; written out by hand, differentiated by hand)::

    omega = (phi' - psi' sin theta,
             theta' cos phi + psi' sin phi cos theta,
             -theta' sin phi + psi' cos phi cos theta)
    alpha = d omega / dt          (component by component, see :meth:`Motion.kinematics`)
    a_O = R^T (x'', y'', z''),     g = R^T (0, 0, -g)

Analogs (positions from ``O``, tank components)
-----------------------------------------------
* dry mass ``m_d`` at ``O``;
* fixed mass: a rigid body of mass ``m_f`` centred at ``(0, 0, h_f)`` with central inertia
  ``diag(I, I, I_ax)`` (pitch/roll and axial);
* spherical pendulum: bob ``m`` at ``rho = (0, 0, h_p) + L u``, ``u = (sin a cos b, sin b,
  -cos a cos b)`` (``a`` swings toward +x, ``b`` toward +y); its absolute acceleration
  ``A = a_O + rho'' + 2 omega x rho' + alpha x rho + omega x (omega x rho)`` and, for each
  ``q`` in ``(a, b)``, d'Alembert's principle ``m (A - g) . d rho/dq + c q' + k q = 0``
  (hinge damping ``c`` on each angle's rate and an optional hinge spring ``k``).

Six-axis outputs
----------------
The force and torque that the transducer applies to the tank assembly, about ``O`` in tank
components::

    F = m_d (a_O - g) + m_f (A_f - g) + m (A - g)
    M_O = rho_f x m_f (A_f - g) + I alpha + omega x (I omega) + rho x m (A - g)

The transducer measures them at its reference point ``P`` (tank components ``r_P``) in its own
axes ``S``, turned from the tank axes by ``R_S = Rz(yaw_s) Ry(pitch_s) Rx(roll_s)`` (the same
convention; a transducer mounted turned by 180 deg about z has ``yaw_s = pi``)::

    F_S = R_S^T F,     M_S = R_S^T (M_O - r_P x F)

Records as a rig makes them
---------------------------
Each motion axis is a sum of signals (:class:`RampedSine`, :class:`Move`); a ramped sine is
faded in from rest by the quintic ``s(x) = 10 x^3 - 15 x^4 + 6 x^5`` (and out, when it
stops), so the tank starts at rest and never jerks. Every channel gets white noise, a tone
(a motor or electrical line at its own phase per channel) and a linear drift of the
transducer's offset; forces and torques each at a fraction of the largest swing of their
kind (a quiet transverse channel is as noisy as the driven one, as on a real transducer),
and optionally quantised. The motion is recorded with white noise (m, rad) on each axis.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["AXES", "CHANNELS", "FixedMass", "Motion", "Move", "Noise", "RampedSine",
           "SphericalPendulum", "Transducer", "energy", "simulate_motion"]

CHANNELS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
#: Motion axes: translations (m) and z-y-x attitude angles (rad).
AXES = ("x", "y", "z", "roll", "pitch", "yaw")
STANDARD_GRAVITY = 9.80665


def _quintic_at(t: float, start: float, duration: float):
    """:func:`_quintic` at one time (plain floats: the integrator calls it ~1e5 times)."""
    x = min(max((t - start) / duration, 0.0), 1.0)
    return (x**3 * (10 - 15 * x + 6 * x * x), 30 * x * x * (1 - x) ** 2 / duration,
            60 * x * (1 - x) * (1 - 2 * x) / duration**2)


def _quintic(t, start: float, duration: float):
    """The smooth step ``s(x) = 10 x^3 - 15 x^4 + 6 x^5``, ``x = (t - start)/duration``
    clipped to [0, 1], with its first and second time derivatives."""
    x = np.clip((np.asarray(t, float) - start) / duration, 0.0, 1.0)
    s = x**3 * (10 - 15 * x + 6 * x**2)
    ds = 30 * x**2 * (1 - x) ** 2 / duration
    dds = 60 * x * (1 - x) * (1 - 2 * x) / duration**2
    return s, ds, dds


@dataclass(frozen=True)
class RampedSine:
    """``amplitude sin(2 pi frequency (t - start) + phase)`` faded in by the quintic over
    ``ramp`` s from ``start`` (s) and, with ``stop`` (s), faded out over ``ramp`` s ending
    there (the tank then rests for the free decay). Amplitude in m or rad."""

    amplitude: float
    frequency: float
    phase: float = 0.0
    ramp: float = 1.5
    start: float = 0.5
    stop: float | None = None

    def __call__(self, t):
        t = np.asarray(t, float)
        w = 2 * np.pi * self.frequency
        arg = w * (t - self.start) + self.phase
        y, dy, ddy = np.sin(arg), w * np.cos(arg), -w * w * np.sin(arg)
        e, de, dde = _quintic(t, self.start, self.ramp)
        if self.stop is not None:
            f, df, ddf = _quintic(t, self.stop - self.ramp, self.ramp)
            e, de, dde = e * (1 - f), de * (1 - f) - e * df, dde * (1 - f) - 2 * de * df - e * ddf
        a = self.amplitude
        return a * e * y, a * (de * y + e * dy), a * (dde * y + 2 * de * dy + e * ddy)

    def at(self, t: float):
        """The same at one time, in plain floats."""
        w = 2 * math.pi * self.frequency
        arg = w * (t - self.start) + self.phase
        y, dy, ddy = math.sin(arg), w * math.cos(arg), -w * w * math.sin(arg)
        e, de, dde = _quintic_at(t, self.start, self.ramp)
        if self.stop is not None:
            f, df, ddf = _quintic_at(t, self.stop - self.ramp, self.ramp)
            e, de, dde = e * (1 - f), de * (1 - f) - e * df, dde * (1 - f) - 2 * de * df - e * ddf
        a = self.amplitude
        return a * e * y, a * (de * y + e * dy), a * (dde * y + 2 * de * dy + e * ddy)


@dataclass(frozen=True)
class Move:
    """A point-to-point move by ``distance`` (m or rad) along the quintic in ``duration`` s
    from ``start`` (s): a transport test."""

    distance: float
    duration: float
    start: float = 0.5

    def __call__(self, t):
        s, ds, dds = _quintic(t, self.start, self.duration)
        return self.distance * s, self.distance * ds, self.distance * dds

    def at(self, t: float):
        """The same at one time, in plain floats."""
        s, ds, dds = _quintic_at(t, self.start, self.duration)
        return self.distance * s, self.distance * ds, self.distance * dds


#: A signal maps times to ``(value, rate, acceleration)``; signals that the integrator
#: evaluates often also have ``at(t)`` for one time in plain floats.
Signal = Callable[[np.ndarray], tuple]


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """``Rz(yaw) Ry(pitch) Rx(roll)``: lab (or tank) components from tank (or transducer)
    components."""
    return _rot_z(yaw) @ _rot_y(pitch) @ _rot_x(roll)


@dataclass(frozen=True)
class Motion:
    """The prescribed pose of the tank: each axis of :data:`AXES` is ``None`` (still), a
    signal ``t -> (value, rate, acceleration)`` or a sequence of signals (summed)."""

    x: Signal | Sequence[Signal] | None = None
    y: Signal | Sequence[Signal] | None = None
    z: Signal | Sequence[Signal] | None = None
    roll: Signal | Sequence[Signal] | None = None
    pitch: Signal | Sequence[Signal] | None = None
    yaw: Signal | Sequence[Signal] | None = None
    gravity: float = STANDARD_GRAVITY

    @property
    def axes(self) -> tuple[str, ...]:
        """The axes that move."""
        return tuple(a for a in AXES if getattr(self, a) is not None)

    def axis(self, name: str, t):
        """``(value, rate, acceleration)`` of one axis on the times ``t``."""
        t = np.asarray(t, float)
        spec = getattr(self, name)
        zero = np.zeros_like(t)
        if spec is None:
            return zero, zero.copy(), zero.copy()
        parts = spec if isinstance(spec, (list, tuple)) else (spec,)
        out = [zero.copy(), zero.copy(), zero.copy()]
        for sig in parts:
            for k, v in enumerate(sig(t)):
                out[k] = out[k] + v
        return tuple(out)

    def _axis_at(self, name: str, t: float):
        spec = getattr(self, name)
        if spec is None:
            return 0.0, 0.0, 0.0
        parts = spec if isinstance(spec, (list, tuple)) else (spec,)
        v = dv = ddv = 0.0
        for sig in parts:
            a, b, c = sig.at(t) if hasattr(sig, "at") else (float(np.asarray(x).ravel()[0])
                                                             for x in sig(np.array([t])))
            v, dv, ddv = v + a, dv + b, ddv + c
        return v, dv, ddv

    def at(self, t: float):
        """:meth:`kinematics` at one time without ``R``: ``omega``, ``alpha``, ``a_O``, ``g``
        as 3-vectors (the same formulas in plain floats, for the integrator)."""
        xdd, ydd, zdd = (self._axis_at(a, t)[2] for a in "xyz")
        (ph, dph, ddph), (th, dth, ddth), (ps, dps, ddps) = (
            self._axis_at(a, t) for a in ("roll", "pitch", "yaw"))
        sph, cph, sth, cth, sps, cps = (math.sin(ph), math.cos(ph), math.sin(th), math.cos(th),
                                        math.sin(ps), math.cos(ps))
        cols = ((cps * cth, cps * sth * sph - sps * cph, cps * sth * cph + sps * sph),
                (sps * cth, sps * sth * sph + cps * cph, sps * sth * cph - cps * sph),
                (-sth, cth * sph, cth * cph))
        omega = np.array([dph - dps * sth, dth * cph + dps * sph * cth,
                          -dth * sph + dps * cph * cth])
        alpha = np.array([
            ddph - ddps * sth - dps * dth * cth,
            ddth * cph - dth * dph * sph + ddps * sph * cth + dps * dph * cph * cth
            - dps * dth * sph * sth,
            -ddth * sph - dth * dph * cph + ddps * cph * cth - dps * dph * sph * cth
            - dps * dth * cph * sth])
        a_o = np.array([cols[0][k] * xdd + cols[1][k] * ydd + cols[2][k] * zdd for k in range(3)])
        g = -self.gravity * np.array(cols[2])
        return omega, alpha, a_o, g

    def kinematics(self, t):
        """At the times ``t`` (n,): ``R`` (n, 3, 3), and in tank components ``omega``,
        ``alpha``, ``a_O`` and ``g``, each (n, 3)."""
        t = np.atleast_1d(np.asarray(t, float))
        (_, _, xdd), (_, _, ydd), (_, _, zdd) = (self.axis(a, t) for a in "xyz")
        (ph, dph, ddph), (th, dth, ddth), (ps, dps, ddps) = (
            self.axis(a, t) for a in ("roll", "pitch", "yaw"))
        sph, cph, sth, cth, sps, cps = (np.sin(ph), np.cos(ph), np.sin(th), np.cos(th),
                                        np.sin(ps), np.cos(ps))
        # R = Rz(psi) Ry(theta) Rx(phi), element by element
        R = np.empty((t.size, 3, 3))
        R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = (cps * cth, cps * sth * sph - sps * cph,
                                              cps * sth * cph + sps * sph)
        R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = (sps * cth, sps * sth * sph + cps * cph,
                                              sps * sth * cph - cps * sph)
        R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = -sth, cth * sph, cth * cph
        omega = np.stack([dph - dps * sth,
                          dth * cph + dps * sph * cth,
                          -dth * sph + dps * cph * cth], axis=1)
        alpha = np.stack([
            ddph - ddps * sth - dps * dth * cth,
            ddth * cph - dth * dph * sph + ddps * sph * cth + dps * dph * cph * cth
            - dps * dth * sph * sth,
            -ddth * sph - dth * dph * cph + ddps * cph * cth - dps * dph * sph * cth
            - dps * dth * cph * sth], axis=1)
        a_lab = np.stack([xdd, ydd, zdd], axis=1)
        a_o = np.einsum("nji,nj->ni", R, a_lab)
        g = -self.gravity * R[:, 2, :]  # R^T (0, 0, -g): the third row of R
        return R, omega, alpha, a_o, g


@dataclass(frozen=True)
class FixedMass:
    """Mass (kg), centre height above ``O`` (m), central pitch/roll and axial inertias
    (kg m^2)."""

    mass: float
    height: float
    inertia: float = 0.0
    axial_inertia: float = 0.0


@dataclass(frozen=True)
class SphericalPendulum:
    """Bob mass (kg), length (m), hinge height above ``O`` (m), hinge damping on each
    angle's rate (N m s/rad), hinge stiffness on each angle (N m/rad)."""

    mass: float
    length: float
    hinge_height: float
    damping: float = 0.0
    stiffness: float = 0.0

    def frequency_hz(self, gravity: float = STANDARD_GRAVITY) -> float:
        """Small-swing natural frequency in a tank at rest (Hz)."""
        m, L = self.mass, self.length
        return float(np.sqrt(gravity / L + self.stiffness / (m * L * L)) / (2 * np.pi))


@dataclass(frozen=True)
class Transducer:
    """Reference point ``position`` (m, tank components) and the turn of the transducer's
    axes from the tank axes (``roll``, ``pitch``, ``yaw`` in rad, z-y-x)."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    @property
    def matrix(self) -> np.ndarray:
        return rotation(self.roll, self.pitch, self.yaw)


@dataclass(frozen=True)
class Noise:
    """What acquisition adds. ``force`` and ``torque``: white noise as fractions of the
    largest standard deviation (the swing about the mean) of the force and of the torque
    channels; ``tone``: ``(fraction, Hz)``, a line of that fraction of the same scale on
    every channel (its own phase each); ``drift``:
    the offset drifts linearly from 0 to that fraction (sign drawn per channel);
    ``quantum``: ``(N, N m)`` steps of the recorded values (``None``: none); ``motion``:
    ``(m, rad)`` white noise on the recorded translations and angles."""

    force: float = 0.015
    torque: float = 0.015
    tone: tuple[float, float] | None = (0.03, 27.0)
    drift: float = 0.02
    quantum: tuple[float, float] | None = None
    motion: tuple[float, float] = (2e-5, 2e-4)


def _cross(a, b):
    return np.cross(a, b)


def _cross3(a, b):
    """``a x b`` of two 3-vectors (np.cross costs ~30 times more on one pair)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _bob(p: SphericalPendulum, a, b):
    """Relative position, its first and second partial derivatives in ``(a, b)``."""
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    L = p.length
    rho = np.array([L * sa * cb, L * sb, p.hinge_height - L * ca * cb])
    r_a = L * np.array([ca * cb, 0.0, sa * cb])
    r_b = L * np.array([-sa * sb, cb, ca * sb])
    r_aa = L * np.array([-sa * cb, 0.0, ca * cb])
    r_ab = L * np.array([-ca * sb, 0.0, -sa * sb])
    r_bb = L * np.array([-sa * cb, -sb, ca * cb])
    return rho, r_a, r_b, r_aa, r_ab, r_bb


def _pendulum(p: SphericalPendulum, x, omega, alpha, a_o, g):
    """Angle accelerations ``(a'', b'')`` and the bob's absolute acceleration ``A`` (tank
    components) at one instant."""
    a, b, ad, bd = x
    rho, r_a, r_b, r_aa, r_ab, r_bb = _bob(p, a, b)
    v_rel = r_a * ad + r_b * bd
    quad = r_aa * ad * ad + 2 * r_ab * ad * bd + r_bb * bd * bd
    # everything in A but the angle accelerations
    rest = (a_o + quad + 2 * _cross3(omega, v_rel) + _cross3(alpha, rho)
            + _cross3(omega, _cross3(omega, rho)))
    m = p.mass
    m11, m12, m22 = m * (r_a @ r_a), m * (r_a @ r_b), m * (r_b @ r_b)
    f1 = -m * (r_a @ (rest - g)) - p.damping * ad - p.stiffness * a
    f2 = -m * (r_b @ (rest - g)) - p.damping * bd - p.stiffness * b
    det = m11 * m22 - m12 * m12
    acc = np.array([(m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det])
    return acc, rest + r_a * acc[0] + r_b * acc[1], rho


def _loads(t, X, motion: Motion, pendulum, fixed, dry_mass):
    """Force and torque about ``O`` (tank components, each (n, 3)) and the kinematics."""
    R, omega, alpha, a_o, g = motion.kinematics(t)
    force = dry_mass * (a_o - g)
    torque = np.zeros_like(force)
    if fixed is not None:
        rf = np.array([0.0, 0.0, fixed.height])
        A_f = a_o + _cross(alpha, rf) + _cross(omega, _cross(omega, rf))
        F_f = fixed.mass * (A_f - g)
        inertia = np.array([fixed.inertia, fixed.inertia, fixed.axial_inertia])
        h = inertia * omega
        force = force + F_f
        torque = torque + _cross(rf, F_f) + inertia * alpha + _cross(omega, h)
    if pendulum is not None:
        for i in range(t.size):
            _, A, rho = _pendulum(pendulum, X[i], omega[i], alpha[i], a_o[i], g[i])
            F_p = pendulum.mass * (A - g[i])
            force[i] += F_p
            torque[i] += _cross(rho, F_p)
    return force, torque, (R, omega, alpha, a_o, g)


def energy(t, X, motion: Motion, *, pendulum=None, fixed=None, dry_mass=0.0, power=False):
    """Total mechanical energy (J) of the tank assembly in the lab (kinetic plus gravity's
    potential, lab z up), and with ``power`` also the power the transducer delivers
    (``F . v_O + M_O . omega``, W), on the times ``t`` for the states ``X`` (n, 4)."""
    t = np.atleast_1d(np.asarray(t, float))
    R, omega, alpha, a_o, g = motion.kinematics(t)
    pos = np.stack([motion.axis(a, t)[0] for a in "xyz"], axis=1)
    vel = np.stack([motion.axis(a, t)[1] for a in "xyz"], axis=1)
    v_o = np.einsum("nji,nj->ni", R, vel)  # tank components
    grav = motion.gravity

    def point(mass, rho, v_rel):
        v = v_o + _cross(omega, rho) + v_rel
        z = pos[:, 2] + np.einsum("nj,nj->n", R[:, 2, :], rho)
        return 0.5 * mass * np.einsum("nj,nj->n", v, v) + mass * grav * z

    zero = np.zeros_like(v_o)
    E = point(dry_mass, zero, zero)
    if fixed is not None:
        rf = np.broadcast_to([0.0, 0.0, fixed.height], v_o.shape)
        inertia = np.array([fixed.inertia, fixed.inertia, fixed.axial_inertia])
        E = E + point(fixed.mass, rf, zero) + 0.5 * np.einsum("nj,nj->n", omega, inertia * omega)
    if pendulum is not None:
        rho = np.empty_like(v_o)
        v_rel = np.empty_like(v_o)
        for i in range(t.size):
            r, r_a, r_b, *_ = _bob(pendulum, X[i, 0], X[i, 1])
            rho[i], v_rel[i] = r, r_a * X[i, 2] + r_b * X[i, 3]
        E = E + point(pendulum.mass, rho, v_rel)
    if not power:
        return E
    F, M, _ = _loads(t, X, motion, pendulum, fixed, dry_mass)
    return E, np.einsum("nj,nj->n", F, v_o) + np.einsum("nj,nj->n", M, omega)


def simulate_motion(t, motion: Motion, *, pendulum: SphericalPendulum | None = None,
                    fixed: FixedMass | None = None, dry_mass: float = 0.0,
                    transducer: Transducer = Transducer(), noise: Noise | None = None,
                    seed: int = 0, x0=None, rtol: float = 1e-10, atol: float = 1e-12
                    ) -> dict:
    """Six-axis record of the tank moved by ``motion`` on the grid ``t`` (s), the pendulum
    from rest unless ``x0 = (a, b, a', b')``.

    Returns a dict: ``time``; the six channels as recorded (with ``noise``; exact without);
    ``clean`` (the exact channels in the transducer's axes at its point); ``tank`` (the
    exact force and torque about ``O`` in tank axes, ``(n, 3)`` each); ``states`` (n, 4);
    ``motion`` (each moving axis as recorded, m or rad) and ``motion_clean`` (value, rate,
    acceleration of every axis).
    """
    t = np.asarray(t, float)
    state0 = np.zeros(4) if x0 is None else np.asarray(x0, float)
    if pendulum is not None:
        def rhs(tt, x):
            omega, alpha, a_o, g = motion.at(tt)
            acc, _, _ = _pendulum(pendulum, x, omega, alpha, a_o, g)
            return np.array([x[2], x[3], acc[0], acc[1]])

        sol = solve_ivp(rhs, (t[0], t[-1]), state0, method="DOP853", t_eval=t, rtol=rtol,
                        atol=atol)
        if not sol.success:  # pragma: no cover - a reference that fails must say so
            raise RuntimeError(sol.message)
        X = sol.y.T.copy()
    else:
        X = np.zeros((t.size, 4))
    F, M, _ = _loads(t, X, motion, pendulum, fixed, dry_mass)
    S = transducer.matrix
    r_p = np.asarray(transducer.position, float)
    F_s = F @ S  # rows: S^T F
    M_s = (M - _cross(r_p, F)) @ S
    clean = dict(zip(CHANNELS, (*F_s.T, *M_s.T)))
    out: dict = {"time": t, "clean": clean, "tank": {"force": F, "torque": M}, "states": X,
                 "motion_clean": {a: motion.axis(a, t) for a in AXES}}
    rng = np.random.default_rng(seed)
    nz = noise or Noise(0.0, 0.0, None, 0.0, None, (0.0, 0.0))
    # the scale of each kind is the largest swing about its mean (the weight in force_z and
    # its moment are no signal of a moving tank)
    scale = {"force": max(np.std(clean[c]) for c in CHANNELS[:3]),
             "torque": max(np.std(clean[c]) for c in CHANNELS[3:])}
    ramp = (t - t[0]) / (t[-1] - t[0])
    for c in CHANNELS:
        kind = c.split("_")[0]
        s = scale[kind]
        y = clean[c] + getattr(nz, kind) * s * rng.standard_normal(t.size)
        if nz.tone is not None:
            y = y + nz.tone[0] * s * np.sin(2 * np.pi * nz.tone[1] * t + rng.uniform(0, 2 * np.pi))
        if nz.drift:
            y = y + rng.choice((-1.0, 1.0)) * nz.drift * s * ramp
        if nz.quantum is not None:
            q = nz.quantum[0 if kind == "force" else 1]
            y = q * np.round(y / q)
        out[c] = y
    out["motion"] = {a: out["motion_clean"][a][0]
                     + nz.motion[0 if a in "xyz" else 1] * rng.standard_normal(t.size)
                     for a in motion.axes}
    return out


@dataclass(frozen=True)
class Truth:
    """What a record was made with (for tests): analogs, dry mass, gravity."""

    pendulum: SphericalPendulum
    fixed: FixedMass
    dry_mass: float
    gravity: float = STANDARD_GRAVITY
    extra: dict = field(default_factory=dict)
