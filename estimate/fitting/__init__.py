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
           "PredictionStart", "SquaredCost", "fit", "profile_interval"]
