"""Analytic schedules of rig signals (smooth ramps) and excitations stacked from parts.

A rig that takes its motion as inputs (e.g. :class:`analogs.SpinningRig` with
``motion="input"``) is driven either by measured signals (:class:`derive.Sampled`) or by
schedules written here: a table spun up over 12 s, a cone angle ramped in over 5 s. Every
signal comes with its first and second time derivatives, in closed form, so a schedule is
evaluated exactly inside generated code (``analytic = True``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from analogs.errors import InputError

from .excitation import Excitation

__all__ = ["SmoothRamp", "Schedule", "Stacked", "smootherstep"]


def smootherstep(tau, lib=np):
    """``s(tau) = tau^3 (10 - 15 tau + 6 tau^2)`` on ``[0, 1]`` with its integral and first
    two derivatives: ``(S, s, s', s'')``. ``s`` rises from 0 to 1 with zero slope and
    curvature at both ends (C2), so a ramped rate has a continuous acceleration and a
    ramped angle a continuous angular acceleration. ``tau`` must already be clipped to
    ``[0, 1]``."""
    t2 = tau * tau
    t3 = t2 * tau
    s = t3 * (10 - 15 * tau + 6 * t2)
    integral = t2 * t2 * (2.5 - 3 * tau + t2)
    ds = 30 * t2 * (1 - tau) ** 2
    dds = 60 * tau * (1 - tau) * (1 - 2 * tau)
    return integral, s, ds, dds


def _ops(t):
    """Element-wise max/min for NumPy arrays and CasADi expressions."""
    if isinstance(t, (ca.SX, ca.MX, ca.DM)):
        return ca.fmax, ca.fmin
    return np.maximum, np.minimum


@dataclass(frozen=True)
class SmoothRamp:
    """One scheduled signal with its two time derivatives.

    ``kind="level"``: the signal rises from 0 to ``final`` between ``start`` and ``start +
    duration`` (s) along :func:`smootherstep` (e.g. a cone angle in rad).
    ``kind="rate"``: its *rate* does, so the signal is an angle that is spun up from rest to
    ``final`` rad/s (its value at ``start`` is 0 and after the ramp it grows as ``final (t -
    start - duration / 2)``).

    ``duration = 0`` gives a constant level ``final`` (or rate) from ``start = 0``; a jump
    later in the record is not a motion a rig can make and is refused.
    """

    final: float
    duration: float = 0.0
    start: float = 0.0
    kind: str = "level"

    def __post_init__(self) -> None:
        if self.kind not in ("level", "rate"):
            raise InputError(f"SmoothRamp kind must be 'level' or 'rate', got {self.kind!r}")
        for name in ("final", "duration", "start"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"SmoothRamp {name} must be finite, got {getattr(self, name)!r}")
        if self.duration < 0:
            raise InputError(f"SmoothRamp duration must be >= 0 s, got {self.duration!r}")
        if self.duration == 0 and self.start != 0:
            raise InputError(
                f"SmoothRamp: a jump at start = {self.start!r} s (duration 0) is not a rig "
                "motion; give a ramp duration > 0 s")

    def parts(self, t, lib=np):
        """``(value, first derivative, second derivative)`` at times ``t`` (s)."""
        fmax, fmin = _ops(t)
        a = self.final
        if self.duration == 0:
            zero = 0 * t
            if self.kind == "level":
                return a + zero, zero, zero
            return a * t, a + zero, zero
        T = self.duration
        tau = fmin(fmax((t - self.start) / T, 0), 1)
        S, s, ds, dds = smootherstep(tau, lib)
        if self.kind == "level":
            return a * s, a * ds / T, a * dds / T**2
        after = fmax(t - self.start - T, 0)
        return a * (T * S + after), a * s, a * ds / T


@dataclass(frozen=True)
class Schedule(Excitation):
    """An excitation of scheduled signals (:class:`SmoothRamp`), three input values each
    (value, rate, acceleration), in the order the derived model lists its inputs.

    Examples
    --------
    >>> from derive.schedule import Schedule, SmoothRamp
    >>> spin_up = Schedule((SmoothRamp(6.0, 12.0, kind="rate"),))
    >>> float(spin_up.values([20.0])[1, 0])   # rad/s after the spin-up
    6.0
    """

    signals: tuple[SmoothRamp, ...]
    analytic: bool = field(default=True, init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "signals", tuple(self.signals))
        object.__setattr__(self, "size", 3 * len(self.signals))

    def values(self, t) -> np.ndarray:
        t = np.asarray(t, float).ravel()
        if not self.signals:
            return np.zeros((0, t.size))
        return np.vstack([np.vstack(s.parts(t, np)) for s in self.signals])

    def symbolic(self, t):
        if not self.signals:
            return type(t)(0, 1)
        return ca.vertcat(*[v for s in self.signals for v in s.parts(t, ca)])


@dataclass(frozen=True)
class Stacked(Excitation):
    """Input values of several excitations one after the other (e.g. a measured spin angle
    and a scheduled cone angle); analytic when every part is."""

    parts: tuple[Excitation, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "parts", tuple(self.parts))
        object.__setattr__(self, "size", sum(p.size for p in self.parts))
        object.__setattr__(self, "analytic", all(p.analytic for p in self.parts))

    def values(self, t) -> np.ndarray:
        t = np.asarray(t, float).ravel()
        if not self.parts:
            return np.zeros((0, t.size))
        return np.vstack([np.asarray(p.values(t), float).reshape(p.size, t.size)
                          for p in self.parts])

    def symbolic(self, t):
        if not self.parts:
            return type(t)(0, 1)
        return ca.vertcat(*[p.symbolic(t) for p in self.parts])
