"""Independent reference simulator of a lateral slosh rig, for tests and example data.

Plain numpy + ``scipy.integrate.solve_ivp`` with HAND-WRITTEN equations; it deliberately does
not import ``analogs``, ``derive`` or ``estimate``, so it can check them.

Model
-----
The tank translates by a prescribed ``x(t)`` along the rig axis. Each planar pendulum ``i``
(bob mass ``m``, length ``L``, hinge spring ``k`` [N m/rad], linear hinge damper ``c``
[N m s/rad], quadratic hinge damper ``c2`` [N m s^2/rad^2], torque ``c2 thd |thd|``) obeys::

    m L^2 thdd + m L xdd cos(th) + m g L sin(th) + k th + c thd + c2 thd |thd| + T = 0

where ``T`` holds the optional hinge torques of a diaphragm or bearing: a cubic spring
``k3 th^3`` [N m/rad^3], Coulomb friction ``Tc sign(thd)`` [N m] (made continuous as
``Tc tanh(thd / 1e-3 rad/s)``, far sharper than the estimation's regularisation) and any
other torque ``extra(th, thd)`` [N m] a test supplies (effects outside every analog family).

and the force the transducer measures is::

    F = (m_dry + m_fixed) xdd + sum_i m_i (xdd + L_i thdd_i cos(th_i) - L_i thd_i^2 sin(th_i))

Measurement effects (all optional):

* sensor delay ``tau``: the recorded force at ``t`` is the force at ``t - tau``. The pendulums
  start from their initial state at ``t[0] - tau`` and ``solve_ivp`` reports the state exactly
  at both ``t`` and ``t - tau`` (``t_eval``), so no interpolation is involved.
* rig friction seen by the transducer: ``F_c sign(xd) + c_v xd`` (the transducer pushes the
  carriage, so it also pushes against the friction).
* a motor tone ``a sin(2 pi f t + phase)`` added to the force.
* white Gaussian force noise of standard deviation ``noise * RMS(F_mech)``, with ``F_mech`` the
  delayed mechanical force plus friction (the tone is not counted), and optional white
  displacement noise [m].

Excitations are objects returning ``(x, xd, xdd)`` at any times, with analytic derivatives:
:class:`Sine`, :class:`Crank` (the seed's "locomotive arm"), :class:`LinearSweep`,
:class:`SteppedSweep` and :class:`AmplitudeSteps` (the last two with smooth C2 transitions so the
acceleration stays finite and continuous), and :class:`Ramped`, any of them faded in from rest.

Example
-------
>>> import numpy as np
>>> from reference_models import Pendulum, Sine, simulate_lateral
>>> t = np.arange(3001) * 0.01
>>> out = simulate_lateral(t, Sine(0.005, 1.855), pendulums=[Pendulum(1.338, 0.057)],
...                        fixed_mass=1.456, dry_mass=1.2)
>>> out["force"].shape
(3001,)
"""

from __future__ import annotations

import math
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

__all__ = [
    "AmplitudeSteps",
    "Crank",
    "Excitation",
    "Friction",
    "LinearSweep",
    "Pendulum",
    "Ramped",
    "Sine",
    "SteppedSweep",
    "Tone",
    "hinge_damping",
    "natural_frequency",
    "simulate_lateral",
]

Array = NDArray[np.float64]
STANDARD_GRAVITY = 9.80665


# ----------------------------------------------------------------------------------------------
# components and measurement effects


@dataclass(frozen=True)
class Pendulum:
    """Planar pendulum on the tank.

    Attributes
    ----------
    mass : float
        Bob mass m [kg].
    length : float
        Length L [m].
    stiffness : float
        Hinge spring k [N m/rad].
    damping : float
        Linear hinge damper c [N m s/rad].
    quadratic_damping : float
        Quadratic hinge damper c2 [N m s^2/rad^2] (torque ``c2 thd |thd|``).
    cubic_stiffness : float
        Cubic hinge spring k3 [N m/rad^3] (torque ``k3 th^3``; > 0 hardens).
    coulomb : float
        Coulomb (dry) hinge friction Tc [N m] (torque ``Tc sign(thd)``).
    extra : callable, optional
        Any further hinge torque ``extra(th, thd)`` [N m], vectorised over arrays.
    """

    mass: float
    length: float
    stiffness: float = 0.0
    damping: float = 0.0
    quadratic_damping: float = 0.0
    cubic_stiffness: float = 0.0
    coulomb: float = 0.0
    extra: object = None


