"""Derivation of analog models: SymPy equations of motion -> cached CasADi functions,
simulation, and (later) C/FMU export.

Public API::

    from derive import derive, simulate, RK4, Adaptive, Sine, Sampled
"""

from ._derive import derive
from .derived import OUTPUT_NAMES, OUTPUT_UNITS, DerivedModel, ParameterError
from .excitation import Excitation, NoExcitation, Sampled, Sine
from .simulate import RK4, Adaptive, Simulation, rk4_step, simulate

__all__ = [
    "Adaptive",
    "DerivedModel",
    "Excitation",
    "NoExcitation",
    "OUTPUT_NAMES",
    "OUTPUT_UNITS",
    "ParameterError",
    "RK4",
    "Sampled",
    "Simulation",
    "Sine",
    "derive",
    "rk4_step",
    "simulate",
]
