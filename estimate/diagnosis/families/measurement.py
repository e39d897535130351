"""Measurement models: a force transducer that is not zeroed and drifts (offset + linear
drift) and rig friction the transducer sees (viscous + Coulomb, in phase with the carriage
velocity; only with a measured carriage motion), screened by their score on lateral
records; a six-axis transducer whose channels are not zeroed and drift, from the share of
the residual a line per channel takes up."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...fitting.measurement import ChannelOffsets as ChannelOffsetsModel
from ...fitting.measurement import RigFriction as RigFrictionModel
from ...fitting.measurement import SensorOffset as SensorOffsetModel
from ...fitting.result import FitResult
from ..evidence import Evidence
from .base import Context, Family, Proposal, Score, Term, screened_proposal

__all__ = ["SensorOffset", "RigFriction", "ChannelOffsets", "line_share", "MIN_LINE_SHARE"]

#: A six-axis record's channels are proposed zero and drift errors when a line per channel
#: takes up at least this share of the scaled residual power (white noise: about
#: 2/samples).
MIN_LINE_SHARE = 0.02


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


def line_share(result: FitResult, case: int = 0) -> float:
    """The share of the scaled residual power of ``case`` (fitted samples) that a line per
    channel (offset + drift over time) takes up, 0..1."""
    t = np.asarray(result.problem.experiments[case].case.time, float)
    w = result.weights[case] if result.weights else np.ones(t.size)
    keep = w > 0
    r = result.scaled_residuals(case).reshape(t.size, -1)[keep]
    basis = np.column_stack([np.ones(keep.sum()), t[keep] - t[0]])
    coef, *_ = np.linalg.lstsq(basis, r, rcond=None)
    total = float(np.sum(r**2))
    return float(np.sum((basis @ coef) ** 2)) / total if total > 0 else 0.0


class ChannelOffsets(Family):
    """A six-axis transducer whose channels are not zeroed and drift: an offset and a linear
    drift on every channel (:class:`~estimate.fitting.ChannelOffsets`), proposed when a line
    per channel takes up a share of the residual."""

    cause, rig = "channel_offsets", "motion"

    def applies(self, ctx: Context) -> bool:
        return super().applies(ctx) and not any(isinstance(m, ChannelOffsetsModel)
                                                for m in ctx.measurement)

    def _share(self, ctx: Context) -> float:
        return ctx.once("line share", lambda: line_share(ctx.current))  # type: ignore[return-value]

    def why_not(self, ctx: Context) -> str | None:
        share = self._share(ctx)
        if share >= MIN_LINE_SHARE:
            return None
        return (f"channel offsets not tried: a line per channel takes up {100 * share:.1f} % "
                f"of the residual (below {100 * MIN_LINE_SHARE:g} %)")

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        share = self._share(ctx)
        if share < MIN_LINE_SHARE:
            return []

        def describe(r: FitResult) -> str:
            names = [n for n in r.names if "rig." in n and n.endswith("_offset")]
            top = max(names, key=lambda n: abs(r.value(n)) / (r.stderr[r.names.index(n)] or 1))
            return (f"a line per channel takes up {100 * share:.0f} % of the residual -> the "
                    f"transducer's channels are not zeroed and drift; offset and drift "
                    f"estimated on each (largest: {top} {r.value(top):.3g})")

        return [Proposal(self.cause, (self.cause,), ctx.model,
                         ctx.measurement + (ChannelOffsetsModel(),), {}, describe=describe)]