def natural_frequency(p: Pendulum, gravity: float = STANDARD_GRAVITY) -> float:
    """Small-amplitude undamped natural frequency ``sqrt(g/L + k/(m L^2))`` [rad/s]."""
    return float(np.sqrt(gravity / p.length + p.stiffness / (p.mass * p.length**2)))


def hinge_damping(mass: float, length: float, damping_ratio: float, *, stiffness: float = 0.0,
                  gravity: float = STANDARD_GRAVITY) -> float:
    """Hinge damper ``c = 2 zeta m L^2 omega`` [N m s/rad] for a damping ratio ``zeta``."""
    omega = np.sqrt(gravity / length + stiffness / (mass * length**2))
    return float(2.0 * damping_ratio * mass * length**2 * omega)


@dataclass(frozen=True)
class Tone:
    """Motor tone added to the measured force: ``amplitude sin(2 pi frequency t + phase)``.

    Attributes
    ----------
    amplitude : float
        [N].
    frequency : float
        [Hz].
    phase : float
        [rad].
    """

    amplitude: float
    frequency: float
    phase: float = 0.0


@dataclass(frozen=True)
class Friction:
    """Rig friction seen by the transducer: ``coulomb sign(xd) + viscous xd``.

    Attributes
    ----------
    coulomb : float
        Coulomb force level [N].
    viscous : float
        Viscous coefficient [N s/m].
    """

    coulomb: float = 0.0
    viscous: float = 0.0


# ----------------------------------------------------------------------------------------------
# excitations


class Excitation(Protocol):
    """Prescribed carriage motion: ``motion(t) -> (x [m], xd [m/s], xdd [m/s^2])``."""

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]: ...


def _harmonic(a: Array, da: Array, dda: Array, ph: Array, dph: Array, ddph: Array
              ) -> tuple[Array, Array, Array]:
    """x = A(t) sin(phi(t)) and its first two derivatives (product and chain rules)."""
    s, c = np.sin(ph), np.cos(ph)
    x = a * s
    xd = da * s + a * dph * c
    xdd = dda * s + 2.0 * da * dph * c + a * ddph * c - a * dph**2 * s
    return x, xd, xdd


def _smoothstep_levels(t: Array, levels: Sequence[float], dwell: float, ramp: float
                       ) -> tuple[Array, Array, Array, Array]:
    """Piecewise-constant levels joined by quintic smoothsteps (C2).

    Level k holds from ``k dwell + ramp`` to ``(k + 1) dwell``; the change from level k-1 to k
    takes ``[k dwell, k dwell + ramp]``. Returns (value, d/dt, d2/dt2, integral from 0 to t).
    """
    v0 = float(levels[0])
    val = np.full_like(t, v0)
    d1 = np.zeros_like(t)
    d2 = np.zeros_like(t)
    integral = v0 * t
    for k in range(1, len(levels)):
        jump = float(levels[k]) - float(levels[k - 1])
        u = (t - k * dwell) / ramp
        uc = np.clip(u, 0.0, 1.0)
        inside = (u > 0.0) & (u < 1.0)
        val = val + jump * (10 * uc**3 - 15 * uc**4 + 6 * uc**5)
        d1 = d1 + np.where(inside, jump * (30 * uc**2 - 60 * uc**3 + 30 * uc**4) / ramp, 0.0)
        d2 = d2 + np.where(inside, jump * (60 * uc - 180 * uc**2 + 120 * uc**3) / ramp**2, 0.0)
        # integral of the smoothstep: 2.5 u^4 - 3 u^5 + u^6 on [0, 1] (0.5 at u = 1), then linear
        integ = np.where(u <= 0.0, 0.0,
                         np.where(u < 1.0, 2.5 * uc**4 - 3 * uc**5 + uc**6, 0.5 + (u - 1.0)))
        integral = integral + jump * ramp * integ
    return val, d1, d2, integral


