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
"""

from .analysis.ntc import (
                           NutationTimeConstant,
                           envelope_growth_rate,
                           linearize,
                           nutation_time_constant,
                           steady_spin,
)
from .data.case import Case, CaseError
from .data.experiment import Experiment, experiment
from .data.models import BASELINE, model_from_spec
from .data.reader import load_case
from .data.writer import write_case
from .diagnosis.search import Diagnosis, Finding, diagnose
from .fitting.measurement import ChannelOffsets
from .fitting.nlp import Hessian, fit
from .fitting.problem import FitProblem
from .fitting.profile import profile_interval
from .fitting.result import FitResult
from .fitting.transcription import Collocation, MultipleShooting

__all__ = [
    "BASELINE",
    "Case",
    "CaseError",
    "ChannelOffsets",
    "Collocation",
    "Diagnosis",
    "Experiment",
    "FitProblem",
    "FitResult",
    "Finding",
    "Hessian",
    "MultipleShooting",
    "NutationTimeConstant",
    "diagnose",
    "envelope_growth_rate",
    "experiment",
    "fit",
    "linearize",
    "load_case",
    "model_from_spec",
    "nutation_time_constant",
    "profile_interval",
    "steady_spin",
    "write_case",
]
