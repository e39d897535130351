"""Records in the formats test labs write: LabVIEW TDMS, MATLAB ``.mat`` (v4/v5/v7 and the
HDF5-based v7.3) and HDF5, read channel by channel and converted to SI units.

A case file names such a file in ``[test] data`` (the suffix decides the format: ``.tdms``,
``.mat``, ``.h5``/``.hdf5``/``.hdf``) and maps our column names to the file's channels in a
``[data.columns]`` table, each a channel name or a table with the channel and its unit::

    [test]
    data = "A1.tdms"

    [data.columns]
    time = "Time"                                 # SI (s) unless the file says otherwise
    displacement = { channel = "x", unit = "mm" }
    force = { channel = "Loads/Fx", unit = "lbf" }

Channels are named as the file names them:

* TDMS: ``"Group/Channel"``, or ``"Channel"`` when one group has it. ``time`` may be left
  out when the channels are waveforms (``wf_increment`` and ``wf_start_offset``, as
  LabVIEW writes them): the time is then the force channel's time track.
* MAT v4-v7 (read with :func:`scipy.io.loadmat`): a top-level variable holding a vector.
* MAT v7.3 and HDF5 (read with h5py): the path of a dataset holding a vector, e.g. ``"Fx"``
  or ``"run1/Fx"``. A v7.3 file is an HDF5 file with a 512-byte MATLAB header; MATLAB
  stores a column vector ``N x 1`` as a dataset of shape ``(1, N)`` with the attribute
  ``MATLAB_class = "double"``, which is what is read (any vector shape is accepted).

The unit of a channel is, in this order: ``unit`` in ``[data.columns]``; the unit the file
gives (TDMS property ``unit_string``, HDF5 attribute ``unit`` or ``units``); the SI unit of
the column (s, m, N; N m for torques; rad or rad/s for the rig motion columns of
``[rig.spin]``). Units are read and converted by pint, so any unit it knows is accepted
(``lbf``, ``kN``, ``mm``, ``in``, ``ms``, ``deg``) and a unit of the wrong kind (a mass
``lb`` for a force) is refused. Without a ``[data.columns]`` table the channels are looked
up by our column names (``time``, ``displacement``, ``force``; the six force and torque
channels of the spinning rig), in SI units.

Every problem names the file and the channel (or the case file's key), like the CSV
reader's; samples are then checked exactly as a CSV's (finite, at least 50, strictly
increasing uniform time, the memory budget of :mod:`estimate.data.budget` before anything
is read). npTDMS, h5py and pint are the optional ``lab`` extra
(``python3 -m pip install '.[lab]'``); a missing one raises
:class:`~analogs.errors.MissingDependency` naming it.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import MissingDependency

from ._lab_damage import captured_warnings
from ._lab_files import _Channel, _mat5_damage, _open, _require
from ._samples import check_samples, rows_text
from .budget import decimation_hint, max_samples
from .case import SPINNING_CHANNELS, Rig

__all__ = ["LAB_SUFFIXES", "is_lab_file", "read_lab"]

#: File suffixes read by this module, and their format.
LAB_SUFFIXES: dict[str, str] = {".tdms": "TDMS", ".mat": "MAT", ".h5": "HDF5", ".hdf5": "HDF5",
                                ".hdf": "HDF5"}

_LATERAL = ("time", "displacement", "force")
_SI = {"time": "s", "displacement": "m", "force": "N"} | {c: "N" for c in SPINNING_CHANNELS[:3]} \
    | {c: "N*m" for c in SPINNING_CHANNELS[3:]}
_SPIN_UNITS = {"spin_angle": "rad", "spin_rate": "rad/s", "nutation_phase": "rad",
               "cone_angle": "rad"}
_EXAMPLE_UNITS = {"s": '"s" or "ms"', "m": '"m", "mm" or "in"', "N": '"N", "kN" or "lbf"',
                  "N*m": '"N m" or "lbf in"', "rad": '"rad" or "deg"', "rad/s": '"rad/s" or "rpm"'}
_KIND = {"s": "a time", "m": "a length", "N": "a force", "N*m": "a torque", "rad": "an angle",
         "rad/s": "an angular rate"}
_MAX_LISTED_CHANNELS = 12
def is_lab_file(path: Path) -> bool:
    """Whether ``path`` is read by :func:`read_lab` (by its suffix) rather than as a CSV."""
    return path.suffix.lower() in LAB_SUFFIXES


@functools.cache
def _registry():
    import pint

    return pint.UnitRegistry()


@dataclass(frozen=True)
class _Spec:
    """One entry of ``[data.columns]``: our column, the file's channel, the unit given."""

    column: str
    channel: str
    unit: str | None
    explicit: bool  # named in [data.columns] (else looked up by our column name)
    optional: bool = False  # looked up by name, and the case does not need it


