"""Measurement models screened by their score: a force transducer that is not zeroed and
drifts (offset + linear drift), and rig friction the transducer sees (viscous + Coulomb, in
phase with the carriage velocity; only with a measured carriage motion)."""

from __future__ import annotations

from collections.abc import Sequence

from ...fitting.measurement import RigFriction as RigFrictionModel
from ...fitting.measurement import SensorOffset as SensorOffsetModel
from ...fitting.result import FitResult
from ..evidence import Evidence
from .base import Context, Family, Proposal, Score, Term, screened_proposal

__all__ = ["SensorOffset", "RigFriction"]


class _MeasurementFamily(Family):
    model: type
    parameters: tuple[str, ...]
    signs: dict[str, int] = {}

    def terms(self, ctx: Context) -> tuple[Term, ...]:
        if any(isinstance(m, self.model) for m in ctx.measurement):
            return ()
        return (Term(self.cause, self.cause, (), (self.model(),), self.parameters,
                     dict(self.signs)),)

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        return [screened_proposal(self, sc, ctx) for sc in scores]


class SensorOffset(_MeasurementFamily):
    """A force transducer that is not zeroed and drifts: an offset and a linear drift of the
    measured force."""

    cause, model, parameters = ("sensor_offset", SensorOffsetModel,
                                ("rig.force_offset", "rig.force_drift"))

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        return (f"{statistic} -> the force transducer is not zeroed and drifts: offset "
                f"{r.value('rig.force_offset'):.3g} N, drift {r.value('rig.force_drift'):.3g} N/s")


class RigFriction(_MeasurementFamily):
    """Friction of the carriage seen by the transducer: a viscous and a Coulomb force in
    phase with the carriage velocity (with a measured carriage motion only)."""

    cause, model = "rig_friction", RigFrictionModel
    parameters = ("rig.friction_viscous", "rig.friction_coulomb")
    signs = dict.fromkeys(parameters, 1)

    def applies(self, ctx: Context) -> bool:
        return super().applies(ctx) and ctx.measured_excitation

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        return (f"{statistic} -> a force in phase with the carriage velocity: rig friction seen "
                f"by the transducer (viscous {r.value('rig.friction_viscous'):.3g} N s/m, Coulomb "
                f"{r.value('rig.friction_coulomb'):.3g} N)")