@dataclass(frozen=True)
class Sine:
    """``x = amplitude sin(2 pi frequency t + phase)``; amplitude [m], frequency [Hz]."""

    amplitude: float
    frequency: float
    phase: float = 0.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        w = 2.0 * np.pi * self.frequency
        one = np.ones_like(tt)
        zero = np.zeros_like(tt)
        return _harmonic(self.amplitude * one, zero, zero, w * tt + self.phase, w * one, zero)


@dataclass(frozen=True)
class Crank:
    """The seed's crank ("locomotive arm") drive.

    Flywheel angle ``phi = phi0 + (2 pi frequency + d_omega) t``; carriage displacement
    ``x = r cos(phi) + sqrt(l^2 - r^2 sin(phi)^2) - l``.

    Attributes
    ----------
    radius : float
        Crank radius r [m].
    rod_length : float
        Connecting-rod length l [m] (> r).
    frequency : float
        Nominal drive frequency [Hz].
    d_omega : float
        Angular-velocity correction dOmega [rad/s].
    phi0 : float
        Initial flywheel angle [rad].
    """

    radius: float
    rod_length: float
    frequency: float
    d_omega: float = 0.0
    phi0: float = 0.0

    @property
    def omega(self) -> float:
        """Actual flywheel rate ``2 pi frequency + d_omega`` [rad/s]."""
        return 2.0 * np.pi * self.frequency + self.d_omega

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        r, l, om = self.radius, self.rod_length, self.omega
        phi = self.phi0 + om * tt
        sp, cp = np.sin(phi), np.cos(phi)
        s = np.sqrt(l**2 - r**2 * sp**2)
        g = r**2 * sp * cp                 # -(1/2) d(s^2)/dphi, so ds/dphi = -g / s
        dg = r**2 * (cp**2 - sp**2)
        x = r * cp + s - l
        xd = om * (-r * sp - g / s)
        xdd = om**2 * (-r * cp - dg / s - g**2 / s**3)
        return x, xd, xdd


@dataclass(frozen=True)
class LinearSweep:
    """Linear chirp from ``f_start`` to ``f_end`` [Hz] over ``duration`` [s], amplitude [m].

    The frequency is held at ``f_start`` before 0 and at ``f_end`` after ``duration`` (the
    acceleration has a finite jump in slope there).
    """

    amplitude: float
    f_start: float
    f_end: float
    duration: float
    phase: float = 0.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        rate = (self.f_end - self.f_start) / self.duration
        tc = np.clip(tt, 0.0, self.duration)
        cycles = self.f_start * tc + 0.5 * rate * tc**2
        cycles = cycles + np.where(tt < 0.0, self.f_start * tt, 0.0)
        cycles = cycles + np.where(tt > self.duration, self.f_end * (tt - self.duration), 0.0)
        freq = self.f_start + rate * tc
        dfreq = np.where((tt >= 0.0) & (tt <= self.duration), rate, 0.0)
        one = np.ones_like(tt)
        zero = np.zeros_like(tt)
        return _harmonic(self.amplitude * one, zero, zero, 2 * np.pi * cycles + self.phase,
                         2 * np.pi * freq, 2 * np.pi * dfreq)


@dataclass(frozen=True)
class SteppedSweep:
    """Stepped-frequency sine: ``frequencies`` [Hz] each held ``dwell`` [s], amplitude [m].

    Frequency changes take ``ramp`` seconds (quintic smoothstep), phase continuous.
    """

    amplitude: float
    frequencies: tuple[float, ...]
    dwell: float
    ramp: float = 0.5
    phase: float = 0.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        f, df, ddf, cycles = _smoothstep_levels(tt, self.frequencies, self.dwell, self.ramp)
        one = np.ones_like(tt)
        zero = np.zeros_like(tt)
        return _harmonic(self.amplitude * one, zero, zero, 2 * np.pi * cycles + self.phase,
                         2 * np.pi * f, 2 * np.pi * df)


