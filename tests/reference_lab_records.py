"""Test types as labs record them: free decays with the carriage at rest, a short window cut
from a running test, a transport move with receive-time timestamps, and a displacement
integrated from an accelerometer (which drifts).

Independent of the project, like ``reference_models`` and ``reference_rig_records``: numpy,
SciPy and those two modules only. Every record returns the samples a lab would write
(``time``, ``displacement``, ``force``) and the truth (``truth``: the pendulum's natural
frequency in Hz and damping ratio, its mass and length, the fixed and dry masses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import reference_models as ref
import reference_rig_records as rig
from numpy.typing import NDArray
from scipy.integrate import cumulative_trapezoid

__all__ = ["Rest", "Tank", "SMALL", "LARGE", "free_decay", "running_window", "transport",
           "integrated_displacement"]

Array = NDArray[np.float64]
G = rig.G


@dataclass(frozen=True)
class Tank:
    """A tank's first-mode analog (a sphere's, from its modal analysis rounded) and the
    rig: pendulum ``mass`` [kg] and ``length`` [m], damping ratio ``zeta``, ``fixed`` and
    ``dry`` masses [kg]; the case-file keys of the sphere it stands for."""

    mass: float
    length: float
    zeta: float
    fixed: float
    dry: float
    radius: float
    fill: float

    @property
    def frequency(self) -> float:
        """Linear natural frequency [Hz]."""
        return math.sqrt(G / self.length) / (2 * math.pi)

    def pendulum(self) -> ref.Pendulum:
        return ref.Pendulum(self.mass, self.length, 0.0,
                            ref.hinge_damping(self.mass, self.length, self.zeta, gravity=G))

    def truth(self) -> dict[str, float]:
        return {"p1.mass": self.mass, "p1.length": self.length, "fixed.mass": self.fixed,
                "rig.dry_mass": self.dry, "p1.frequency_hz": self.frequency,
                "p1.damping_ratio": self.zeta}


#: The 8-inch sphere at 60 % fill (2.08 Hz) and a 0.5 m sphere at 50 % (0.90 Hz, smaller
#: damping: viscous damping falls as R^-3/4); each a little off its tank's modal
#: prediction (1.335 kg, 0.0568 m, 0.73 %; 151.5 kg, 0.320 m, 0.27 %), as real tanks are.
SMALL = Tank(mass=1.32, length=0.0575, zeta=0.008, fixed=1.50, dry=1.2, radius=0.1016, fill=0.6)
LARGE = Tank(mass=148.0, length=0.31, zeta=0.0025, fixed=112.0, dry=40.0, radius=0.5, fill=0.5)


class Rest:
    """The carriage at rest: ``(x, xd, xdd) = 0``."""

    def __call__(self, t):
        z = np.zeros(np.shape(t))
        return z, z, z


def _record(t: Array, motion, tank: Tank, rng: np.random.Generator, *, theta0: float = 0.0,
            theta_dot0: float = 0.0, lag: float = 0.0, sensor: dict | None = None,
            encoder: dict | None = None) -> dict:
    sim = ref.simulate_lateral(t, motion, pendulums=[tank.pendulum()], fixed_mass=tank.fixed,
                               dry_mass=tank.dry, gravity=G, initial_theta=[theta0],
                               initial_theta_dot=[theta_dot0], sensor_delay=lag)
    scale = float(np.sqrt(np.mean(sim["force_true"] ** 2)))
    opts = {"white": 0.01 * scale, "pink": 0.005 * scale,
            "lines": ((17.3, 0.003 * scale), (50.0, 0.002 * scale)), "quantum": 0.002 * scale,
            "offset": 0.0} | (sensor or {})
    force = rig.force_sensor(t, sim["force_clean"], rng=rng, **opts)
    disp = rig.encoder_position(sim["displacement_clean"], rng=rng, **(encoder or {}))
    return {"time": t, "displacement": disp, "force": force, "truth": tank.truth(), "sim": sim}


def free_decay(tank: Tank, *, rate: float = 500.0, duration: float = 12.0, theta0: float = 0.3,
               seed: int = 0) -> dict:
    """The natural-frequency test: the tank was shaken and stopped; the record starts with
    the carriage at rest and the liquid swinging (``theta0`` rad, at rest in its swing).
    The displacement is an encoder's (constant but for its noise and 5 um steps)."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    return _record(t, Rest(), tank, np.random.default_rng(seed), theta0=theta0)


