"""Reading and writing parameter files: a flat JSON map or the JSON ``slosh fit`` writes."""

from __future__ import annotations

import json
import math
from pathlib import Path

from analogs.errors import InputError

__all__ = ["read_params", "read_json"]


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
