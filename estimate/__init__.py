"""Estimation of analog parameters from tank-test data: case files, signal processing,
the NLP (multiple shooting or collocation, IPOPT), uncertainties, diagnosis, reports.

Public API::

    from estimate import load_case, FitProblem, fit, MultipleShooting, Collocation
    problem = FitProblem.build(load_case("examples/A1.toml"), model)
    result = fit(problem)
    print(result.report())
"""

from .case import Case, CaseError, load_case, write_case
from .diagnose import Diagnosis, Finding, diagnose
from .experiment import Experiment, experiment
from .fit import Hessian, fit
from .models import BASELINE, model_from_spec
from .ntc import (NutationTimeConstant, envelope_growth_rate, linearize, nutation_time_constant,
                  steady_spin)
from .problem import FitProblem
from .profile import profile_interval
from .result import FitResult
from .transcription import Collocation, MultipleShooting

__all__ = [
    "BASELINE",
    "Case",
    "CaseError",
    "Diagnosis",
    "Collocation",
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
