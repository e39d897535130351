"""The choices of a fit as objects, each with its one default: how the carriage motion
enters (:class:`EstimatedInput`, :class:`FilteredInput`; :data:`DEFAULT_INPUT`), the cost
(:class:`SquaredCost`, :class:`AbsCost`; :data:`DEFAULT_COST`) and where the estimates
start (:class:`FirstStageStart`, :class:`PredictionStart`; :data:`DEFAULT_START`).

The former string arguments (``input="filtered"``, ``cost="abs"``) still work: the
registries (:data:`INPUT_MODES`, :data:`COSTS`) map them to the objects.

Examples
--------
>>> input_mode("filtered")
FilteredInput(cutoff_hz=10.0)
>>> input_mode(None).name, cost_of("abs").name
('estimated', 'abs')
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from analogs.errors import InputError

__all__ = ["AbsCost", "COSTS", "Cost", "DEFAULT_COST", "DEFAULT_INPUT", "DEFAULT_START",
           "EstimatedInput", "FILTERED_FORCE_CUTOFF_HZ", "FilteredInput", "FirstStageStart",
           "INPUT_MODES", "InputMode", "PredictionStart", "SquaredCost", "StartPolicy",
           "cost_of", "input_mode", "record_cutoff", "start_policy"]

#: Force low-pass of the filtered-input mode [Hz] (the seed's workflow).
FILTERED_FORCE_CUTOFF_HZ = 10.0


class InputMode:
    """How a measured carriage displacement enters the fit (lateral rig); the force
    low-pass it implies is :attr:`force_cutoff_hz` [Hz] (None: none)."""

    #: The mode's name in case files, options and fit records.
    name: ClassVar[str] = ""
    #: What the mode does, for help texts.
    description: ClassVar[str] = ""

    @property
    def force_cutoff_hz(self) -> float | None:
        return None


@dataclass(frozen=True)
class EstimatedInput(InputMode):
    """The carriage motion estimated with the parameters (:mod:`estimate.fitting.carriage`):
    its residual weighted by the displacement noise and the force residual by the force
    noise, both read from the spectra; the force is not filtered (the residuals stay
    white, so the covariance holds)."""

    name: ClassVar[str] = "estimated"
    description: ClassVar[str] = "the carriage motion estimated with the parameters"


@dataclass(frozen=True)
class FilteredInput(InputMode):
    """The displacement smoothed and differentiated beforehand
    (:func:`estimate.data.signals.displacement_derivatives`) and treated as exact; the
    force low-passed at ``cutoff_hz`` [Hz] (None: not filtered)."""

    cutoff_hz: float | None = FILTERED_FORCE_CUTOFF_HZ
    name: ClassVar[str] = "filtered"
    description: ClassVar[str] = "the displacement smoothed and differentiated beforehand"

    @property
    def force_cutoff_hz(self) -> float | None:
        return self.cutoff_hz


#: The input modes by name.
INPUT_MODES: dict[str, type[InputMode]] = {"estimated": EstimatedInput, "filtered": FilteredInput}
#: The input mode of a fit that names none.
DEFAULT_INPUT: InputMode = EstimatedInput()


def input_mode(value: InputMode | str | None = None,
               force_cutoff_hz: float | None | str = "auto") -> InputMode:
    """The input mode an argument names.

    Parameters
    ----------
    value : InputMode, str or None
        An input mode, its name (:data:`INPUT_MODES`), or None for :data:`DEFAULT_INPUT`.
    force_cutoff_hz : float, None or "auto", default "auto"
        The former separate force low-pass [Hz]: ``"auto"`` keeps the mode's; a number or
        None sets a filtered input's cutoff, and must be None with the estimated input.

    Raises
    ------
    InputError
        An unknown mode, or a force filter with the estimated input.
    """
    if value is None:
        mode = DEFAULT_INPUT
    elif isinstance(value, InputMode):
        mode = value
    elif isinstance(value, str) and value in INPUT_MODES:
        mode = INPUT_MODES[value]()
    else:
        raise InputError(f"input must be one of {', '.join(map(repr, INPUT_MODES))} (or "
                         f"`EstimatedInput()`, `FilteredInput(cutoff_hz=...)`), got {value!r}")
    if force_cutoff_hz == "auto":
        return mode
    if isinstance(mode, FilteredInput):
        return FilteredInput(cutoff_hz=force_cutoff_hz)
    if force_cutoff_hz is not None:
        raise InputError("the estimated input weighs the force by its white-noise level: "
                         "leave `force_cutoff_hz` at its default (no force filter), or use "
                         "input='filtered'")
    return mode


def record_cutoff(cases, value: InputMode | str | None,
                  force_cutoff_hz: float | None | str = "auto") -> float | None | str:
    """The force low-pass ``force_cutoff_hz`` as the records call for it: six-axis records
    (every case with ``[rig.motion]``, :mod:`estimate.data.motion`) fitted with the filtered
    input named by its string (``value="filtered"``) keep their channels unfiltered (None):
    a 10 Hz filter cut the harmonics of 0.6 rad swings and biased the masses by 1.7 %. A
    cutoff given (not ``"auto"``) or a :class:`FilteredInput` object's own is kept.

    Parameters
    ----------
    cases : sequence of Case
        The records.
    value : InputMode, str or None
        The input mode as :func:`input_mode` takes it.
    force_cutoff_hz : float, None or "auto", default "auto"
        The force low-pass asked for [Hz].
    """
    six_axis = bool(cases) and all(getattr(c, "motion", None) is not None for c in cases)
    if force_cutoff_hz == "auto" and six_axis and value == FilteredInput.name:
        return None
    return force_cutoff_hz


class Cost:
    """The cost of the fit over the residuals ``simulated - measured``."""

    #: The cost's name in options and fit records.
    name: ClassVar[str] = ""
    #: What the cost sums, for help texts.
    description: ClassVar[str] = ""

    def check(self, problem) -> None:
        """Raise :class:`InputError` when the cost cannot fit ``problem``."""


@dataclass(frozen=True)
class SquaredCost(Cost):
    """The sum of squared residuals (N^2, or in units of the noise with the estimated
    input)."""

    name: ClassVar[str] = "squared"
    description: ClassVar[str] = "sum of squared force residuals"


@dataclass(frozen=True)
class AbsCost(Cost):
    """The seed's ``sum((|E| - |S|)^2)`` with a smooth absolute value: force magnitudes
    only (filtered input only)."""

    name: ClassVar[str] = "abs"
    description: ClassVar[str] = "the seed's sum((|E| - |S|)^2)"

    def check(self, problem) -> None:
        if any(c is not None for c in problem.carriage):
            raise InputError("cost='abs' compares force magnitudes only, so it cannot tell the "
                             "carriage motion's sign: build the problem with input='filtered' "
                             "(`slosh fit --cost abs --input filtered`)")


#: The costs by name.
COSTS: dict[str, type[Cost]] = {"squared": SquaredCost, "abs": AbsCost}
#: The cost of a fit that names none.
DEFAULT_COST: Cost = SquaredCost()


def cost_of(value: Cost | str | None = None) -> Cost:
    """The cost an argument names: a :class:`Cost`, its name (:data:`COSTS`) or None
    (:data:`DEFAULT_COST`).

    Parameters
    ----------
    value : Cost, str or None
        The cost.
    """
    if value is None:
        return DEFAULT_COST
    if isinstance(value, Cost):
        return value
    if isinstance(value, str) and value in COSTS:
        return COSTS[value]()
    raise InputError(f"cost must be 'squared' or 'abs', got {value!r}")


class StartPolicy:
    """Where the estimates start (the values the user gives always win)."""

    #: The policy's name.
    name: ClassVar[str] = ""
    #: Whether the first stage (:mod:`estimate.fitting.first_stage`,
    #: :mod:`estimate.fitting.spin_stage`) runs.
    first_stage: ClassVar[bool] = False


@dataclass(frozen=True)
class FirstStageStart(StartPolicy):
    """The first slosh mode, the rigid mass and the lag from a linear identification of
    the records (lateral measured cases; the spinning rig's stage there), else the tank
    prediction."""

    name: ClassVar[str] = "first-stage"
    first_stage: ClassVar[bool] = True


@dataclass(frozen=True)
class PredictionStart(StartPolicy):
    """The tank prediction (``[prediction]`` or the tank modal analysis) and the declared
    defaults."""

    name: ClassVar[str] = "prediction"
    first_stage: ClassVar[bool] = False


#: The start of a fit that names none.
DEFAULT_START: StartPolicy = FirstStageStart()


def start_policy(value: StartPolicy | bool | None = None) -> StartPolicy:
    """The start policy an argument names: a :class:`StartPolicy`, the former
    ``first_stage`` flag (True: :class:`FirstStageStart`, False: :class:`PredictionStart`)
    or None (:data:`DEFAULT_START`).

    Parameters
    ----------
    value : StartPolicy, bool or None
        The policy.
    """
    if value is None:
        return DEFAULT_START
    if isinstance(value, StartPolicy):
        return value
    if isinstance(value, bool):
        return FirstStageStart() if value else PredictionStart()
    raise InputError(f"start must be `FirstStageStart()` or `PredictionStart()`, got {value!r}")
