"""Measurement models: what stands between the analog's force and the recorded one.

A measurement model either adds a term to the simulated force (``term``, with its own
estimated parameters) or transforms the recorded data (``measured``). They are candidates
of the diagnosis as much as components are.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.interpolate import CubicSpline

from analogs import Param

__all__ = ["ChannelOffsets", "MeasurementModel", "RigFriction", "SensorDelay", "SensorOffset",
           "StreamLag", "LAG_BOUND"]

#: Largest stream lag estimated [s] either way (the shift's Taylor series is exact within a
#: spline piece and loses accuracy beyond a few pieces: at 0.1 s and 3 Hz, 1e-4 of the motion).
LAG_BOUND = 0.1


class MeasurementModel:
    """Base class: no term, data unchanged."""

    #: Parameters by full dotted name.
    parameters: Mapping[str, Param] = {}
    #: The measured channels the term adds to, in its columns' order; ``None``: the one
    #: channel of a lateral case.
    channels: tuple[str, ...] | None = None
    #: Whether the parameters are estimated separately for every case (a property of each
    #: record, such as a transducer's zero) rather than shared.
    per_case: bool = False

    def term(self, u: ca.DM, inputs: tuple[str, ...], p: Mapping[str, ca.MX],
             t: np.ndarray) -> ca.MX | None:
        """Force (N) added to the simulated force at the sample times ``t`` (s), given the
        values ``u`` there of the rig's ``inputs`` (names) and the parameters ``p`` (CasADi
        expressions by name), or ``None``; with :attr:`channels`, a ``samples x channels``
        matrix added to those channels."""
        return None

    def measured(self, t: np.ndarray, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Recorded force as the model should see it, and sample weights (0 = unusable)."""
        return force, np.ones_like(force)


@dataclass(frozen=True)
class RigFriction(MeasurementModel):
    """Carriage friction the transducer sees: ``c_v xd + F_c tanh(xd / v_smooth)``.

    Parameters ``rig.friction_viscous`` (N s/m) and ``rig.friction_coulomb`` (N). Needs the
    carriage velocity as a model input (measured excitation).
    """

    v_smooth: float = 1e-3  # m/s, smooths the sign of the Coulomb term

    parameters = {
        "rig.friction_viscous": Param("N s/m", 0.0, 0.0, description="viscous carriage friction"),
        "rig.friction_coulomb": Param("N", 0.0, 0.0, description="Coulomb carriage friction"),
    }

    def term(self, u, inputs, p, t):
        if "rig.x_dot" not in inputs:
            raise ValueError("RigFriction needs the carriage velocity input `rig.x_dot` "
                             "(a measured-displacement case)")
        xd = u[inputs.index("rig.x_dot"), :].T
        return p["rig.friction_viscous"] * xd + p["rig.friction_coulomb"] * ca.tanh(xd / self.v_smooth)


@dataclass(frozen=True)
class SensorOffset(MeasurementModel):
    """A transducer that is not zeroed and drifts: ``F_rec = F + offset + drift (t - t0)``.

    Parameters ``rig.force_offset`` (N) and ``rig.force_drift`` (N/s)."""

    parameters = {
        "rig.force_offset": Param("N", 0.0, description="force transducer offset"),
        "rig.force_drift": Param("N/s", 0.0, description="force transducer drift rate"),
    }

    def term(self, u, inputs, p, t):
        t = np.asarray(t, float)
        return p["rig.force_offset"] + p["rig.force_drift"] * ca.DM(t - t[0])


_CHANNEL_UNITS = {"force": "N", "torque": "N m"}


@dataclass(frozen=True)
class ChannelOffsets(MeasurementModel):
    """A multi-axis transducer whose every channel has its own zero error and drifts
    linearly over the record: ``y_rec,c(t) = y_c(t) + offset_c + drift_c (t - t0)``, with
    ``t0`` the record's first sample.

    Parameters ``rig.<channel>_offset`` (N or N m) and ``rig.<channel>_drift`` (N/s or
    N m/s) for every channel in ``channels``, estimated for each case separately (a zero and
    a drift belong to one record). ``channels=None`` stands for every channel the cases
    measure (:meth:`estimate.fitting.FitProblem.build` fills it in); ``drift=False``
    estimates the offsets only.

    Examples
    --------
    >>> prob = FitProblem.build(case, model, measurement=(ChannelOffsets(),))  # doctest: +SKIP
    """

    channels: tuple[str, ...] | None = None
    drift: bool = True

    per_case = True

    @property
    def parameters(self) -> dict[str, Param]:  # type: ignore[override]
        out = {}
        for c in self.channels or ():
            unit = _CHANNEL_UNITS[c.split("_")[0]]
            out[f"rig.{c}_offset"] = Param(unit, 0.0, description=f"{c} transducer offset")
            if self.drift:
                out[f"rig.{c}_drift"] = Param(f"{unit}/s", 0.0,
                                              description=f"{c} transducer drift rate")
        return out

    def term(self, u, inputs, p, t):
        t = np.asarray(t, float)
        dt = ca.DM(t - t[0])
        cols = [p[f"rig.{c}_offset"] + (p[f"rig.{c}_drift"] * dt if self.drift else 0 * dt)
                for c in self.channels or ()]
        return ca.horzcat(*cols)


@dataclass(frozen=True)
class SensorDelay(MeasurementModel):
    """The transducer records the force ``delay`` seconds late: ``F_rec(t) = F(t - delay)``.

    The recorded force is advanced by ``delay`` (cubic spline); the last ``delay`` seconds
    have no counterpart and get weight 0. The delay itself is estimated by profiling the
    cost over ``delay`` (:func:`estimate.diagnosis.search.estimate_delay`).
    """

    delay: float = 0.0

    def measured(self, t, force):
        if self.delay == 0.0:
            return force, np.ones_like(force)
        shifted = CubicSpline(t, force)(np.clip(t + self.delay, t[0], t[-1]))
        weights = (t + self.delay <= t[-1]).astype(float)
        return shifted, weights


@dataclass(frozen=True)
class StreamLag(MeasurementModel):
    """The force and the motion come from two acquisition streams, the force ``rig.lag``
    seconds behind (a sensor's buffer and filter, another clock): the force recorded at
    ``t`` belongs to the motion recorded at ``t - lag``.

    It acts on an estimated carriage motion (:mod:`estimate.fitting.carriage`): the spline
    is the motion in the force stream's time, and the recorded displacement is compared
    with it ``lag`` later, ``x_rec(t) = s(t + lag)``, written as the spline's Taylor series
    to the 5th derivative (a quintic spline's exact within a piece). Parameter
    ``rig.lag`` [s], estimated with the others (positive: the force is late).
    """

    parameters = {
        "rig.lag": Param("s", 0.0, -LAG_BOUND, LAG_BOUND,
                         description="lag of the force stream behind the motion stream"),
    }
    #: Derivatives of the Taylor series of the shift.
    order: int = 5

    per_case = True  # a lag belongs to one record's acquisition
