"""Errors in what a user gave: a model, a parameter value, a file, an option.

Every such error derives from :class:`InputError`; its message says what was expected and
what was found. The ``slosh`` command line prints an ``InputError`` as one line and exits
with status 2; any other exception is a defect of the program and shows its traceback.
"""

from __future__ import annotations

__all__ = ["InputError", "MissingDependency", "UnknownNameError"]


class InputError(ValueError):
    """Invalid input from the user (model declaration, parameter values, files, options)."""


class UnknownNameError(InputError, KeyError):
    """A name (parameter, channel, component, key) the model or file does not have."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class MissingDependency(ImportError):
    """An optional library is not installed; the message names the extra to install."""
