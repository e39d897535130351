"""Reading fit records (the JSON ``slosh fit`` writes, :data:`~.writer.SCHEMA`): every
command that takes a fit reads it here (:func:`read_fit`; a flat JSON map of values and the
warnings before use: :mod:`.parameters`).

A record written before the schema was versioned (no ``"schema"`` key: version 1, without
provenance) still reads; :attr:`Fit.notes` says what it lacks."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import InputError

from .parameters import _is_number, _stream_lag, read_json, schema_version

__all__ = ["Fit", "read_fit"]

#: Two-sided 95 % normal quantile: the interval of a record that does not hold its own
#: (version 1) is the estimate +/- this many standard errors.
_Z95 = 1.959963984540054


@dataclass(frozen=True)
class Fit:
    """A fit record as the commands that take a fit read it (:func:`read_fit`).

    Attributes
    ----------
    path : pathlib.Path or None
        The file read.
    model_spec : str
        The specification of the fitted model (``"fixed,p1:nospring"``).
    case : str or None
        The case file a flat parameter record names, if any.
    values, units, lower, upper : mapping
        Every parameter's value, unit (SI) and bounds (+/-inf when open), by dotted name.
    estimated : tuple of str
        The estimated parameters (the others were fixed or follow them).
    covariance_names : tuple of str
        The estimates the covariance holds (those inside their bounds), in its order.
    covariance : ndarray
        Their covariance (units squared).
    off_bounds : tuple of (str, mapping)
        Per bound the covariance holds an estimate (or the masses) on: its label and how the
        estimates move, by name, when it leaves the bound by one standard deviation (SI
        units; empty for a record written before they were kept).
    to_modes : tuple of (str, mapping)
        Per pendulum far heavier than its tank mode's prediction (the fit's
        ``covariance.to_predicted_modes``): its label and how every estimate moves, by name,
        when that mass is put at the prediction (SI units; the intervals reach that far).
    stderr : mapping
        Standard error of each parameter (NaN when there is none: fixed, or at a bound).
    intervals : mapping
        95 % interval of each estimate, as the fit report gives it; for a version 1 record,
        which holds none, the estimate +/- 1.96 standard errors.
    derived : mapping
        Derived quantities: ``(value, stderr, unit)`` (stderr NaN when there is none).
    derived_intervals : mapping
        Their 95 % intervals (a version 1 record: +/- 1.96 standard errors; NaN where there
        is no standard error).
    converged, status : bool or None, str or None
        Whether IPOPT converged, and its status.
    r_squared : float
        NaN when the record does not give it.
    information_criteria : mapping
        ``aic``, ``bic`` and how they were computed (empty for a version 1 record).
    cases : tuple of str
        The case files fitted.
    schema : int
        The record's layout version (1: written before records carried provenance).
    provenance : mapping or None
        Versions, date, files with their SHA-256, options (None for a version 1 record).
    notes : tuple of str
        What the reader says about the file (an old layout, what it lacks).
    data : mapping
        The whole record as read.
    """

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
    off_bounds: tuple[tuple[str, Mapping[str, float]], ...] = field(default=(), repr=False)
    to_modes: tuple[tuple[str, Mapping[str, float]], ...] = field(default=(), repr=False)
    stderr: Mapping[str, float] = field(default_factory=dict, repr=False)
    intervals: Mapping[str, tuple[float, float]] = field(default_factory=dict, repr=False)
    derived: Mapping[str, tuple[float, float, str]] = field(default_factory=dict, repr=False)
    derived_intervals: Mapping[str, tuple[float, float]] = field(default_factory=dict,
                                                                 repr=False)
    converged: bool | None = None
    status: str | None = None
    r_squared: float = math.nan
    information_criteria: Mapping[str, Any] = field(default_factory=dict, repr=False)
    cases: tuple[str, ...] = ()
    schema: int = 1
    provenance: Mapping[str, Any] | None = field(default=None, repr=False)
    notes: tuple[str, ...] = ()
    data: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @property
    def draw_names(self) -> tuple[str, ...]:
        """The parameters a Monte Carlo draws: the covariance's, then those held on a bound
        that move off it (:attr:`off_bounds`) or with a mode put at its prediction
        (:attr:`to_modes`)."""
        extra = [n for _, move in (*self.off_bounds, *self.to_modes) for n in move
                 if n not in self.covariance_names]
        return self.covariance_names + tuple(dict.fromkeys(extra))

    @property
    def name(self) -> str:
        """A short label: the file's name, or ``"(fit)"``."""
        return self.path.name if self.path is not None else "(fit)"