def _columns_table(doc: Mapping[str, Any], toml_name: str, problems: list[str]
                   ) -> dict[str, _Spec] | None:
    """The ``[data.columns]`` entries (``{}`` when absent), or None after a problem."""
    data = doc.get("data")
    if data is None:
        return {}
    where = f"{toml_name}: [data]"
    if not isinstance(data, Mapping):
        problems.append(f"{where}: expected a table with a `columns` table, found `{data!r}`")
        return None
    columns = data.get("columns", {})
    if not isinstance(columns, Mapping):
        problems.append(f"{where} columns: expected a table mapping column names to channels "
                        f'(e.g. `force = {{ channel = "Fx", unit = "lbf" }}`), found `{columns!r}`')
        return None
    out: dict[str, _Spec] = {}
    ok = True
    for column, value in columns.items():
        key = f"{toml_name}: [data.columns] {column}"
        unit = None
        if isinstance(value, Mapping):
            extra = sorted(set(value) - {"channel", "unit"})
            channel, unit = value.get("channel"), value.get("unit")
            if extra:
                problems.append(f"{key}: unknown key(s) {', '.join(f'`{k}`' for k in extra)} "
                                "(expected `channel` and optionally `unit`)")
                ok = False
            if unit is not None and (not isinstance(unit, str) or not unit.strip()):
                problems.append(f"{key}: `unit`: expected a unit name such as \"lbf\" or \"mm\", "
                                f"found `{unit!r}`")
                ok = False
        else:
            channel = value
        if not isinstance(channel, str) or not channel.strip():
            problems.append(f"{key}: expected a channel name (`{column} = \"Fx\"`) or a table "
                            f'(`{column} = {{ channel = "Fx", unit = "lbf" }}`), found `{value!r}`')
            ok = False
            continue
        out[column] = _Spec(column, channel.strip(), unit.strip() if isinstance(unit, str) else None,
                            True)
    return out if ok else None


def _wanted(specs: dict[str, _Spec], rig_kind: str | None, excitation: str | None,
            rig: Rig | None, toml_name: str, problems: list[str]) -> dict[str, _Spec] | None:
    """Every column to read, with the defaults for those ``[data.columns]`` leaves out."""
    if rig_kind == "spinning":
        required = ("time", *SPINNING_CHANNELS)
        spin_cols = tuple(rig.spin.columns.values()) if rig is not None and rig.spin else ()
        optional = tuple(c for c in spin_cols if c not in required)
        allowed = None
    else:
        optional = ("displacement",) if excitation == "crank" else ()
        required = tuple(c for c in _LATERAL if c not in optional)
        allowed = _LATERAL
    if allowed is not None:
        unknown = [c for c in specs if c not in allowed]
        if unknown:
            problems.append(f"{toml_name}: [data.columns]: unknown column(s) "
                            f"{', '.join(f'`{c}`' for c in unknown)} (expected "
                            f"{', '.join(f'`{c}`' for c in allowed)})")
            return None
    out = dict(specs)
    for column in (*required, *optional):
        if column not in out:
            out[column] = _Spec(column, column, None, False, optional=column in optional)
    order = [c for c in _LATERAL if c in out] if allowed is not None else \
        [*required, *optional, *(c for c in out if c not in required and c not in optional)]
    return {c: out[c] for c in order}


def _target_unit(column: str, rig: Rig | None) -> str | None:
    """The SI unit of ``column`` (None: an extra column, converted to base SI units)."""
    if column in _SI:
        return _SI[column]
    if rig is not None and rig.spin is not None:
        for key, col in rig.spin.columns.items():
            if col == column:
                return _SPIN_UNITS[key]
    return None


