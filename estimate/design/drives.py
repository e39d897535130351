"""Drives a rig can run, as design candidates: their motion, their peaks and their fit to
the rig's limits (``[rig.limits]``, :class:`estimate.data.case.Limits`).

A lateral drive is a carriage displacement ``x(t) = scale e(t) A(t) sin(phi(t))`` (m): the
rig at rest for ``lead`` seconds, the drive faded in over ``ramp`` seconds and out over the
last ``ramp`` seconds (a C2 smootherstep envelope ``e``: the carriage never jerks, and the
record starts and ends at rest), with a family-specific amplitude ``A(t)`` and phase
``phi(t)``. Each family (:data:`LATERAL_FAMILIES`) names its design variables and their
bounds; the amplitude levels are the largest the limits allow at each frequency
(:func:`limit_amplitude`), and ``scale`` (<= 1) takes off what the envelope's overshoot or a
swing limit asks for. Velocity and acceleration are CasADi derivatives of the displacement
expression, so every family is exact to the last digit without hand-written derivatives.

A spinning-rig drive (:class:`SpinDrive`) spins the table up, then ramps the cone angle in
and holds the spin rate, coning frequency and cone angle: the ``[rig.spin]`` schedule of a
test.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import ClassVar

import casadi as ca
import numpy as np

from analogs.errors import InputError
from derive.schedule import smootherstep

from ..data.case import Limits

__all__ = ["LateralDrive", "SteadySine", "SteppedSine", "AmplitudeSteps", "LinearChirp",
           "SpinDrive", "LATERAL_FAMILIES", "LIMIT_MARGIN", "limit_amplitude", "fit_to_limits",
           "Peaks"]

#: Seconds of rest before the drive fades in (a record that starts quiet starts at rest).
LEAD = 0.5
#: Fade-in and fade-out time [s] (at most a sixth of the record).
RAMP = 2.0
#: Duration of a frequency or amplitude change of a stepped drive [s].
TRANSITION = 1.0
#: Peaks are read on a grid this many times finer than the drive file's.
OVERSAMPLE = 10
#: Relative margin kept from each limit: peaks read on a grid twice (the search) or ten
#: times (:func:`fit_to_limits`) the rig's rate miss at most ``1 - cos(pi f / (2 rate))`` of
#: a peak, 0.5 % at a tenth of the rate.
LIMIT_MARGIN = 0.01


def _clamp01(u):
    return ca.fmin(ca.fmax(u, 0), 1)


def limit_amplitude(frequency, limits) -> float:
    """The largest displacement amplitude (m) of a steady sine at ``frequency`` (Hz) within
    the stroke (+/- stroke/2), speed and acceleration limits (a :class:`Limits`, or the
    CasADi vector ``[stroke, velocity, acceleration]``)."""
    w = 2 * math.pi * frequency
    if isinstance(limits, Limits):
        return min(limits.stroke / 2, limits.velocity / w, limits.acceleration / w**2)
    return ca.fmin(ca.fmin(limits[0] / 2, limits[1] / w), limits[2] / w**2)


def _stepped(t, freqs, amps, t0, t1):
    """``(A(t), phi(t))`` of levels ``freqs`` (Hz) and ``amps`` (m) held in equal dwells
    over ``[t0, t1]``, each change a smootherstep of :data:`TRANSITION` seconds (at most a
    third of a dwell), the phase continuous. The amplitude is ``c(t) / f(t)^2`` with ``c``
    changing as smoothly as ``f``: an acceleration limited at both levels stays limited
    through the change."""
    dwell = (t1 - t0) / len(freqs)
    ramp = ca.fmin(TRANSITION, dwell / 3)
    c = [a * f**2 for a, f in zip(amps, freqs)]
    f, cycles, ck = freqs[0] + 0 * t, freqs[0] * (t - t0), c[0] + 0 * t
    for k in range(1, len(freqs)):
        start = t0 + k * dwell - ramp / 2
        S, s, _, _ = smootherstep(_clamp01((t - start) / ramp), ca)
        df = freqs[k] - freqs[k - 1]
        f = f + df * s
        cycles = cycles + df * (ramp * S + ca.fmax(t - start - ramp, 0))
        ck = ck + (c[k] - c[k - 1]) * s
    return ck / f**2, 2 * math.pi * cycles


@dataclass(frozen=True)
class Peaks:
    """Largest displacement (m, from the centre), speed (m/s) and acceleration (m/s^2)."""

    displacement: float
    velocity: float
    acceleration: float

    def ratios(self, limits: Limits) -> dict[str, float]:
        """Each peak over its limit (stroke: over ``stroke / 2``)."""
        return {"stroke": self.displacement / (limits.stroke / 2),
                "velocity": self.velocity / limits.velocity,
                "acceleration": self.acceleration / limits.acceleration}


_FUNCTIONS: dict = {}


@dataclass(frozen=True)
class LateralDrive:
    """Base of the lateral-rig drive families: ``duration`` (s) of the record, the amplitude
    ``scale`` (<= 1) over the levels the limits allow, and the ``limits`` themselves
    (``[rig.limits]``).

    A family defines its design variables and ``_carrier``; the motion of every drive of a
    family comes from one CasADi function of time, scale, variables, limits and duration
    (compiled once when a C compiler is available)."""

    family: ClassVar[str] = ""
    #: Design variables (Hz) in order, and how the family is described.
    variables: ClassVar[tuple[str, ...]] = ()
    title: ClassVar[str] = ""

    limits: Limits = field(repr=False)
    duration: float
    scale: float = 1.0

    # -- what a family defines ---------------------------------------------------------------
    @classmethod
    def _carrier(cls, t, v, lim, t0, t1):
        """``(A(t), phi(t))`` as CasADi expressions of the time ``t``, the design variables
        ``v`` and limits ``lim`` (``[stroke, velocity, acceleration]``) over the driven
        segment ``[t0, t1]``."""
        raise NotImplementedError

    # -- common ------------------------------------------------------------------------------
    @property
    def values(self) -> dict[str, float]:
        """The design variables by name."""
        return {v: float(getattr(self, v)) for v in self.variables}

    @property
    def ramp(self) -> float:
        return min(RAMP, self.duration / 6)

    @classmethod
    def _motion_function(cls) -> ca.Function:
        """``(t, scale, v, lim, duration) -> [x; xd; xdd]`` of the family."""
        if cls.family not in _FUNCTIONS:
            t, scale, T = ca.SX.sym("t"), ca.SX.sym("scale"), ca.SX.sym("duration")
            v = ca.SX.sym("v", len(cls.variables))
            lim = ca.SX.sym("limits", 3)
            ramp = ca.fmin(RAMP, T / 6)
            _, rise, _, _ = smootherstep(_clamp01((t - LEAD) / ramp), ca)
            _, fall, _, _ = smootherstep(_clamp01((T - t) / ramp), ca)
            a, phi = cls._carrier(t, v, lim, LEAD, T)
            x = scale * rise * fall * a * ca.sin(phi)
            xd = ca.gradient(x, t)
            xdd = ca.gradient(xd, t)
            fn = ca.Function(f"drive_{cls.family}", [t, scale, v, lim, T],
                             [ca.vertcat(x, xd, xdd)])
            from derive import c_compiler, compiled

            _FUNCTIONS[cls.family] = compiled(fn) if c_compiler() else fn
        return _FUNCTIONS[cls.family]

    def motion(self, t: np.ndarray) -> np.ndarray:
        """Displacement (m), velocity (m/s) and acceleration (m/s^2) at ``t`` (s): ``(3, n)``."""
        t = np.asarray(t, float).ravel()
        fn = self._motion_function()
        key = (self.family, t.size)
        if key not in _FUNCTIONS:
            _FUNCTIONS[key] = fn.map(t.size)
        lim = [self.limits.stroke, self.limits.velocity, self.limits.acceleration]
        v = [getattr(self, name) for name in self.variables]
        return np.asarray(_FUNCTIONS[key](t.reshape(1, -1), self.scale, v, lim, self.duration))

    def peaks(self, rate: float) -> Peaks:
        """Peaks of the motion on a grid :data:`OVERSAMPLE` times finer than ``rate`` (Hz)."""
        n = int(round(self.duration * rate * OVERSAMPLE))
        m = np.abs(self.motion(np.linspace(0.0, self.duration, n + 1))).max(axis=1)
        return Peaks(*map(float, m))

    def describe(self) -> str:
        raise NotImplementedError


@dataclass(frozen=True)
class SteadySine(LateralDrive):
    """A steady sine at ``frequency`` (Hz), at the largest amplitude the limits allow."""

    family: ClassVar[str] = "sine"
    variables: ClassVar[tuple[str, ...]] = ("frequency",)
    title: ClassVar[str] = "steady sine"
    frequency: float = 1.0

    @classmethod
    def _carrier(cls, t, v, lim, t0, t1):
        return limit_amplitude(v[0], lim) + 0 * t, 2 * math.pi * v[0] * (t - t0)

    def describe(self) -> str:
        return f"steady sine at {self.frequency:.4g} Hz"


@dataclass(frozen=True)
class SteppedSine(LateralDrive):
    """A sine stepped through two frequencies, ``first`` and ``second`` (Hz), each held half
    the driven time at the
    largest amplitude the limits allow there; phase-continuous smooth changes."""

    family: ClassVar[str] = "stepped"
    variables: ClassVar[tuple[str, ...]] = ("first", "second")
    title: ClassVar[str] = "stepped sine"
    first: float = 1.0
    second: float = 2.0

    @classmethod
    def _carrier(cls, t, v, lim, t0, t1):
        f = [v[0], v[1]]
        return _stepped(t, f, [limit_amplitude(x, lim) for x in f], t0, t1)

    def describe(self) -> str:
        return f"stepped sine {self.first:.4g} Hz then {self.second:.4g} Hz"


@dataclass(frozen=True)
class AmplitudeSteps(LateralDrive):
    """A sine at ``frequency`` (Hz) in three amplitude steps, 1/3, 2/3 and all of the
    largest amplitude the limits allow: the swing, and what depends on it, in three levels."""

    family: ClassVar[str] = "steps"
    variables: ClassVar[tuple[str, ...]] = ("frequency",)
    title: ClassVar[str] = "amplitude steps"
    frequency: float = 1.0
    fractions: ClassVar[tuple[float, ...]] = (1 / 3, 2 / 3, 1.0)

    @classmethod
    def _carrier(cls, t, v, lim, t0, t1):
        a = limit_amplitude(v[0], lim)
        return _stepped(t, [v[0]] * 3, [a * k for k in cls.fractions], t0, t1)

    def describe(self) -> str:
        return f"amplitude steps (1/3, 2/3, 1) at {self.frequency:.4g} Hz"


@dataclass(frozen=True)
class LinearChirp(LateralDrive):
    """A linear chirp from ``start`` to ``end`` (Hz, up or down) over the driven segment, at
    one displacement amplitude: the largest the limits allow over the whole band."""

    family: ClassVar[str] = "chirp"
    variables: ClassVar[tuple[str, ...]] = ("start", "end")
    title: ClassVar[str] = "linear chirp"
    start: float = 1.0
    end: float = 5.0

    @classmethod
    def _carrier(cls, t, v, lim, t0, t1):
        a = ca.fmin(limit_amplitude(v[0], lim), limit_amplitude(v[1], lim))
        tau = t - t0
        rate = (v[1] - v[0]) / (t1 - t0)
        return a + 0 * t, 2 * math.pi * (v[0] * tau + 0.5 * rate * tau**2)

    def describe(self) -> str:
        rate = (self.end - self.start) / (self.duration - LEAD)
        return (f"linear chirp {self.start:.4g} -> {self.end:.4g} Hz "
                f"({rate:+.3g} Hz/s)")


#: The lateral-rig families, by name (``--families``).
LATERAL_FAMILIES: dict[str, type[LateralDrive]] = {
    cls.family: cls for cls in (SteadySine, SteppedSine, AmplitudeSteps, LinearChirp)}


def fit_to_limits(drive: LateralDrive, rate: float) -> LateralDrive:
    """``drive`` scaled to the largest amplitude whose displacement, speed and acceleration
    stay within its limits less :data:`LIMIT_MARGIN` (the motion is linear in the scale,
    so one look at the peaks of the unscaled drive suffices)."""
    unit = replace(drive, scale=1.0)
    ratios = unit.peaks(rate).ratios(drive.limits)
    worst = max(ratios.values())
    if not worst > 0:
        raise InputError(f"the {drive.describe()} does not move the carriage")
    return replace(drive, scale=(1 - LIMIT_MARGIN) / worst)


@dataclass(frozen=True)
class SpinDrive:
    """A spinning-rig test: the table spun up from rest to ``spin_rate`` (rad/s) over
    ``spin_up`` seconds, then the cone angle ramped from 0 to ``cone_angle`` (rad) over
    ``nutation_ramp`` seconds while the table axis cones at ``nutation_frequency`` (Hz),
    held to the end of the ``duration`` (s) record. The cone angle is the amplitude: it is
    the largest the ``limits`` allow, less what a swing limit asks for (``scale``)."""

    family: ClassVar[str] = "spin"
    variables: ClassVar[tuple[str, ...]] = ("spin_rate", "nutation_frequency")
    title: ClassVar[str] = "spin and coning"

    limits: Limits = field(repr=False)
    duration: float
    spin_rate: float = 1.0
    nutation_frequency: float = 0.1
    scale: float = 1.0

    @property
    def values(self) -> dict[str, float]:
        """The design variables by name (rad/s, Hz)."""
        return {v: float(getattr(self, v)) for v in self.variables}

    @property
    def cone_angle(self) -> float:
        """Cone half-angle held after the ramp (rad)."""
        return self.scale * self.limits.cone_angle

    @property
    def spin_up(self) -> float:
        """Spin-up time (s): a fifth of the record, at most 12 s."""
        return min(12.0, self.duration / 5)

    @property
    def nutation_ramp(self) -> float:
        """Cone-angle ramp (s) after the spin-up: a tenth of the record, at most 5 s."""
        return min(5.0, self.duration / 10)

    @property
    def tank_frame_frequency(self) -> float:
        """Frequency of the coning seen from the spinning table, ``|rate - 2 pi f_n| / 2 pi``
        (Hz): what excites the slosh modes."""
        return abs(self.spin_rate - 2 * math.pi * self.nutation_frequency) / (2 * math.pi)

    def describe(self) -> str:
        return (f"spin {self.spin_rate:.4g} rad/s, coning {self.nutation_frequency:+.4g} Hz at "
                f"{self.cone_angle:.3g} rad (tank-frame excitation "
                f"{self.tank_frame_frequency:.4g} Hz)")
