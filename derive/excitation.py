"""Prescribed excitations: the rig input signals as functions of time.

Every input signal comes with its first and second time derivatives, in the order the
derived model lists them (``rig.x``, ``rig.x_dot``, ``rig.x_ddot``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np

from analogs.errors import InputError

__all__ = ["Excitation", "NoExcitation", "Sine", "Sampled"]


class Excitation:
    """Base class: ``values(t)`` for numeric grids, ``symbolic(t)`` for CasADi."""

    #: Number of input values supplied (3 per signal: value and two derivatives).
    size: int = 3
    #: True when :meth:`symbolic` accepts SX as well as MX (closed-form in time), so the
    #: excitation can be evaluated inside generated code instead of passed as data.
    analytic: bool = False

    def values(self, t: np.ndarray) -> np.ndarray:
        """Input values at times ``t`` (s), shape ``(size, len(t))``."""
        raise NotImplementedError

    def symbolic(self, t: ca.MX) -> ca.MX:
        """Input values as a CasADi expression of the time ``t`` (s; a column of
        :attr:`size`)."""
        raise NotImplementedError


@dataclass(frozen=True)
class NoExcitation(Excitation):
    """A tank at rest (all signals zero), or a rig whose motion needs no input."""

    size: int = 3
    analytic: bool = True

    def values(self, t: np.ndarray) -> np.ndarray:
        return np.zeros((self.size, np.size(t)))

    def symbolic(self, t):
        return ca.DM.zeros(self.size, 1) * t if self.size else type(t)(0, 1)


@dataclass(frozen=True)
class Sine(Excitation):
    """``x = amplitude sin(2 pi frequency t + phase)``: ``amplitude`` (m), ``frequency``
    (Hz), ``phase`` (rad, default 0)."""

    amplitude: float
    frequency: float
    phase: float = 0.0
    analytic: bool = field(default=True, init=False, repr=False)

    def _parts(self, t, lib):
        w = 2 * math.pi * self.frequency
        s, c = lib.sin(w * t + self.phase), lib.cos(w * t + self.phase)
        a = self.amplitude
        return a * s, a * w * c, -a * w * w * s

    def values(self, t: np.ndarray) -> np.ndarray:
        return np.vstack(self._parts(np.asarray(t, float), np))

    def symbolic(self, t: ca.MX) -> ca.MX:
        return ca.vertcat(*self._parts(t, ca))


@dataclass(frozen=True)
class Sampled(Excitation):
    """Signals given on a uniform or non-uniform time grid, interpolated by cubic B-splines.

    Parameters
    ----------
    time : array, shape (n,)
        Sample times (s), strictly increasing.
    signals : array, shape (3, n) or (3k, n)
        Value, first and second derivative of each signal on ``time`` (SI units), e.g.
        displacement (m), velocity (m/s) and acceleration (m/s^2) from
        :func:`estimate.signals.displacement_derivatives`.
    """

    time: np.ndarray
    signals: np.ndarray = field(repr=False)

    def __post_init__(self) -> None:
        t = np.asarray(self.time, float)
        s = np.atleast_2d(np.asarray(self.signals, float))
        if t.ndim != 1 or t.size < 4 or np.any(np.diff(t) <= 0):
            raise InputError("Sampled.time must be a strictly increasing 1-D array of >= 4 samples")
        if s.shape[1] != t.size or s.shape[0] % 3:
            raise InputError(
                f"Sampled.signals must have shape (3k, {t.size}) (value, rate, acceleration "
                f"per signal), got {s.shape}"
            )
        if not np.all(np.isfinite(s)):
            raise InputError("Sampled.signals contain NaN or inf")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "signals", s)
        object.__setattr__(self, "size", s.shape[0])

    @cached_property
    def _interpolant(self) -> ca.Function:
        return ca.interpolant("excitation", "bspline", [self.time], self.signals.T.ravel(order="C"))

    def values(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, float)
        lo, hi = self.time[0], self.time[-1]
        if t.size and (t.min() < lo - 1e-9 or t.max() > hi + 1e-9):
            raise InputError(
                f"excitation samples cover [{lo}, {hi}] s; requested [{t.min()}, {t.max()}] s"
            )
        return np.asarray(self._interpolant.map(t.size)(t.reshape(1, -1)))

    def symbolic(self, t: ca.MX) -> ca.MX:
        return self._interpolant(t)
