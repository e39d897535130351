"""What the commands that take a fit or a parameter file read besides the record itself
(:func:`~.reader.read_fit`): the values of a flat map or a record, the warnings before a
fit is used, a free-start record's initial state, the model a record names, its layout
version."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from analogs.errors import InputError

__all__ = ["fit_notes", "fit_spec", "fitted_initial_state", "read_json", "read_params",
           "schema_version"]


def read_json(path: str | Path, what: str) -> object:
    """JSON content of ``path``, a ``what`` (``"fit file"``); errors name the file and say
    what it should be (a regular
    file within :data:`estimate.inputs.MAX_JSON_BYTES` bytes: :func:`estimate.inputs.load_json`)."""
    from ...inputs import load_json

    return load_json(path, f"a {what} (JSON)")


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
    where = "{}"
    if isinstance(data, dict) and isinstance(data.get("parameters"), dict):  # a fit result
        data = {k: (v.get("value") if isinstance(v, dict) else v) for k, v in data["parameters"].items()}
        where = "parameters.{}.value"
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object of parameter values, found {type(data).__name__}")
    out, problems = {}, []
    for key, value in data.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            problems.append(f"`{where.format(key)}`: expected a finite number, found {value!r}")
        else:
            out[key] = float(value)
    if problems:
        raise InputError(f"{path}: " + "; ".join(problems))
    return {k: v for k, v in out.items() if not _stream_lag(k)}


def _stream_lag(name: str) -> bool:
    """A stream lag of one record (``<case>:rig.lag``): a property of the recording, not
    of the analog, which simulations and draws leave out."""
    return name.split(":")[-1] == "rig.lag"


def fit_notes(path: str | Path, *, force: bool = False, what: str = "fit file") -> list[str]:
    """Warnings about the fit result ``path`` before a command uses it; a flat map of values
    gives none. ``what`` names the file in messages (``"parameter file"``).

    Raises
    ------
    InputError
        When the file says the fit did not converge (``"converged": false``), unless
        ``force`` (``--force``): then a warning says it is used anyway.
    """
    from ..nlp import LOW_R_SQUARED

    data = read_json(path, what)
    if not isinstance(data, dict):
        return []
    notes = []
    if isinstance(data.get("parameters"), dict) and schema_version(data) == 1:
        notes.append(f"{path}: a fit record written before records carried their provenance "
                     "(no `schema`): the package version, date and data checksums are unknown")
    converged, status = data.get("converged"), data.get("status")
    if converged is False:
        what = (f"{path}: the fit did not converge (`converged: false`"
                + (f", IPOPT status {status}" if isinstance(status, str) else "") + ")")
        if not force:
            raise InputError(f"{what}: its values are not estimates; fit again (other start "
                             "values, model or options), or pass --force to use them anyway")
        notes.append(f"{what}; its values are used because of --force")
    r2 = data.get("r_squared")
    if _is_number(r2) and r2 < LOW_R_SQUARED:
        notes.append(f"{path}: the fitted model explains almost nothing of the measurement "
                     f"(R^2 = {r2:.3g}); its values may not describe the tank")
    return notes


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


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def schema_version(data: Mapping, problems: list[str] | None = None) -> int:
    """The layout version of the fit record ``data``: 1 without ``"schema"`` (written before
    records carried provenance), else the number after ``slosh-analogs/fit/``; a schema of
    another kind is a problem (appended to ``problems``) and reads as the current one."""
    from .writer import SCHEMA

    raw = data.get("schema")
    if raw is None:
        return 1
    head, _, number = str(raw).rpartition("/")
    if not isinstance(raw, str) or head != SCHEMA.rpartition("/")[0] or not number.isdigit():
        if problems is not None:
            problems.append(f"`schema`: expected \"{SCHEMA}\" (a fit record of slosh-analogs), "
                            f"found {raw!r}")
        return int(SCHEMA.rpartition("/")[2])
    return int(number)


def fit_spec(path: str | Path) -> str | None:
    """The model specification the fit record ``path`` names (``model_spec``, else its
    ``model`` list), or None for a flat map of parameter values.

    Raises
    ------
    InputError
        When ``model_spec`` is not a string.
    """
    data = read_json(path, "fit file")
    if not isinstance(data, dict):
        return None
    spec, model = data.get("model_spec"), data.get("model")
    if spec is not None and not isinstance(spec, str):
        raise InputError(f"{path}: `model_spec`: expected a string such as \"fixed,p1\", "
                         f"found {spec!r}")
    if spec:
        return spec
    if isinstance(model, list) and model and all(isinstance(m, str) for m in model):
        return ",".join(model)
    return None
