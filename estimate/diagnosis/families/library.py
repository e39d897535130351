"""The hinge-torque library: small torque terms of the first mode's angle and rate that no
named family covers (an asymmetric spring, cubic damping, ...), screened by their score and
fitted only when no named family explains the residual (or one term's score dwarfs every
named family's)."""

from __future__ import annotations

from collections.abc import Sequence

from analogs import HingeTorqueTerms
from analogs.hinge_nonlinear import TORQUE_TERMS

from ...fitting.result import FitResult
from ..evidence import Evidence
from .base import Context, Family, Proposal, Score, Term, screened_proposal
from .hinge import HOST

__all__ = ["HingeTorque", "LIBRARY_TERMS"]

#: Library terms screened: those no family covers (quadratic damping, dry friction and the
#: cubic spring are families of their own).
LIBRARY_TERMS = ("angle_squared", "rate_cubed", "angle2_rate", "abs_angle_rate", "angle_rate2")
#: How each term reads in a finding.
_SHAPES = {"angle_squared": "theta^2", "rate_cubed": "thetadot^3",
           "angle2_rate": "theta^2 thetadot", "abs_angle_rate": "|theta| thetadot",
           "angle_rate2": "theta thetadot^2"}


class HingeTorque(Family):
    """A hinge torque no named element describes: one term of a small library of powers and
    products of the first mode's angle and rate."""

    cause, library = "hinge_torque", True

    def terms(self, ctx: Context) -> tuple[Term, ...]:
        present = {t for c in ctx.model.components if isinstance(c, HingeTorqueTerms)
                   for t in c.terms}
        return tuple(Term(self.cause, f"{HOST}:torque_{t}", (HingeTorqueTerms(HOST, terms=(t,)),),
                          (), (f"{HOST}.torque_{t}",))
                     for t in LIBRARY_TERMS if t not in present)

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        return [screened_proposal(self, sc, ctx) for sc in scores]

    def describe(self, r: FitResult, names, evidence: Evidence, statistic: str) -> str:
        (name,) = names
        term = name.split(".torque_", 1)[1]
        unit = r.problem.estimated[r.names.index(name)].unit
        return (f"{statistic}; no named element explains the residual, but a hinge torque "
                f"~ {_SHAPES.get(term, term)} ({TORQUE_TERMS[term][2]}) does: coefficient "
                f"{r.value(name):.3g} {unit} on {HOST}")