def _bound(entry: Mapping, key: str, default: float, where: str, problems: list[str]) -> float:
    v = entry.get(key)
    if v is None:
        return default
    if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v):
        problems.append(f"`{where}.{key}`: expected a number or null, found {v!r}")
        return default
    return float(v)


def _optional_number(entry: Mapping, key: str, where: str, problems: list[str]) -> float:
    """A number or null (NaN) at ``entry[key]``; absent is NaN."""
    v = entry.get(key)
    if v is None:
        return math.nan
    if not _is_number(v):
        problems.append(f"`{where}.{key}`: expected a finite number or null, found {v!r}")
        return math.nan
    return float(v)


def _interval(raw: Any, value: float, se: float, key: str, problems: list[str]
              ) -> tuple[float, float]:
    """The 95 % interval ``raw`` found at ``key`` (``[lower, upper]``, null for none); a
    version 1 record has none (``raw`` None): the estimate +/- 1.96 standard errors."""
    if raw is None:
        return (value - _Z95 * se, value + _Z95 * se) if math.isfinite(se) else \
            (math.nan, math.nan)
    if not (isinstance(raw, list) and len(raw) == 2
            and all(x is None or _is_number(x) for x in raw)):
        problems.append(f"`{key}`: expected [lower, upper] (numbers or null), found {raw!r}")
        return math.nan, math.nan
    return tuple(math.nan if x is None else float(x) for x in raw)  # type: ignore[return-value]


def _parameters(params: Mapping, problems: list[str]):
    values, units, lower, upper, estimated = {}, {}, {}, {}, []
    stderr, intervals = {}, {}
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
        stderr[name] = _optional_number(entry, "stderr", where, problems)
        flag = entry.get("estimated", False)
        if not isinstance(flag, bool):
            problems.append(f"`{where}.estimated`: expected true or false, found {flag!r}")
        elif flag:
            estimated.append(name)
            intervals[name] = _interval(entry.get("interval_95"), values[name], stderr[name],
                                        f"{where}.interval_95", problems)
    return values, units, lower, upper, estimated, stderr, intervals


def _derived(data: Mapping, problems: list[str]
             ) -> tuple[dict[str, tuple[float, float, str]], dict[str, tuple[float, float]]]:
    """Derived quantities ``(value, stderr, unit)`` and their 95 % intervals."""
    values, errors, units, intervals = (data.get(k) for k in (
        "derived", "derived_stderr", "derived_units", "derived_interval_95"))
    if values is None:
        return {}, {}
    if not isinstance(values, Mapping):
        problems.append(f"`derived`: expected an object of numbers, found {values!r}"[:300])
        return {}, {}
    errors = errors if isinstance(errors, Mapping) else {}
    units = units if isinstance(units, Mapping) else {}
    out, bands = {}, {}
    for k, v in values.items():
        if not _is_number(v):
            problems.append(f"`derived.{k}`: expected a finite number, found {v!r}")
            continue
        se = errors.get(k)
        out[k] = (float(v), float(se) if _is_number(se) else math.nan, str(units.get(k, "")))
        raw = intervals.get(k) if isinstance(intervals, Mapping) else None
        bands[k] = _interval(raw, *out[k][:2], f"derived_interval_95.{k}", problems)
    return out, bands


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


def _moves(cov: Any, values: Mapping, problems: list[str], key: str, label: str
           ) -> tuple[tuple[str, dict[str, float]], ...]:
    """The labelled moves of the estimates in ``covariance.<key>`` (``off_bounds``:
    ``{"bound": ..., "move": {...}}``; ``to_predicted_modes``: ``{"mode": ..., ...}``)."""
    raw = cov.get(key) if isinstance(cov, Mapping) else None
    if raw is None:
        return ()
    if not isinstance(raw, list):
        problems.append(f"`covariance.{key}`: expected a list, found {raw!r}"[:300])
        return ()
    out = []
    for i, entry in enumerate(raw):
        where = f"`covariance.{key}[{i}]`"
        move = entry.get("move") if isinstance(entry, Mapping) else None
        if not (isinstance(entry, Mapping) and isinstance(entry.get(label), str)
                and isinstance(move, Mapping) and all(_is_number(v) for v in move.values())):
            problems.append(f"{where}: expected an object with a \"{label}\" string and a "
                            f"\"move\" object of finite numbers, found {entry!r}"[:300])
            continue
        unknown = [n for n in move if n not in values]
        if unknown:
            problems.append(f"{where}.move: not in parameters: {', '.join(unknown)}")
            continue
        out.append((entry[label], {n: float(v) for n, v in move.items()}))
    return tuple(out)