@dataclass(frozen=True)
class AmplitudeSteps:
    """Sine at ``frequency`` [Hz] with amplitude ``amplitudes`` [m] each held ``dwell`` [s].

    Amplitude changes take ``ramp`` seconds (quintic smoothstep).
    """

    amplitudes: tuple[float, ...]
    frequency: float
    dwell: float
    ramp: float = 0.5
    phase: float = 0.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        a, da, dda, _ = _smoothstep_levels(tt, self.amplitudes, self.dwell, self.ramp)
        w = 2.0 * np.pi * self.frequency
        return _harmonic(a, da, dda, w * tt + self.phase, w * np.ones_like(tt), np.zeros_like(tt))


@dataclass(frozen=True)
class Ramped:
    """A drive faded in from rest, as rig tests start: ``x = s(t) x0(t)`` with ``s`` a quintic
    smoothstep from 0 at ``start`` [s] to 1 at ``start + duration`` [s] (C2: the carriage
    never jerks), 0 before; derivatives by the product rule.

    Attributes
    ----------
    drive : Excitation
        The steady drive ``x0(t)``.
    duration : float
        Ramp length [s].
    start : float, default 0
        Time the ramp begins [s]; the carriage is at rest before.
    """

    drive: Excitation
    duration: float
    start: float = 0.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        x0, xd0, xdd0 = self.drive(tt)
        u = np.clip((tt - self.start) / self.duration, 0.0, 1.0)
        inside = (u > 0.0) & (u < 1.0)
        s = 10 * u**3 - 15 * u**4 + 6 * u**5
        ds = np.where(inside, (30 * u**2 - 60 * u**3 + 30 * u**4) / self.duration, 0.0)
        dds = np.where(inside, (60 * u - 180 * u**2 + 120 * u**3) / self.duration**2, 0.0)
        return s * x0, ds * x0 + s * xd0, dds * x0 + 2 * ds * xd0 + s * xdd0


# ----------------------------------------------------------------------------------------------
# the drives at one time, for the integrator's right-hand side: the same formulas on floats
# (NumPy on one-element arrays cost ~25 us a call, the half of every reference record's time);
# ``test_reference_models`` checks them against the array forms above


def _harmonic_at(a: float, da: float, dda: float, ph: float, dph: float, ddph: float
                 ) -> tuple[float, float, float]:
    s, c = math.sin(ph), math.cos(ph)
    return (a * s, da * s + a * dph * c,
            dda * s + 2.0 * da * dph * c + a * ddph * c - a * dph**2 * s)


def _smoothstep_at(u: float, duration: float) -> tuple[float, float, float]:
    """The quintic smoothstep at ``u`` (clipped to [0, 1]) and its time derivatives for a
    ramp of ``duration`` [s]."""
    uc = min(max(u, 0.0), 1.0)
    s = 10 * uc**3 - 15 * uc**4 + 6 * uc**5
    if not 0.0 < u < 1.0:
        return s, 0.0, 0.0
    return (s, (30 * uc**2 - 60 * uc**3 + 30 * uc**4) / duration,
            (60 * uc - 180 * uc**2 + 120 * uc**3) / duration**2)


def _levels_at(t: float, levels: Sequence[float], dwell: float, ramp: float
               ) -> tuple[float, float, float, float]:
    val, d1, d2 = float(levels[0]), 0.0, 0.0
    integral = val * t
    for k in range(1, len(levels)):
        jump = float(levels[k]) - float(levels[k - 1])
        u = (t - k * dwell) / ramp
        uc = min(max(u, 0.0), 1.0)
        s, ds, dds = _smoothstep_at(u, ramp)
        val, d1, d2 = val + jump * s, d1 + jump * ds, d2 + jump * dds
        integ = 0.0 if u <= 0.0 else (2.5 * uc**4 - 3 * uc**5 + uc**6 if u < 1.0 else 0.5 + (u - 1.0))
        integral += jump * ramp * integ
    return val, d1, d2, integral


