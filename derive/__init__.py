"""Derivation of analog models: SymPy equations of motion -> cached CasADi functions,
simulation, and (later) C/FMU export.

Public API::

    from derive import derive, simulate, RK4, Adaptive, Sine, Sampled
    from derive import compiled, c_compiler   # CasADi functions as C, and the compiler
"""

from ._compile import c_compiler, compiled
from ._derive import derive
from .derived import OUTPUT_NAMES, OUTPUT_UNITS, DerivedModel, ParameterError
from .excitation import Excitation, NoExcitation, Sampled, Sine
from .export_c import CExport, export_c, has_c_compiler, run_driver, write_input_csv
from .simulate import RK4, Adaptive, Simulation, rk4_step, simulate, simulate_outputs

__all__ = [
    "Adaptive",
    "CExport",
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
    "c_compiler",
    "compiled",
    "derive",
    "export_c",
    "export_fmu",
    "has_c_compiler",
    "rk4_step",
    "run_driver",
    "simulate",
    "simulate_outputs",
    "write_input_csv",
]


def __getattr__(name: str):
    """:func:`derive.fmu.export_fmu` (``derive.export_fmu``), imported when first used."""
    if name == "export_fmu":
        from .fmu import export_fmu

        return export_fmu
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