def running_window(tank: Tank, *, rate: float = 500.0, amplitude: float | None = None,
                   frequency_ratio: float = 0.95, start: float = 14.0, window: float = 2.0,
                   seed: int = 0) -> dict:
    """A ``window`` s cut from the middle of a running sine test: a sine of ``amplitude`` m
    (default 1.8 % of the pendulum length: swings of about 0.1 rad) at ``frequency_ratio``
    times the natural frequency ramped in over 3 s from rest at t = 0, recorded from
    ``start`` s on (the liquid and the carriage moving at the first sample). Force noise
    1.5 % RMS white, a 17.3 Hz line and a drifting offset; displacement noise 2e-5 m.
    Neither a sensor filter nor 1/f noise: a filter's group delay is a lag between the
    channels, and 1/f noise puts power at the slosh frequency, which a 2 s window cannot
    tell from damping (0.5 % 1/f noise moved the damping ratio by +70 to +230 %, a 3.7 ms
    lag by a factor 30) unless the lag and a noise model are estimated too."""
    amplitude = 0.018 * tank.length if amplitude is None else amplitude
    f = frequency_ratio * tank.frequency
    full = np.arange(int(round((start + window) * rate)) + 1) / rate
    sim = ref.simulate_lateral(full, ref.Ramped(ref.Sine(amplitude, f), 3.0),
                               pendulums=[tank.pendulum()], fixed_mass=tank.fixed,
                               dry_mass=tank.dry, gravity=G, noise=0.015,
                               tone=ref.Tone(0.002 * (tank.mass + tank.fixed + tank.dry), 17.3),
                               offset=0.001 * (tank.mass + tank.fixed + tank.dry) * G,
                               drift=1e-4 * (tank.mass + tank.fixed + tank.dry) * G,
                               displacement_noise=2e-5, seed=seed)
    keep = full >= start - 1e-12
    out = {k: sim[k][keep] for k in ("time", "displacement", "force")}
    return out | {"truth": tank.truth(), "theta0": float(sim["theta"][0][keep][0]),
                  "drive_hz": f}


def transport(tank: Tank, *, rate: float = 500.0, distance: float = 0.4, duration: float = 0.8,
              start: float = 1.0, decay: float = 12.0, lag: float = 0.020,
              jitter: float = 1e-3, seed: int = 0) -> dict:
    """A transport move (``distance`` m in ``duration`` s from ``start`` s, jerk-limited)
    followed by ``decay`` s of free slosh, as a robot-arm rig records it: the force through
    a six-axis sensor (60 Hz internal low-pass, quantised, white + 1/f noise, lines) ``lag``
    s behind the motion, the motion from encoders with a servo's lag and ripple, and
    receive-time ``stamps`` that jitter by +/- ``jitter`` s (the values are taken on the
    uniform ``time``)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round((start + duration + decay) * rate)) + 1) / rate
    move = rig.TransportMove(distance, duration, start)
    true = rig.ServoFollow(move, lag=0.012, ripple=2e-5, ripple_frequency=18.0)
    rec = _record(t, true, tank, rng, lag=lag)
    stamps = rig.receive_times(t, jitter=jitter, rng=rng)
    return rec | {"stamps": stamps, "lag": lag + rig.sensor_group_delay(60.0)}


def integrated_displacement(t: Array, acceleration: Array, *, rng: np.random.Generator,
                            bias: float = 0.02, noise: float = 0.02) -> Array:
    """The displacement a lab gets by integrating an accelerometer twice (trapezoid rule,
    from rest at ``t[0]``): the true ``acceleration`` [m/s^2] plus a ``bias`` [m/s^2] and
    white ``noise`` [m/s^2 RMS]. It drifts: ``bias t^2 / 2`` plus a random walk."""
    a = np.asarray(acceleration, float) + bias + rng.normal(0.0, noise, np.size(t))
    v = cumulative_trapezoid(a, t, initial=0.0)
    return cumulative_trapezoid(v, t, initial=0.0)
