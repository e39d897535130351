"""Parameter estimation: the problem, its transcription, the NLP solved by IPOPT, the result
with uncertainties and identifiability, profile-likelihood intervals and fit plots."""

from .measurement import ChannelOffsets
from .nlp import Hessian, fit
from .problem import FitProblem
from .profile import profile_interval
from .result import FitResult
from .strategies import (
    AbsCost,
    EstimatedInput,
    FilteredInput,
    FirstStageStart,
    PredictionStart,
    SquaredCost,
)
from .transcription import Collocation, MultipleShooting

__all__ = ["AbsCost", "ChannelOffsets", "Collocation", "EstimatedInput", "FilteredInput",
           "FirstStageStart", "FitProblem", "FitResult", "Hessian", "MultipleShooting",
           "PredictionStart", "SquaredCost", "fit", "plot_fit", "profile_interval"]


def __getattr__(name: str):
    """:func:`estimate.fitting.plots.plot_fit` (``estimate.fitting.plot_fit``), imported
    when first used (it brings matplotlib)."""
    if name == "plot_fit":
        from .plots import plot_fit

        return plot_fit
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
