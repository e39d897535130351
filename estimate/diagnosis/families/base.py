"""What a diagnosis family is: one object carrying its cause name, what it adds (components
or measurement models), how it is screened or scanned, its start from the evidence, its
plausibility rule and its description. The registry (:mod:`estimate.diagnosis.families`)
derives the cause list, the screening and the proposals from these objects."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

from analogs import Component, Model

from ...fitting.measurement import MeasurementModel
from ...fitting.result import FitResult
from ..evidence import SIGNIFICANT_T, Evidence, segment_damping
from ..scoring import distinct

if TYPE_CHECKING:
    from ...fitting.linearise import Linearisation
    from ..fitter import Fitter

__all__ = ["Family", "Term", "Score", "Proposal", "Context", "screened_proposal",
           "frequency", "free_name", "trend_text"]

#: Smallest start value of a positive parameter, relative to the score step's value.
START_FLOOR = 0.2


@dataclass(frozen=True)
class Term:
    """A screened addition with linear-in-effect parameters, at their null values in the
    screening's super-model: its cause, label, the components and measurement models it
    adds, its new parameters, and which must be positive to be physical (``+1``)."""

    cause: str
    label: str
    components: tuple[Component, ...]
    measurement: tuple[MeasurementModel, ...]
    parameters: tuple[str, ...]
    signs: Mapping[str, int] = field(default_factory=dict)


@dataclass(frozen=True)
class Score:
    """A screened term: the objective reduction one Gauss-Newton step predicts over the
    residual variance (``statistic``), its degrees of freedom, the parameter values the
    step points to, and why they are not physical (``None`` when they are). When the
    free step points to an unphysical sign, the statistic and values are those of the best
    step of the physical signs, with the parameters ``held`` at their null values
    (:func:`~estimate.diagnosis.screening.screen`)."""

    term: Term
    statistic: float
    dof: int
    values: Mapping[str, float]
    unphysical: str | None
    held: tuple[str, ...] = ()

    def text(self) -> str:
        held = (f", with {', '.join(f'`{n}`' for n in self.held)} at 0: the free step "
                "gives it the unphysical sign" if self.held else "")
        return f"score {self.statistic:.0f} (chi-square, {self.dof} dof{held})"


def _no_objection(result: FitResult) -> str | None:
    return None


@dataclass(frozen=True)
class Proposal:
    """A candidate fit: the extended model and measurement models, start values and bounds
    over the current estimates, parameters it holds (and every later fit holds once it is
    accepted), what it adds, and the score that ranks it (the objective
    reduction its screening or scan predicts over the residual variance; NaN: none).

    ``cold_start``: start values of the new parameters for a fit from the prediction when
    the current estimates are a poor start; ``retry``: other start values, over the current
    estimates, for a second fit when the first does not converge or stays far from the
    noise; ``fit(fitter, start, current)``: a fitting strategy of its own (the sensor
    delay's profile-and-refit), else the default warm/cold start; ``extra_parameters``:
    estimated quantities the model does not list (a profiled delay), counted by the BIC.
    ``plausible(result)`` returns ``None`` or why the fit is not physical;
    ``describe(result)`` the evidence in words. ``first``: fitted before the scored
    candidates (the evidence that proposes it is its own); an unscored candidate that is
    not ``first`` comes after them."""

    cause: str
    added: tuple[str, ...]
    model: Model
    measurement: tuple[MeasurementModel, ...]
    initial: Mapping[str, float]
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    hold: Mapping[str, float] = field(default_factory=dict)
    score: float = math.nan
    first: bool = False
    cold_start: Mapping[str, float] | None = None
    retry: Mapping[str, float] | None = None
    fit: Callable | None = field(default=None, repr=False)
    extra_parameters: int = 0
    plausible: Callable[[FitResult], str | None] = field(default=_no_objection, repr=False)
    describe: Callable[[FitResult], str] = field(default=lambda r: "", repr=False)


@dataclass
class Context:
    """What a family reads to screen and propose itself in one round: the current fit and
    its evidence, the tank's prediction (of the current model and its next mode), gravity
    (m/s^2), the fitter, the kind of record, and the round's linearisation of the
    screening's super-model (set by the round before the proposals are asked for)."""

    current: FitResult
    evidence: Evidence
    predicted: Mapping[str, float]
    gravity: float
    fitter: Fitter
    lateral: bool
    measured_excitation: bool
    segments: int = 4
    linearisation: Linearisation | None = None
    base_names: tuple[str, ...] = ()
    memo: dict = field(default_factory=dict)

    @property
    def model(self) -> Model:
        return self.current.problem.model

    @property
    def measurement(self) -> tuple[MeasurementModel, ...]:
        return tuple(self.current.problem.measurement)

    @property
    def single_channel(self) -> bool:
        return all(len(e.channels) == 1 for e in self.current.problem.experiments)

    @property
    def six_axis(self) -> bool:
        """Whether the records are six-axis records of a tank moved in 3-D
        (``[rig.motion]``: fitted on :class:`~analogs.MotionRig`)."""
        return all(getattr(e.case, "motion", None) is not None
                   for e in self.current.problem.experiments)

    @property
    def inertia(self) -> float | None:
        """The predicted first mode's hinge inertia m L^2 (kg m^2), or ``None``."""
        i = self.predicted.get("p1.mass", math.nan) * self.predicted.get("p1.length", math.nan) ** 2
        return i if math.isfinite(i) and i > 0 else None

    def once(self, key: str, make: Callable[[], object]) -> object:
        """``make()``, made once a round (a scan two families read)."""
        if key not in self.memo:
            self.memo[key] = make()
        return self.memo[key]

    def with_trends(self) -> Evidence:
        """The evidence with the amplitude trends of segment refits (made once a round)."""
        if not self.evidence.segments:
            segs = segment_damping(self.current, n_segments=self.segments)
            self.fitter.extra += len(segs)
            self.evidence = replace(self.evidence, segments=segs)
        return self.evidence


class Family:
    """A diagnosis family (subclass it, one module each). Class attributes: ``cause`` (the
    name a finding carries), ``rig`` (``"lateral"``: single-channel lateral records;
    ``"spinning"``: six-channel spinning-rig records; ``"motion"``: six-axis records of a
    tank moved in 3-D), ``library`` (a term of the
    hinge-torque library, fitted only when no named family explains the residual). A
    family's docstring is its :attr:`description`: the physical effect and what it adds."""

    cause: ClassVar[str] = ""
    rig: ClassVar[str] = "lateral"
    library: ClassVar[bool] = False
    description: ClassVar[str] = ""

    def __init_subclass__(cls, **kw) -> None:
        super().__init_subclass__(**kw)
        cls.description = " ".join((cls.__doc__ or "").split())

    def applies(self, ctx: Context) -> bool:
        """Whether the family can describe this kind of record: single-channel lateral
        records of the lateral carriage, the spinning rig's, or six-axis records of a tank
        moved in 3-D (``"motion"``: a :class:`~analogs.MotionRig` case, any channels; the
        lateral families' scans and screening drive the model along x alone)."""
        from analogs import SpinningRig

        if self.rig == "lateral":
            return ctx.lateral and ctx.single_channel and not ctx.six_axis
        if self.rig == "spinning":
            return isinstance(ctx.model.rig, SpinningRig)
        return ctx.six_axis

    def terms(self, ctx: Context) -> tuple[Term, ...]:
        """The additions the round's screening scores at their null values (none: the
        family is scanned or proposed another way)."""
        return ()

    def propose(self, ctx: Context, scores: Sequence[Score]) -> list[Proposal]:
        """The fits to try this round, given the scores of :meth:`terms`."""
        return []

    def finish(self, fitter: Fitter, final: FitResult) -> tuple[FitResult, str | None]:
        """Refine the diagnosis's final fit (of the whole record) when the family's element
        is in it; returns the fit and a note for the report (``None``: unchanged)."""
        return final, None

    def why_not(self, ctx: Context) -> str | None:
        """Why the family proposes nothing this round, when the report should say so."""
        return None

    def describe(self, result: FitResult, names: tuple[str, ...], evidence: Evidence,
                 statistic: str) -> str:
        """The finding of a screened term in words (``statistic``: its score in words)."""
        return statistic


def frequency(res: FitResult, name: str) -> float:
    """The fitted frequency (Hz) of component ``name`` (NaN when it has none)."""
    return res.derived.get(f"{name}.frequency_hz", (math.nan, 0.0))[0]


def free_name(model: Model, prefix: str) -> str:
    """The first of ``<prefix>1``, ``<prefix>2``, ... that no component of ``model`` uses."""
    used = {c.name for c in model.components}
    return next(f"{prefix}{k}" for k in range(1, 99) if f"{prefix}{k}" not in used)


def trend_text(evidence: Evidence, quantity: str) -> str:
    """The amplitude trend of ``"damping"`` or ``"frequency"`` in words, when it is one (at
    least :data:`~estimate.diagnosis.evidence.SIGNIFICANT_T` standard errors), with a trailing
    ``"; "``."""
    trend = evidence.damping_trend if quantity == "damping" else evidence.frequency_trend
    return f"{trend.text()}; " if trend is not None and abs(trend.t) >= SIGNIFICANT_T else ""


def screened_proposal(family: Family, score: Score, ctx: Context,
                      cold_start: Mapping[str, float] | None = None) -> Proposal:
    """The fit of a screened term, started at the current estimates and at the values the
    score step points to; plausible when its new parameters are of their physical signs
    and one at least is distinct from zero (3 standard errors: a rig friction whose
    viscous part a slow carriage does not resolve is still a Coulomb rig friction)."""
    term = score.term
    model = ctx.model
    for c in term.components:
        model = model + c
    initial = {}
    for n in term.parameters:
        v = score.values[n]
        if term.signs.get(n, 0) > 0:
            v = max(v, START_FLOOR * abs(v), 1e-12)
        initial[n] = v

    def plausible(r: FitResult) -> str | None:
        for n in term.parameters:
            if term.signs.get(n, 0) * r.value(n) < 0:
                return f"`{n}` = {r.value(n):.3g} has the unphysical sign"
        if not any(distinct(r, n) for n in term.parameters):
            return " and ".join(f"`{n}` = {r.value(n):.3g}" for n in term.parameters) + (
                " is not distinguishable from zero" if len(term.parameters) == 1
                else " are not distinguishable from zero")
        return None

    evidence = ctx.evidence
    return Proposal(term.cause, (term.label,), model, ctx.measurement + term.measurement,
                    initial, score=score.statistic, cold_start=cold_start, plausible=plausible,
                    describe=lambda r: family.describe(r, term.parameters, evidence,
                                                       score.text()))
