"""Reading and writing parameter files: a flat JSON map or the JSON ``slosh fit`` writes."""

from __future__ import annotations

import json
import math
from pathlib import Path

from analogs.errors import InputError

__all__ = ["read_params", "read_json", "fitted_initial_state"]


def read_json(path: str | Path, what: str) -> object:
    """JSON content of ``path``; errors name the file and say what it should be."""
    path = Path(path)
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise FileNotFoundError(f"{what} {path} does not exist") from None
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: not valid JSON ({err})") from None


def read_params(path: str | Path) -> dict[str, float]:
    """Parameter values from ``path``.

    Accepts a flat map ``{"p1.mass": 1.338, ...}`` or a fit result with
    ``"parameters": {"p1.mass": {"value": 1.338, ...}, ...}``.

    Raises
    ------
    ValueError
        Naming the file and the key when the file is not such JSON.
    """
    path = Path(path)
    data = read_json(path, "parameter file")
    if isinstance(data, dict) and isinstance(data.get("parameters"), dict):
        data = {k: (v.get("value") if isinstance(v, dict) else v) for k, v in data["parameters"].items()}
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object of parameter values, found {type(data).__name__}")
    out, problems = {}, []
    for key, value in data.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            problems.append(f"`{key}`: expected a finite number, found {value!r}")
        else:
            out[key] = float(value)
    if problems:
        raise InputError(f"{path}: " + "; ".join(problems))
    return out


def fitted_initial_state(path: str | Path, case) -> dict[str, float]:
    """The initial state a fit estimated for ``case`` (``[test] initial_state = "free"``),
    from the fit result ``path`` (its ``"initial_states"`` by case id).

    Raises
    ------
    InputError
        When the file holds no initial state for the case.
    """
    data = read_json(path, "parameter file")
    states = data.get("initial_states") if isinstance(data, dict) else None
    entry = states.get(case.test.id) if isinstance(states, dict) else None
    if not isinstance(entry, dict) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in entry.values()):
        raise InputError(f"{path}: case {case.test.id!r} starts from an estimated state "
                         "([test] initial_state = \"free\"), but the file has no "
                         f"`initial_states.{case.test.id}`; give the JSON `slosh fit` wrote "
                         "for this case")
    return {k: float(v) for k, v in entry.items()}
