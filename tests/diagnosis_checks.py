"""One diagnosis family on one record, without the rest of the search: fit the baseline
(held-out blocks as the diagnosis leaves them out), screen the family's terms or let it scan,
ask it for its proposals and fit the first. The per-family tests
(``tests/estimate/diagnosis/families/``) use it on short records of the independent
reference simulators, with the effect and without."""

from __future__ import annotations

from dataclasses import dataclass

from analogs import Pendulum
from estimate.data.case import Case
from estimate.diagnosis.evidence import collect_evidence
from estimate.diagnosis.families import Context, Proposal, Score, family
from estimate.diagnosis.fitter import Fitter
from estimate.diagnosis.scoring import holdout_weights
from estimate.diagnosis.screening import screen
from estimate.diagnosis.search import MIN_SCORE, baseline_model, fit_candidate, force_cutoff
from estimate.fitting.initial import predicted_values
from estimate.fitting.result import FitResult


@dataclass
class FamilyRun:
    """The baseline fit, the family's scores and proposals on it, and (when asked for) the
    fit of its first proposal."""

    baseline: FitResult
    context: Context
    scores: list[Score]
    proposals: list[Proposal]
    fit: FitResult | None = None

    @property
    def proposed(self) -> bool:
        return bool(self.proposals)


def run_family(case: Case, cause: str, *, fit: bool = True) -> FamilyRun:
    """Screen or scan family ``cause`` on ``case`` at the baseline fit; its proposals are
    the ones the diagnosis would fit (screened terms: a score of at least ``MIN_SCORE`` and
    physical values); fit the first when ``fit``."""
    lateral = case.test.rig == "lateral"
    fitter = Fitter([case], [holdout_weights(case.time.size)],
                    "estimated" if lateral else "filtered", force_cutoff([case]))
    model = baseline_model(case)
    base = fitter(model, (), {}, purpose="baseline")
    predicted = predicted_values(case, model + Pendulum("p2")) if lateral else {}
    ctx = Context(base, collect_evidence(base), predicted, case.rig.gravity, fitter, lateral,
                  case.test.excitation == "measured")
    fam = family(cause)
    assert fam.applies(ctx), f"{cause} does not apply to {case.test.id}"
    terms = fam.terms(ctx)
    scores: list[Score] = []
    if ctx.lateral and ctx.single_channel:
        ctx.linearisation, ctx.base_names, scores = screen(
            base, terms, build=lambda m, mm, init: fitter.problem(m, mm, init))
    good = [sc for sc in scores if sc.statistic >= MIN_SCORE and sc.unphysical is None]
    proposals = fam.propose(ctx, good[:1]) if (good or not terms) else []
    run = FamilyRun(base, ctx, scores, proposals)
    if fit and proposals:
        run.fit = fit_candidate(fitter, proposals[0], base)
    return run
