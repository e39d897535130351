"""Estimation of analog parameters from tank-test data: case files, signal processing,
the NLP (multiple shooting or collocation, IPOPT), uncertainties, diagnosis, reports.

Public API::

    from estimate import load_case, FitProblem, fit, MultipleShooting, Collocation
    problem = FitProblem.build(load_case("examples/A1.toml"), model)
    result = fit(problem)
    print(result.report())
"""

from .case import Case, CaseError, load_case, write_case
from .experiment import Experiment, experiment
from .fit import Hessian, fit
from .models import BASELINE, model_from_spec
from .problem import FitProblem
from .result import FitResult
from .transcription import Collocation, MultipleShooting

__all__ = [
    "BASELINE",
    "Case",
    "CaseError",
    "Collocation",
    "Experiment",
    "FitProblem",
    "FitResult",
    "Hessian",
    "MultipleShooting",
    "experiment",
    "fit",
    "load_case",
    "model_from_spec",
    "write_case",
]
