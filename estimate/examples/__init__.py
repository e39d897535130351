"""The bundled SYNTHETIC example cases, found through the installed package.

Every file is synthetic (made by the independent reference simulator of the test suite,
never a measurement): ``A1.toml`` (8-inch sphere at 60 % fill on the lateral rig,
measured excitation; truth in ``A1_truth.json`` and ``A1_params.json``), ``A1_crank.toml``
(the same test driven by the crank), ``D1_two_modes.toml`` (a 1-5 Hz sweep whose data hide
a second slosh mode at 3.8 Hz, for the diagnosis) and ``spacecraft.toml`` (an NTC input).

Examples
--------
>>> from estimate import examples, load_case
>>> case = load_case(examples.path("A1.toml"))
>>> case.test.id
'A1'
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from analogs.errors import InputError

__all__ = ["path", "names"]

_SUFFIXES = (".toml", ".csv", ".json")


def _folder() -> Path:
    return Path(str(resources.files(__name__).joinpath("data")))


def names() -> list[str]:
    """File names of the bundled examples (case files, their data, truths)."""
    return sorted(p.name for p in _folder().iterdir() if p.suffix in _SUFFIXES)


def path(name: str) -> Path:
    """The path of the bundled example file ``name`` (e.g. ``"A1.toml"``).

    Raises
    ------
    InputError
        When there is no such example; the message lists the examples.
    """
    p = _folder() / name
    if name not in names():
        raise InputError(f"no bundled example `{name}`; the examples are {', '.join(names())}")
    return p
