"""The public API of :mod:`estimate.design`: every name in ``__all__`` imports, every
public callable says what it does, and the command is registered."""

import inspect

import estimate.design as design
from estimate.cli import _COMMANDS


def test_every_public_name_imports_and_is_documented():
    for name in design.__all__:
        obj = getattr(design, name)
        if callable(obj):
            assert inspect.getdoc(obj), name


def test_design_parameters_are_documented():
    doc = inspect.getdoc(design.design)
    for p in inspect.signature(design.design).parameters:
        assert p in doc, p
    doc = inspect.getdoc(design.DesignProblem.build)
    for p in inspect.signature(design.DesignProblem.build).parameters:
        if p != "cls":
            assert p in doc, p


def test_the_command_is_registered():
    assert "design" in _COMMANDS