def read_fit(path: str | Path) -> Fit:
    """Read the fit record ``path`` (the JSON of ``slosh fit``), of any schema version.

    Raises
    ------
    InputError
        Naming the file and, for every problem, the key: missing keys, values of the wrong
        type, a covariance that is not square, names that are not parameters.

    Examples
    --------
    >>> fit = read_fit("A1_fit.json")                        # doctest: +SKIP
    >>> fit.model_spec, fit.values["p1.mass"], fit.intervals["p1.mass"]   # doctest: +SKIP
    ('fixed,p1', 1.30015, (1.29589, 1.30442))
    """
    from .writer import SCHEMA

    path = Path(path)
    data = read_json(path, "fit file")
    params = data.get("parameters") if isinstance(data, dict) else None
    if not isinstance(params, dict) or not params:
        raise InputError(f"{path}: expected a fit result (as `slosh fit --json` writes) with a "
                         "non-empty \"parameters\" object")
    problems: list[str] = []
    schema = schema_version(data, problems)
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
    values, units, lower, upper, estimated, stderr, intervals = _parameters(params, problems)
    names, matrix = _covariance(data.get("covariance"), values, problems)
    off_bounds = _moves(data.get("covariance"), values, problems, "off_bounds", "bound")
    to_modes = _moves(data.get("covariance"), values, problems, "to_predicted_modes", "mode")
    derived, derived_intervals = _derived(data, problems)
    converged, status = data.get("converged"), data.get("status")
    cases = data.get("cases")
    cases = tuple(cases) if isinstance(cases, list) and all(isinstance(c, str) for c in cases) \
        else ()
    prov = data.get("provenance")
    if prov is not None and not isinstance(prov, Mapping):
        problems.append(f"`provenance`: expected an object, found {prov!r}"[:300])
        prov = None
    criteria = data.get("information_criteria")
    if problems:
        raise InputError(f"{path}: " + "; ".join(problems))
    notes = []
    if schema == 1:
        notes.append(f"{path}: a fit record written before records carried their provenance "
                     "(no `schema`): the package version, date and data checksums are unknown, "
                     "and its 95 % intervals are the estimates +/- 1.96 standard errors")
    elif schema > int(SCHEMA.rpartition("/")[2]):
        notes.append(f"{path}: written by a newer slosh-analogs (schema {data['schema']}); "
                     f"read as {SCHEMA}, keys this version does not know ignored")
    keep = [i for i, n in enumerate(names) if not _stream_lag(n)]  # marginal of the analog
    names, matrix = tuple(names[i] for i in keep), np.asarray(matrix)[np.ix_(keep, keep)]
    estimated = [n for n in estimated if not _stream_lag(n)]
    off_bounds, to_modes = (tuple((label, {n: v for n, v in move.items() if not _stream_lag(n)})
                                  for label, move in moves) for moves in (off_bounds, to_modes))
    for d in (values, units, lower, upper, stderr, intervals):
        for k in [k for k in d if _stream_lag(k)]:
            del d[k]
    return Fit(path=path, model_spec=str(spec), case=case, values=values, units=units,
               lower=lower, upper=upper, estimated=tuple(estimated), covariance_names=names,
               covariance=matrix, off_bounds=off_bounds, to_modes=to_modes, stderr=stderr,
               intervals=intervals,
               derived=derived, derived_intervals=derived_intervals,
               converged=converged if isinstance(converged, bool) else None,
               status=status if isinstance(status, str) else None,
               r_squared=float(data["r_squared"]) if _is_number(data.get("r_squared"))
               else math.nan,
               information_criteria=dict(criteria) if isinstance(criteria, Mapping) else {},
               cases=cases, schema=schema, provenance=prov, notes=tuple(notes), data=data)
