"""Test data: case files (TOML + CSV), signal processing of the records, and the
experiment that ties a case to a derived model and its excitation."""

from .case import Case, CaseError
from .experiment import Experiment, experiment
from .models import BASELINE, model_from_spec
from .reader import load_case
from .writer import write_case

__all__ = ["BASELINE", "Case", "CaseError", "Experiment", "experiment", "load_case",
           "model_from_spec", "write_case"]