def drive_at(excitation: Excitation):
    """``excitation`` at one time [s] as floats ``(x, xd, xdd)``, or None for a drive without
    a float form (the integrator then calls it on a one-element array). A drive of another
    module gives its own as an ``at(t)`` method."""
    e = excitation
    if hasattr(e, "at"):
        return e.at
    if isinstance(e, Sine):
        w = 2.0 * math.pi * e.frequency
        return lambda t: _harmonic_at(e.amplitude, 0.0, 0.0, w * t + e.phase, w, 0.0)
    if isinstance(e, LinearSweep):
        rate = (e.f_end - e.f_start) / e.duration

        def sweep(t: float) -> tuple[float, float, float]:
            tc = min(max(t, 0.0), e.duration)
            cycles = e.f_start * tc + 0.5 * rate * tc**2
            cycles += e.f_start * t if t < 0.0 else 0.0
            cycles += e.f_end * (t - e.duration) if t > e.duration else 0.0
            dfreq = rate if 0.0 <= t <= e.duration else 0.0
            return _harmonic_at(e.amplitude, 0.0, 0.0, 2 * math.pi * cycles + e.phase,
                                2 * math.pi * (e.f_start + rate * tc), 2 * math.pi * dfreq)
        return sweep
    if isinstance(e, SteppedSweep):
        def stepped(t: float) -> tuple[float, float, float]:
            f, df, _, cycles = _levels_at(t, e.frequencies, e.dwell, e.ramp)
            return _harmonic_at(e.amplitude, 0.0, 0.0, 2 * math.pi * cycles + e.phase,
                                2 * math.pi * f, 2 * math.pi * df)
        return stepped
    if isinstance(e, AmplitudeSteps):
        w = 2.0 * math.pi * e.frequency

        def steps(t: float) -> tuple[float, float, float]:
            a, da, dda, _ = _levels_at(t, e.amplitudes, e.dwell, e.ramp)
            return _harmonic_at(a, da, dda, w * t + e.phase, w, 0.0)
        return steps
    if isinstance(e, Ramped):
        inner = drive_at(e.drive)
        if inner is None:
            return None

        def ramped(t: float) -> tuple[float, float, float]:
            x0, xd0, xdd0 = inner(t)
            s, ds, dds = _smoothstep_at((t - e.start) / e.duration, e.duration)
            return s * x0, ds * x0 + s * xd0, dds * x0 + 2 * ds * xd0 + s * xdd0
        return ramped
    return None


# ----------------------------------------------------------------------------------------------
# simulation


#: Rate scale of the reference's Coulomb friction [rad/s]: ``Tc tanh(thd / this)``.
COULOMB_RATE = 1e-3


def hinge_torque(p: Pendulum, th: Array, thd: Array) -> Array:
    """The hinge torques ``k th + c thd + c2 thd|thd| + k3 th^3 + Tc sign(thd) + extra``."""
    torque = (p.stiffness * th + p.damping * thd + p.quadratic_damping * thd * np.abs(thd)
              + p.cubic_stiffness * th**3 + p.coulomb * np.tanh(thd / COULOMB_RATE))
    if p.extra is not None:
        torque = torque + p.extra(th, thd)
    return torque


def _pendulum_accel(th: Array, thd: Array, xdd: Array, p: Pendulum, g: float) -> Array:
    """thdd from m L^2 thdd + m L xdd cos th + m g L sin th + T(th, thd) = 0."""
    m, L = p.mass, p.length
    torque = m * L * xdd * np.cos(th) + m * g * L * np.sin(th) + hinge_torque(p, th, thd)
    return -torque / (m * L**2)