def _unit_problem(unit: str, target: str | None) -> str | None:
    """Why ``unit`` cannot be converted to ``target`` (None: it can)."""
    import pint

    ureg = _registry()
    try:
        parsed = ureg.parse_units(unit)
        compatible = target is None or ureg.Quantity(1.0, parsed).is_compatible_with(target)
    except Exception as exc:  # noqa: BLE001 - pint's parser raises anything on odd text
        detail = str(exc).strip()
        reason = "not a unit pint knows" if isinstance(exc, pint.errors.UndefinedUnitError) \
            else "not a unit expression" + (f" ({detail})" if detail else "")
        expected = f"{_KIND[target]} unit such as {_EXAMPLE_UNITS[target]}" if target else \
            "a unit such as \"deg\" or \"V\""
        return f'unknown unit "{unit}": {reason} (expected {expected})'
    if not compatible:
        dims = ureg.get_dimensionality(parsed)
        return (f'unit "{unit}" ({dims}) is not {_KIND[target]} unit (expected one such as '
                f"{_EXAMPLE_UNITS[target]})")
    return None


def _to_si(values: np.ndarray, unit: str, target: str | None) -> np.ndarray:
    ureg = _registry()
    q = ureg.Quantity(values, ureg.parse_units(unit))
    q = q.to(target) if target is not None else q.to_base_units()
    return np.asarray(q.magnitude, dtype=float)


def _listing(names: list[str]) -> str:
    shown = ", ".join(f"`{n}`" for n in names[:_MAX_LISTED_CHANNELS])
    more = f" and {len(names) - _MAX_LISTED_CHANNELS} more" if len(names) > _MAX_LISTED_CHANNELS \
        else ""
    return shown + more if names else "none"


# ---------------------------------------------------------------------------------------------
# the formats: each returns the channels of the file by every name they can be looked up with


def read_lab(path: Path, toml_name: str, doc: Mapping[str, Any], excitation: str | None,
             rig_kind: str | None, rig: Rig | None, problems: list[str], *,
             uniform: bool = True, unitless: dict[str, str] | None = None,
             decimate: int = 1) -> tuple[Any, ...] | None:
    """Read the channels ``[data.columns]`` of the case document ``doc`` names from the lab
    file ``path``; append problems; return ``(time, displacement, force, columns)`` as
    :func:`estimate.data._csv.read_csv` does, or None (``uniform=False``: the time need not
    be uniform, ``[test] resample_hz``). ``unitless`` receives the columns read with no
    unit (neither ``[data.columns]`` nor the file gives one: read as SI), with their
    channels (:mod:`estimate.data.plausible_units` judges them)."""
    import contextlib

    name = path.name
    fmt = LAB_SUFFIXES[path.suffix.lower()]
    n_before = len(problems)
    specs = _columns_table(doc, toml_name, problems)
    wanted = _wanted(specs, rig_kind, excitation, rig, toml_name, problems) \
        if specs is not None else None
    if wanted is None:
        return None
    _require("pint", "pint", name)
    for spec in wanted.values():
        if spec.unit is not None:
            why = _unit_problem(spec.unit, _target_unit(spec.column, rig))
            if why:
                problems.append(f"{toml_name}: [data.columns] {spec.column}: {why}; for channel "
                                f"`{spec.channel}` of {name}")
    if len(problems) > n_before:
        return None
    with contextlib.ExitStack() as stack, captured_warnings("nptdms") as logged:
        try:
            channels, listing = _open(path, fmt, stack)
            if fmt == "MAT" and (damage := _mat5_damage(path)):
                raise ValueError(damage)
        except MissingDependency:
            raise
        except Exception as exc:  # each library raises its own errors on a damaged file
            problems.append(f"{name}: not a readable {fmt} file (damaged or of another format: "
                            f"{type(exc).__name__}: {exc})")
            return None
        try:
            out = _read_channels(name, fmt, wanted, channels, listing, rig_kind, rig, problems,
                                 n_before, uniform, unitless, decimate)
        except Exception as exc:  # noqa: BLE001 - a library failing inside a damaged file
            del problems[n_before:]
            problems.append(f"{name}: not a readable {fmt} file (damaged: reading its channels "
                            f"failed: {type(exc).__name__}: {exc})")
            return None
        if logged:  # npTDMS read past damage and said so: what it returned is not the record
            del problems[n_before:]
            problems.append(f"{name}: damaged {fmt} file ({logged[0].rstrip('.')}); it was cut "
                            "short or overwritten: copy it again from the acquisition system")
            return None
        return out


