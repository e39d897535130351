"""Screening of candidate extensions without fitting them: the score test.

Every family's screened terms (hinge elements, measurement models, hinge-torque library
terms: :meth:`~estimate.diagnosis.families.base.Family.terms`) are added at once, at their
null values, to the current fitted model. One linearisation of that super-model at the
current fit (:func:`estimate.fitting.linearise.linearise`: states through the dynamics, the
carriage motion re-optimised) gives, for every term, the objective reduction one
Gauss-Newton step would bring (the score or Lagrange multiplier statistic, chi-square with
as many degrees of freedom as new parameters when the term explains nothing) and the
parameter values it points to. The same linearisation serves the families that scan (a
slosh mode's frequency, a sensor delay's profile): with the terms at their null values it
is the current model's.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence

from analogs import HingeTorqueTerms, Model

from ..fitting.linearise import Linearisation, linearise
from ..fitting.problem import FitProblem
from ..fitting.result import FitResult
from .families.base import Score, Term

__all__ = ["screen", "super_model"]


def super_model(model: Model, terms: Sequence[Term]) -> Model:
    """``model`` with every term's components; the library terms merged into one
    :class:`analogs.HingeTorqueTerms` per host (one attachment per host)."""
    merged: dict[str, list[str]] = {}
    out = model
    for term in terms:
        for c in term.components:
            if isinstance(c, HingeTorqueTerms):
                merged.setdefault(c.name, []).extend(c.terms)
            else:
                out = out + c
    for host, names in merged.items():
        out = out + HingeTorqueTerms(host, terms=tuple(names))
    return out


def screen(current: FitResult, terms: Sequence[Term], *,
           build: Callable[..., FitProblem]) -> tuple[Linearisation, tuple[str, ...], list[Score]]:
    """Score every term at the current fit (one linearisation of the super-model).

    ``build(model, measurement, initial)`` makes the fit problem of the diagnosed cases
    (the same weights as ``current``). Returns the linearisation, the current model's
    parameter names in it, and the scores (best first)."""
    model = super_model(current.problem.model, terms)
    measurement = tuple(current.problem.measurement) + tuple(
        m for t in terms for m in t.measurement)
    start = {n: v for n, v in zip(current.names, current.values)}
    lin = linearise(build(model, measurement, start), warm_start=current)
    base = tuple(n for n in current.names if n in lin.names)
    s2 = max(current.residual_variance, 1e-300)
    out = []
    for t in terms:
        reduction, values = lin.score(base + t.parameters)
        wrong = _unphysical(t, values)
        held: tuple[str, ...] = ()
        if wrong:
            reduction, values, held = _physical_step(lin, base, t, reduction, values)
        why = (f"the step points to {', '.join(f'`{n}` = {values[n]:.3g}' for n in wrong)}, "
               "which is not physical") if wrong and not held else None
        out.append(Score(t, reduction / s2, len(t.parameters), values, why, held))
    return lin, base, sorted(out, key=lambda sc: -sc.statistic)


def _unphysical(term: Term, values: Mapping[str, float], held: tuple[str, ...] = ()) -> list[str]:
    """The term's parameters of a physical sign (but those ``held``) that ``values`` gives
    the other sign (or 0)."""
    return [n for n, sign in term.signs.items() if n not in held and sign * values[n] <= 0]


def _physical_step(lin: Linearisation, base: tuple[str, ...], term: Term, reduction: float,
                   values: dict[str, float]) -> tuple[float, dict[str, float], tuple[str, ...]]:
    """The best Gauss-Newton step with the term's signed parameters of their physical sign
    (the score's quadratic model maximised over the sign constraints): on every face
    where some of them stay at their null values, the step in the others; the feasible one
    that reduces the objective most. ``(reduction, values, held)``; ``held`` empty (and the
    unconstrained step returned) when no face with a free new parameter is feasible.

    Two parameters that the record barely tells apart (a viscous and a Coulomb rig
    friction under a small carriage velocity) can make the free step put one of them at
    the unphysical sign while the other, alone, explains most of the effect."""
    signed = [n for n in term.parameters if term.signs.get(n, 0)]
    best: tuple[float, dict[str, float], tuple[str, ...]] | None = None
    for k in range(1, len(signed) + 1):
        for held in itertools.combinations(signed, k):
            free = tuple(n for n in term.parameters if n not in held)
            if not free:
                continue
            r, v = lin.score(base + free)
            v = {**v, **{n: float(lin.values[lin.names.index(n)]) for n in held}}
            if not _unphysical(term, v, held) and (best is None or r > best[0]):
                best = (r, v, held)
    return best if best is not None else (reduction, values, ())
