"""Estimation of analog parameters from tank-test data, by stage:

* :mod:`estimate.data` - case files (TOML + CSV), signal processing, experiments;
* :mod:`estimate.fitting` - the problem, its transcription, the IPOPT NLP, results with
  uncertainties and identifiability, profile intervals, plots;
* :mod:`estimate.diagnosis` - evidence of what a fit gets wrong, candidate extensions,
  the held-out search and its report;
* :mod:`estimate.analysis` - what a fitted or declared analog predicts (Monte Carlo force
  dispersion, spacecraft nutation time constant);
* :mod:`estimate.cli` - the ``slosh`` command line, one module per command.

Public API::

    from estimate import load_case, FitProblem, fit, MultipleShooting, Collocation
    problem = FitProblem.build(load_case("examples/A1.toml"), model)
    result = fit(problem)
    print(result.report())

The names are imported when first used (PEP 562), so ``import estimate.cli`` - the ``slosh``
command's start - does not load CasADi, SciPy and the rest before the command can answer a
Ctrl-C with one line.
"""

import importlib

#: Public name -> module that defines it.
_EXPORTS = {
    "BASELINE": ".data.models",
    "Case": ".data.case",
    "CaseError": ".data.case",
    "AbsCost": ".fitting.strategies",
    "ChannelOffsets": ".fitting.measurement",
    "EstimatedInput": ".fitting.strategies",
    "FilteredInput": ".fitting.strategies",
    "FirstStageStart": ".fitting.strategies",
    "PredictionStart": ".fitting.strategies",
    "SquaredCost": ".fitting.strategies",
    "Collocation": ".fitting.transcription",
    "Diagnosis": ".diagnosis.search",
    "Experiment": ".data.experiment",
    "FitProblem": ".fitting.problem",
    "FitResult": ".fitting.result",
    "Finding": ".diagnosis.search",
    "Hessian": ".fitting.nlp",
    "MultipleShooting": ".fitting.transcription",
    "NutationTimeConstant": ".analysis.ntc",
    "diagnose": ".diagnosis.search",
    "envelope_growth_rate": ".analysis.ntc",
    "experiment": ".data.experiment",
    "fit": ".fitting.nlp",
    "linearize": ".analysis.ntc",
    "load_case": ".data.reader",
    "model_from_spec": ".data.models",
    "nutation_time_constant": ".analysis.ntc",
    "profile_interval": ".fitting.profile",
    "steady_spin": ".analysis.ntc",
    "write_case": ".data.writer",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
