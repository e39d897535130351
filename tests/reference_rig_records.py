"""Records as real rigs make them: transport moves, servo-followed motion, a six-axis
force/torque sensor's internal filter and quantisation, coloured noise, stream lag and
receive-time timestamps.

Independent of the project (numpy, SciPy and ``reference_models`` only), like
``reference_models``: it shapes what :func:`reference_models.simulate_lateral` computes into
what an acquisition system writes. See ``/work/shared/notes/test-records.md`` ("What records
from real hardware add") for why each effect is here.

Typical use::

    move = TransportMove(distance=0.4, duration=0.8, start=1.0)
    true = ServoFollow(move, lag=0.012, ripple=2e-5, ripple_frequency=18.0)
    sim = ref.simulate_lateral(t, true, pendulums=[...], fixed_mass=..., dry_mass=...,
                               sensor_delay=0.020)
    force = force_sensor(t, sim["force_clean"], rng=rng)
    planned = move(t)[0]                      # the commanded path
    measured = encoder_position(sim["displacement_clean"], rng=rng)
    stamps = receive_times(t, jitter=1e-3, rng=rng)

The lag a fit sees between motion and force is ``sensor_delay`` plus the sensor filter's
low-frequency group delay (:func:`sensor_group_delay`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

__all__ = ["TransportMove", "ServoFollow", "force_sensor", "force_through_sensor", "sensor_group_delay",
           "encoder_position", "receive_times", "cylinder_first_mode", "sphere_liquid_mass"]

Array = NDArray[np.float64]
G = 9.80665


@dataclass(frozen=True)
class TransportMove:
    """A rest-to-rest move of ``distance`` [m] in ``duration`` [s] starting at ``start`` [s]:
    ``x = distance * s(u)``, ``u = (t - start) / duration``, with the septic polynomial
    ``s = 35 u^4 - 84 u^5 + 70 u^6 - 20 u^7`` (velocity, acceleration and jerk zero at both
    ends: a jerk-limited robot path). Peak acceleration ``7.51 distance / duration^2``."""

    distance: float
    duration: float
    start: float = 0.0

    def _u(self, t: ArrayLike) -> Array:
        return np.clip((np.asarray(t, float) - self.start) / self.duration, 0.0, 1.0)

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        u, T, D = self._u(t), self.duration, self.distance
        s = 35 * u**4 - 84 * u**5 + 70 * u**6 - 20 * u**7
        ds = (140 * u**3 - 420 * u**4 + 420 * u**5 - 140 * u**6) / T
        dds = (420 * u**2 - 1680 * u**3 + 2100 * u**4 - 840 * u**5) / T**2
        return D * s, D * ds, D * dds

    def at(self, t: float) -> tuple[float, float, float]:
        """:meth:`__call__` at one time [s], on floats (the integrator's right-hand side)."""
        u, T, D = min(max((t - self.start) / self.duration, 0.0), 1.0), self.duration, self.distance
        return (D * (35 * u**4 - 84 * u**5 + 70 * u**6 - 20 * u**7),
                D * (140 * u**3 - 420 * u**4 + 420 * u**5 - 140 * u**6) / T,
                D * (420 * u**2 - 1680 * u**3 + 2100 * u**4 - 840 * u**5) / T**2)

    def window(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        """A smooth bump ``w = 64 u^3 (1 - u)^3`` over the move (0 outside, 1 at mid-move,
        C2 at both ends) and its two time derivatives: where servo ripple lives."""
        u, T = self._u(t), self.duration
        w = 64 * u**3 * (1 - u) ** 3
        dw = 192 * u**2 * (1 - u) ** 2 * (1 - 2 * u) / T
        ddw = 384 * u * (1 - u) * ((1 - 2 * u) ** 2 - u * (1 - u)) / T**2
        return w, dw, ddw


@dataclass(frozen=True)
class ServoFollow:
    """The motion a servo really makes of a commanded :class:`TransportMove`: the command
    delayed by ``lag`` [s] plus a ripple of ``ripple`` [m] at ``ripple_frequency`` [Hz]
    while moving (the drive's cogging), with exact derivatives. The planned path is
    ``command(t)``; the tank moves by ``self(t)``."""

    command: TransportMove
    lag: float = 0.0
    ripple: float = 0.0
    ripple_frequency: float = 20.0

    def __call__(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, float) - self.lag
        x, xd, xdd = self.command(tt)
        if self.ripple:
            w, dw, ddw = self.command.window(tt)
            om = 2 * math.pi * self.ripple_frequency
            s, c = np.sin(om * tt), np.cos(om * tt)
            a = self.ripple
            x = x + a * w * s
            xd = xd + a * (dw * s + w * om * c)
            xdd = xdd + a * (ddw * s + 2 * dw * om * c - w * om**2 * s)
        return x, xd, xdd

    def at(self, t: float) -> tuple[float, float, float]:
        """:meth:`__call__` at one time [s], on floats (the integrator's right-hand side)."""
        tt = t - self.lag
        x, xd, xdd = self.command.at(tt)
        if self.ripple:
            u, T = min(max((tt - self.command.start) / self.command.duration, 0.0), 1.0), \
                self.command.duration
            w = 64 * u**3 * (1 - u) ** 3
            dw = 192 * u**2 * (1 - u) ** 2 * (1 - 2 * u) / T
            ddw = 384 * u * (1 - u) * ((1 - 2 * u) ** 2 - u * (1 - u)) / T**2
            om = 2 * math.pi * self.ripple_frequency
            s, c, a = math.sin(om * tt), math.cos(om * tt), self.ripple
            x += a * w * s
            xd += a * (dw * s + w * om * c)
            xdd += a * (ddw * s + 2 * dw * om * c - w * om**2 * s)
        return x, xd, xdd


def sensor_group_delay(cutoff_hz: float, damping: float = 0.7) -> float:
    """Low-frequency group delay [s] of the sensor's 2nd-order low-pass: ``2 zeta / omega_c``."""
    return 2 * damping / (2 * math.pi * cutoff_hz)


def force_sensor(t: ArrayLike, force: ArrayLike, *, rng: np.random.Generator,
                 cutoff_hz: float = 60.0, damping: float = 0.7, quantum: float = 0.005,
                 white: float = 0.01, pink: float = 0.01,
                 lines: tuple[tuple[float, float], ...] = ((17.3, 0.004), (50.0, 0.003)),
                 offset: float = 0.02, drift: float = 0.0) -> Array:
    """What a six-axis transducer channel records of the ``force`` [N] at uniform ``t`` [s].

    White noise (std ``white`` [N]), 1/f noise (std ``pink`` [N]), structural/electrical
    ``lines`` ``(Hz, amplitude N)``, an ``offset`` [N] and ``drift`` [N/s] are added to the
    force, which then passes the sensor's internal 2nd-order low-pass (``cutoff_hz``,
    ``damping``; started in steady state on the first value) and is quantised in steps of
    ``quantum`` [N]. Above the filter the spectrum holds little but quantisation, while the
    noise in the slosh band is several times larger and coloured.
    """
    tt = np.asarray(t, float)
    F = np.asarray(force, float)
    n = tt.size
    raw = F + offset + drift * (tt - tt[0]) + rng.normal(0.0, white, n)
    if pink:
        spec = np.fft.rfft(rng.normal(size=n))
        f = np.arange(spec.size, dtype=float)
        f[0] = 1.0
        spec = spec / np.sqrt(f)
        spec[0] = 0.0
        p = np.fft.irfft(spec, n)
        raw = raw + pink * p / np.std(p)
    for freq, amp in lines:
        raw = raw + amp * np.sin(2 * math.pi * freq * tt + rng.uniform(0, 2 * math.pi))
    wc = 2 * math.pi * cutoff_hz
    sys = signal.lti([wc**2], [1.0, 2 * damping * wc, wc**2])
    _, filtered, _ = signal.lsim(sys, raw - raw[0], tt - tt[0], interp=True)
    filtered = filtered + raw[0]
    return quantum * np.round(filtered / quantum) if quantum else filtered


def force_through_sensor(csv, sim: dict, seed: int) -> None:
    """Replace the force column of a ``time,displacement,force`` CSV (``synthetic_cases.
    make_case``'s) by what :func:`force_sensor` records of the simulated force ``sim`` (no
    offset; its generator seeded with ``seed``)."""
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    data[:, 2] = force_sensor(sim["time"], sim["force"], rng=np.random.default_rng(seed),
                              offset=0.0)
    np.savetxt(csv, data, delimiter=",", header="time,displacement,force", comments="",
               fmt="%.12g")


def encoder_position(position: ArrayLike, *, rng: np.random.Generator, resolution: float = 5e-6,
                     noise: float = 1e-5) -> Array:
    """A position [m] read from joint encoders through forward kinematics: white noise
    ``noise`` [m] (kinematic errors, arm vibration) then quantised to ``resolution`` [m].
    Differentiated twice it shows accelerations far above the true ones."""
    x = np.asarray(position, float) + rng.normal(0.0, noise, np.size(position))
    return resolution * np.round(x / resolution) if resolution else x


def receive_times(t: ArrayLike, *, jitter: float, rng: np.random.Generator) -> Array:
    """Receive-time timestamps [s] of samples taken at ``t``: each stamp is late by a random
    ``[0, 2 jitter]`` minus the mean ``jitter`` (so +/- ``jitter`` about the true time), kept
    strictly increasing as a logger writes them."""
    tt = np.asarray(t, float)
    stamps = tt + rng.uniform(-jitter, jitter, tt.size)
    step = float(np.median(np.diff(tt)))
    for i in range(1, stamps.size):  # a logger never writes a stamp before the previous one
        if stamps[i] <= stamps[i - 1]:
            stamps[i] = stamps[i - 1] + 1e-3 * step
    return stamps


def cylinder_first_mode(radius: float, depth: float, density: float = 998.2,
                        gravity: float = G) -> dict[str, float]:
    """First lateral slosh mode of an upright circular cylinder (flat bottom, free surface),
    from the textbook potential-flow solution (Abramson, NASA SP-106, ch. 6; Ibrahim 2005):
    ``omega^2 = g xi tanh(xi h / R) / R`` with ``xi = 1.8412`` (first root of J1'),
    slosh mass ``m1 = m_liquid 2 tanh(xi h / R) / (xi (xi^2 - 1) h / R)``, pendulum length
    ``L = g / omega^2``. Returns ``liquid_mass`` [kg], ``mass`` [kg], ``length`` [m],
    ``frequency`` [Hz]."""
    xi = 1.8411837813406593
    ml = density * math.pi * radius**2 * depth
    th = math.tanh(xi * depth / radius)
    om2 = gravity * xi * th / radius
    m1 = ml * 2 * th / (xi * (xi**2 - 1) * depth / radius)
    return {"liquid_mass": ml, "mass": m1, "length": gravity / om2,
            "frequency": math.sqrt(om2) / (2 * math.pi)}


def sphere_liquid_mass(radius: float, fill: float, density: float = 998.2) -> float:
    """Liquid mass [kg] of a sphere of ``radius`` [m] filled to depth ``fill * 2 radius``:
    a spherical cap ``pi h^2 (3 R - h) / 3``."""
    h = 2 * radius * fill
    return density * math.pi * h**2 * (3 * radius - h) / 3