def simulate_lateral(
    t: ArrayLike,
    excitation: Excitation,
    *,
    pendulums: Sequence[Pendulum] = (),
    fixed_mass: float = 0.0,
    dry_mass: float = 0.0,
    gravity: float = STANDARD_GRAVITY,
    initial_theta: Sequence[float] | None = None,
    initial_theta_dot: Sequence[float] | None = None,
    sensor_delay: float = 0.0,
    noise: float = 0.0,
    displacement_noise: float = 0.0,
    tone: Tone | None = None,
    friction: Friction | None = None,
    offset: float = 0.0,
    drift: float = 0.0,
    pink_noise: float = 0.0,
    saturation: float = 0.0,
    seed: int | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> dict[str, NDArray[np.float64] | float | str]:
    """Simulate a lateral slosh rig with hand-written equations (DOP853).

    Parameters
    ----------
    t : array_like
        Increasing output times [s].
    excitation : Excitation
        Carriage motion, ``excitation(t) -> (x, xd, xdd)``.
    pendulums : sequence of Pendulum
        Planar pendulums (any number, may be empty).
    fixed_mass, dry_mass : float
        Fixed liquid mass and rig dry mass [kg], both moving rigidly with the tank.
    gravity : float, default 9.80665
        [m/s^2].
    initial_theta, initial_theta_dot : sequence of float, optional
        Pendulum angles [rad] and rates [rad/s] at ``t[0] - sensor_delay``; default at rest.
    sensor_delay : float, default 0
        Force sensor delay tau [s] >= 0: ``force[i]`` is the force at ``t[i] - tau``.
    noise : float, default 0
        Force noise standard deviation as a fraction of the RMS mechanical force [-].
    displacement_noise : float, default 0
        Displacement noise standard deviation [m].
    tone : Tone, optional
        Motor tone added to the force.
    friction : Friction, optional
        Rig friction seen by the transducer.
    offset, drift : float, default 0
        Transducer offset [N] and linear drift [N/s] added to the recorded force.
    pink_noise : float, default 0
        Standard deviation of an added 1/f ("pink") force noise as a fraction of the RMS
        mechanical force (spectrum shaped in the frequency domain from white noise, with the
        same seed).
    saturation : float, default 0
        Transducer soft saturation level [N]: when > 0 the recorded force (with tone,
        offset and drift, before the noise) is ``saturation * tanh(F / saturation)``, a
        transducer that reads low on large forces (an effect no analog describes).
    seed : int, optional
        Seed of ``numpy.random.default_rng`` for the noise.
    rtol, atol : float
        ``solve_ivp`` tolerances (angles in rad).

    Returns
    -------
    dict
        ``time`` [s]; ``displacement`` (with noise), ``displacement_clean`` [m]; ``velocity``
        [m/s]; ``acceleration`` [m/s^2]; ``force`` (everything), ``force_clean`` (delay,
        friction and tone, no noise), ``force_true`` (mechanical force at ``t``, no effects)
        [N]; ``theta``, ``theta_dot``, ``theta_ddot`` with shape (n_pendulums, n) at ``t``;
        ``nfev``; ``message``.
    """
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2 or np.any(np.diff(tt) <= 0):
        raise ValueError("expected a 1-D increasing array `t` with at least 2 samples")
    if sensor_delay < 0:
        raise ValueError(f"expected `sensor_delay` >= 0 s, found {sensor_delay!r}")
    pend = list(pendulums)
    n_p = len(pend)
    th0 = np.zeros(n_p) if initial_theta is None else np.asarray(initial_theta, dtype=float)
    thd0 = np.zeros(n_p) if initial_theta_dot is None else np.asarray(initial_theta_dot, dtype=float)
    if th0.shape != (n_p,) or thd0.shape != (n_p,):
        raise ValueError(f"expected {n_p} initial angles and rates, found {th0.shape}, {thd0.shape}")

    t_delayed = tt - sensor_delay
    t_all = np.unique(np.concatenate([tt, t_delayed]))
    t0 = t_all[0]

    m = np.array([p.mass for p in pend])
    L = np.array([p.length for p in pend])
    k = np.array([p.stiffness for p in pend])
    c = np.array([p.damping for p in pend])
    c2 = np.array([p.quadratic_damping for p in pend])
    inertia = m * L**2
    one = np.empty(1)

    plain = all(p.cubic_stiffness == 0 and p.coulomb == 0 and p.extra is None for p in pend)
    at_time = drive_at(excitation)

    def rhs(time: float, y: Array) -> Array:
        # the same equation as _pendulum_accel, vectorised over the pendulums for speed
        if at_time is not None:
            xdd = at_time(time)[2]
        else:
            one[0] = time
            xdd = excitation(one)[2][0]
        th, thd = y[:n_p], y[n_p:]
        torque = m * L * xdd * np.cos(th) + m * gravity * L * np.sin(th)
        if plain:
            torque = torque + k * th + c * thd + c2 * thd * np.abs(thd)
        else:
            torque = torque + np.array([hinge_torque(p, th[i], thd[i]) for i, p in enumerate(pend)])
        return np.concatenate([thd, -torque / inertia])

    nfev, message = 0, "no pendulums: nothing to integrate"
    if n_p:
        sol = solve_ivp(rhs, (t0, t_all[-1]), np.concatenate([th0, thd0]), method="DOP853",
                        t_eval=t_all, rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        states = sol.y
        nfev, message = int(sol.nfev), str(sol.message)
    else:
        states = np.zeros((0, t_all.size))

    def at(times: Array) -> tuple[Array, Array, Array, Array, Array, Array, Array]:
        idx = np.searchsorted(t_all, times)
        th, thd = states[:n_p, idx], states[n_p:, idx]
        x, xd, xdd = excitation(times)
        thdd = np.array([_pendulum_accel(th[i], thd[i], xdd, pend[i], gravity)
                         for i in range(n_p)]).reshape(n_p, times.size)
        force = (dry_mass + fixed_mass) * xdd
        for i, p in enumerate(pend):
            force = force + p.mass * (xdd + p.length * thdd[i] * np.cos(th[i])
                                      - p.length * thd[i] ** 2 * np.sin(th[i]))
        return x, xd, xdd, th, thd, thdd, force

    x, xd, xdd, th, thd, thdd, force_true = at(tt)
    _, xd_del, _, _, _, _, force_del = at(t_delayed)
    mech = force_del.copy()
    if friction is not None:
        mech = mech + friction.coulomb * np.sign(xd_del) + friction.viscous * xd_del
    clean = mech.copy()
    if tone is not None:
        clean = clean + tone.amplitude * np.sin(2 * np.pi * tone.frequency * tt + tone.phase)
    if offset or drift:
        clean = clean + offset + drift * (tt - tt[0])
    if saturation:
        clean = saturation * np.tanh(clean / saturation)
    rng = np.random.default_rng(seed)
    rms_mech = float(np.sqrt(np.mean(mech**2)))
    force = clean + rng.normal(0.0, noise * rms_mech, tt.size)
    if pink_noise:
        force = force + pink_noise * rms_mech * _pink(tt.size, rng)
    disp = x + rng.normal(0.0, displacement_noise, tt.size) if displacement_noise else x.copy()
    return {
        "time": tt.copy(), "displacement": disp, "displacement_clean": x, "velocity": xd,
        "acceleration": xdd, "force": force, "force_clean": clean, "force_true": force_true,
        "theta": th, "theta_dot": thd, "theta_ddot": thdd, "nfev": float(nfev),
        "message": message,
    }


def _pink(n: int, rng: np.random.Generator) -> Array:
    """Unit-variance noise with a 1/f power spectrum (white noise shaped by 1/sqrt(f))."""
    spec = np.fft.rfft(rng.normal(size=n))
    f = np.arange(spec.size, dtype=float)
    f[0] = 1.0
    spec = spec / np.sqrt(f)
    spec[0] = 0.0
    x = np.fft.irfft(spec, n)
    return x / np.std(x)
