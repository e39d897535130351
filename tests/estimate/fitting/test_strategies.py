"""Strategies as objects (estimate/fitting/strategies.py): one default each, the former
strings mapped to the objects, and FitProblem.build reporting every argument problem at
once."""

from pathlib import Path

import pytest

from analogs.errors import InputError, UnknownNameError
from estimate import FitProblem, load_case, model_from_spec
from estimate.fitting.strategies import (
    DEFAULT_COST,
    DEFAULT_INPUT,
    DEFAULT_START,
    AbsCost,
    EstimatedInput,
    FilteredInput,
    FirstStageStart,
    PredictionStart,
    SquaredCost,
    cost_of,
    input_mode,
    start_policy,
)

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "A1.toml"


def test_one_default_each():
    assert DEFAULT_INPUT == EstimatedInput() and input_mode(None) is DEFAULT_INPUT
    assert DEFAULT_COST == SquaredCost() and cost_of(None) is DEFAULT_COST
    assert DEFAULT_START == FirstStageStart() and start_policy(None) is DEFAULT_START


def test_strings_and_flags_map_to_the_objects():
    assert input_mode("estimated") == EstimatedInput()
    assert input_mode("filtered") == FilteredInput(cutoff_hz=10.0)
    assert input_mode("filtered", 4.0) == FilteredInput(cutoff_hz=4.0)
    assert input_mode("filtered", None).force_cutoff_hz is None
    assert input_mode(FilteredInput(cutoff_hz=3.0)).force_cutoff_hz == 3.0
    assert input_mode("estimated", None).force_cutoff_hz is None
    assert cost_of("abs") == AbsCost() and cost_of("squared") == SquaredCost()
    assert start_policy(True) == FirstStageStart() and start_policy(False) == PredictionStart()


@pytest.mark.parametrize(("call", "match"), [
    (lambda: input_mode("smoothed"), r"input must be one of 'estimated', 'filtered'"),
    (lambda: input_mode("estimated", 10.0), r"leave `force_cutoff_hz` at its default"),
    (lambda: cost_of("huber"), r"cost must be 'squared' or 'abs', got 'huber'"),
    (lambda: start_policy("truth"), r"start must be `FirstStageStart\(\)`"),
])
def test_unknown_strategies_are_refused(call, match):
    with pytest.raises(InputError, match=match):
        call()


@pytest.fixture(scope="module")
def case():
    return load_case(EXAMPLE)


def test_build_takes_the_objects_as_the_strings(case):
    model = model_from_spec("fixed,p1", case)
    by_name = FitProblem.build(case, model, input="filtered", force_cutoff_hz=5.0,
                               first_stage=False)
    by_object = FitProblem.build(case, model, input=FilteredInput(cutoff_hz=5.0),
                                 start=PredictionStart())
    for p in (by_name, by_object):
        assert p.input == "filtered" and p.force_cutoff_hz == 5.0 and p.first_stage is None
    assert by_name.initial.tolist() == by_object.initial.tolist()
    default = FitProblem.build(case, model)
    assert default.input_mode == DEFAULT_INPUT and default.force_cutoff_hz is None


def test_build_reports_every_argument_problem_at_once(case):
    model = model_from_spec("fixed,p1", case)
    with pytest.raises(InputError, match=r"(?s)3 problems with the fit problem:.*input must be "
                                         r"one of.*channel_weights: expected positive.*lag must "
                                         r"be one of"):
        FitProblem.build(case, model, input="smoothed", channel_weights={"force_x": -1.0},
                         lag="sometimes")


def test_build_reports_every_unknown_name_at_once(case):
    model = model_from_spec("fixed,p1", case)
    with pytest.raises(UnknownNameError, match=r"(?s)2 problems.*unknown parameter `p9.mass`.*"
                                               r"channel_weights: unknown channel `torque_q`"):
        FitProblem.build(case, model, hold={"p9.mass": 1.0}, channel_weights={"torque_q": 1.0})
