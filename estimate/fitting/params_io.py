"""Reading parameter files: a flat JSON map, or the fit result ``slosh fit`` writes."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import InputError

__all__ = ["Fit", "fit_notes", "read_fit", "read_params", "read_json", "fitted_initial_state"]


def read_json(path: str | Path, what: str) -> object:
    """JSON content of ``path``; errors name the file and say what it should be (a regular
    file within :data:`estimate.inputs.MAX_JSON_BYTES` bytes: :func:`estimate.inputs.load_json`)."""
    from ..inputs import load_json

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
    gives none.

    Raises
    ------
    InputError
        When the file says the fit did not converge (``"converged": false``), unless
        ``force`` (``--force``): then a warning says it is used anyway.
    """
    from .nlp import LOW_R_SQUARED

    data = read_json(path, what)
    if not isinstance(data, dict):
        return []
    notes = []
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


@dataclass(frozen=True)
class Fit:
    """What Monte Carlo and export need from the JSON that ``slosh fit`` writes."""

    path: Path | None
    model_spec: str
    case: str | None
    values: Mapping[str, float]
    units: Mapping[str, str]
    lower: Mapping[str, float]
    upper: Mapping[str, float]
    estimated: tuple[str, ...]
    covariance_names: tuple[str, ...]
    covariance: np.ndarray = field(repr=False)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _bound(entry: Mapping, key: str, default: float, where: str, problems: list[str]) -> float:
    v = entry.get(key)
    if v is None:
        return default
    if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v):
        problems.append(f"`{where}.{key}`: expected a number or null, found {v!r}")
        return default
    return float(v)


def _parameters(params: Mapping, problems: list[str]):
    values, units, lower, upper, estimated = {}, {}, {}, {}, []
    for name, entry in params.items():
        where = f"parameters.{name}"
        if not isinstance(entry, Mapping):
            problems.append(f"`{where}`: expected {{\"value\": number, ...}}, found {entry!r}")
            continue
        if not _is_number(entry.get("value")):
            problems.append(f"`{where}.value`: expected a finite number, found "
                            f"{entry.get('value')!r}")
            continue
        values[name] = float(entry["value"])
        unit = entry.get("unit", "")
        if not isinstance(unit, str):
            problems.append(f"`{where}.unit`: expected a string, found {unit!r}")
        units[name] = str(unit)
        lower[name] = _bound(entry, "lower", -math.inf, where, problems)
        upper[name] = _bound(entry, "upper", math.inf, where, problems)
        flag = entry.get("estimated", False)
        if not isinstance(flag, bool):
            problems.append(f"`{where}.estimated`: expected true or false, found {flag!r}")
        elif flag:
            estimated.append(name)
    return values, units, lower, upper, estimated


def _covariance(cov: Any, values: Mapping, problems: list[str]) -> tuple[tuple[str, ...], np.ndarray]:
    empty = np.zeros((0, 0))
    if cov is None:
        return (), empty
    if not isinstance(cov, Mapping):
        problems.append(f"`covariance`: expected an object with \"parameters\" and \"matrix\", "
                        f"found {type(cov).__name__} {cov!r}"[:300])
        return (), empty
    names = cov.get("parameters") or []
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        problems.append(f"`covariance.parameters`: expected a list of parameter names, found "
                        f"{names!r}"[:300])
        return (), empty
    raw = cov.get("matrix")
    rows = raw if raw is not None else []
    if not (isinstance(rows, list) and all(isinstance(r, list) and all(_is_number(x) for x in r)
                                           for r in rows)):
        problems.append("`covariance.matrix`: expected a list of rows of finite numbers, found "
                        f"{raw!r}"[:300])
        return (), empty
    n = len(names)
    if any(len(r) != n for r in rows) or len(rows) != n:
        shape = (len(rows), *sorted({len(r) for r in rows}))
        problems.append(f"`covariance.matrix` must be {n}x{n} (one row per "
                        f"covariance.parameters), found rows x columns {shape}")
        return (), empty
    unknown = [x for x in names if x not in values]
    if unknown:
        problems.append(f"`covariance.parameters` not in parameters: {', '.join(unknown)}")
    return tuple(names), np.array(rows, dtype=float).reshape(n, n)


def read_fit(path: str | Path) -> Fit:
    """Read a fit result (the JSON of ``slosh fit``).

    Raises
    ------
    InputError
        Naming the file and, for every problem, the key: missing keys, values of the wrong
        type, a covariance that is not square, names that are not parameters.
    """
    path = Path(path)
    data = read_json(path, "fit file")
    params = data.get("parameters") if isinstance(data, dict) else None
    if not isinstance(params, dict) or not params:
        raise InputError(f"{path}: expected a fit result (as `slosh fit --json` writes) with a "
                         "non-empty \"parameters\" object")
    problems: list[str] = []
    spec, model = data.get("model_spec"), data.get("model")
    if spec is not None and not isinstance(spec, str):
        problems.append(f"`model_spec`: expected a string such as \"fixed,p1\", found {spec!r}")
        spec = None
    if not spec and isinstance(model, list) and all(isinstance(m, str) for m in model):
        spec = ",".join(model)
    if not spec:
        problems.append("`model_spec`: missing (expected a string such as \"fixed,p1\")")
    case = data.get("case")
    if case is not None and not isinstance(case, str):
        problems.append(f"`case`: expected a string, found {case!r}")
        case = None
    values, units, lower, upper, estimated = _parameters(params, problems)
    names, matrix = _covariance(data.get("covariance"), values, problems)
    if problems:
        raise InputError(f"{path}: " + "; ".join(problems))
    keep = [i for i, n in enumerate(names) if not _stream_lag(n)]  # marginal of the analog
    names, matrix = tuple(names[i] for i in keep), np.asarray(matrix)[np.ix_(keep, keep)]
    values = {k: v for k, v in values.items() if not _stream_lag(k)}
    estimated = [n for n in estimated if not _stream_lag(n)]
    for d in (units, lower, upper):
        for k in [k for k in d if _stream_lag(k)]:
            del d[k]
    return Fit(path=path, model_spec=str(spec), case=case, values=values, units=units,
               lower=lower, upper=upper, estimated=tuple(estimated), covariance_names=names,
               covariance=matrix)