def _read_channels(name: str, fmt: str, wanted: dict[str, _Spec], channels: dict[str, _Channel],
                   listing: list[str], rig_kind: str | None, rig: Rig | None,
                   problems: list[str], n_before: int, uniform: bool = True,
                   unitless: dict[str, str] | None = None, decimate: int = 1
                   ) -> tuple[Any, ...] | None:
    def key(spec: _Spec) -> str:
        return (f"[data.columns] {spec.column}" if spec.explicit else
                f"column `{spec.column}`, looked up by name without [data.columns]")

    found: dict[str, _Channel] = {}
    time_from: _Channel | None = None
    for column, spec in wanted.items():
        ch = channels.get(spec.channel)
        if ch is not None:
            found[column] = ch
            continue
        if column == "time" and not spec.explicit and fmt == "TDMS":
            timed = next((channels[s.channel] for c, s in wanted.items() if c != "time"
                          and s.channel in channels and channels[s.channel].time_track), None)
            if timed is not None:
                time_from = timed
                continue
        if spec.optional:
            continue
        hint = (" or waveform timing (`wf_increment`) on the other channels" if column == "time"
                and fmt == "TDMS" else "")
        problems.append(f"{name}: channel `{spec.channel}` ({key(spec)}): not found{hint}; "
                        f"the file has {_listing(listing)}")
    if len(problems) > n_before:
        return None
    limit = max_samples() * decimate  # a decimated record keeps 1 in `decimate` samples
    for column, ch in found.items():
        spec = wanted[column]
        vector = len([d for d in ch.shape if d != 1]) <= 1
        if not ch.numeric or not vector:
            what = "numbers" if not ch.numeric else f"shape {ch.shape}"
            problems.append(f"{name}: channel `{ch.name}` ({key(spec)}): expected a vector of "
                            f"numbers, found {what}")
    largest = max(found.values(), key=lambda ch: ch.size)
    if len(problems) == n_before and largest.size > limit:  # one problem for the record
        problems.append(f"{name}: channel `{largest.name}`: {largest.size} samples; "
                        f"{decimation_hint(largest.size, decimate)}")
    if len(problems) > n_before:
        return None
    sizes = {column: ch.size for column, ch in found.items()}
    if len(set(sizes.values())) > 1:
        listed = ", ".join(f"`{found[c].name}` ({c}) {n}" for c, n in sizes.items())
        problems.append(f"{name}: channels: expected the same number of samples in every channel, "
                        f"found {listed}")
        return None

    values: dict[str, np.ndarray] = {}
    labels: dict[str, str] = {}
    for column, ch in found.items():
        spec = wanted[column]
        unit = spec.unit or ch.unit
        target = _target_unit(column, rig)
        read = np.asarray(ch.read())
        if np.iscomplexobj(read):
            problems.append(f"{name}: channel `{ch.name}` ({key(spec)}): expected real numbers, "
                            "found complex values (a spectrum or a demodulated signal, not a "
                            "record of the measured quantity)")
            continue
        raw = read.astype(float).reshape(-1)
        if unit is not None and spec.unit is None:  # the file's own unit: checked here
            why = _unit_problem(unit, target)
            if why:
                problems.append(f"{name}: channel `{ch.name}` ({key(spec)}): the file gives {why}; "
                                f"give the unit in [data.columns] (`{column} = {{ channel = "
                                f'"{spec.channel}", unit = "..." }}`)')
                continue
        values[column] = _to_si(raw, unit, target) if unit is not None else raw
        labels[column] = ch.name
        if unit is None and unitless is not None:
            unitless[column] = ch.name
    if time_from is not None:
        values["time"] = np.asarray(time_from.time_track(), dtype=float)
        labels["time"] = f"time track of {time_from.name}"
    if len(problems) > n_before:
        return None

    order = list(values)
    order.remove("time")
    order.insert(0, "time")
    data = np.column_stack([values[c] for c in order])
    check_samples(name, [labels[c] for c in order], data, problems, row=lambda i: i,
                  where=lambda rows: rows_text(rows, "index", "indices"), kind="channel",
                  quantities=order, uniform=uniform)
    if len(problems) > n_before:
        return None
    time = values["time"]
    if rig_kind == "spinning":
        return time, None, None, {c: v for c, v in values.items() if c != "time"}
    return time, values.get("displacement"), values["force"], {}

