"""Opening the files test labs write (LabVIEW TDMS, MATLAB ``.mat`` v4-v7 and v7.3, HDF5):
their channels by name, each with its size, declared unit and a reader
(:mod:`estimate.data.lab_formats` maps and converts them). npTDMS and h5py are optional
(the ``lab`` extra)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import MissingDependency

from ..inputs import open_input
from ._lab_damage import mat5_damage

_INSTALL = "`python3 -m pip install '.[lab]'` (from a checkout) or " \
           "`python3 -m pip install 'slosh-analogs[lab]'`"



def _require(module: str, package: str, fname: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingDependency(f"{fname}: reading this file needs {package}, an optional "
                                f"dependency: {_INSTALL}") from err


@dataclass
class _Channel:
    """A channel found in the file: its full name, sample count, dtype, declared unit, and
    how to read it."""

    name: str
    size: int
    shape: tuple[int, ...]
    numeric: bool
    unit: str | None
    read: Callable[[], np.ndarray]
    time_track: Callable[[], np.ndarray] | None = None


def _decode(value: Any) -> str | None:
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return _decode(value.item())
    return value.strip() or None if isinstance(value, str) else None


def _tdms_channels(path: Path, stack) -> tuple[dict[str, _Channel], list[str]]:
    nptdms = _require("nptdms", "npTDMS", path.name)
    with open_input(path, "a TDMS file") as fh:
        lead_in = fh.read(4)
    if lead_in != b"TDSm":  # npTDMS reads a file without it as one without channels
        raise ValueError(f"expected a TDMS lead-in `TDSm`, found {lead_in!r}")
    tdms = stack.enter_context(nptdms.TdmsFile.open(path))
    found: dict[str, _Channel] = {}
    names: list[str] = []
    by_short: dict[str, list[_Channel]] = {}
    for group in tdms.groups():
        for ch in group.channels():
            full = f"{group.name}/{ch.name}"
            names.append(full)
            dtype = getattr(ch, "dtype", None)
            numeric = dtype is not None and np.issubdtype(dtype, np.number)
            props = ch.properties
            timed = "wf_increment" in props
            entry = _Channel(full, len(ch), (len(ch),), numeric, _decode(props.get("unit_string")),
                             read=functools.partial(lambda c: np.asarray(c[:]), ch),
                             time_track=functools.partial(lambda c: c.time_track(), ch)
                             if timed else None)
            found[full] = entry
            by_short.setdefault(ch.name, []).append(entry)
    for short, entries in by_short.items():
        if short not in found and len(entries) == 1:
            found[short] = entries[0]
    return found, names


def _h5_channels(path: Path, stack, *, mat: bool) -> tuple[dict[str, _Channel], list[str]]:
    h5py = _require("h5py", "h5py", path.name)
    f = stack.enter_context(h5py.File(path, "r"))
    found: dict[str, _Channel] = {}
    names: list[str] = []

    def visit(name: str, obj) -> None:
        if not isinstance(obj, h5py.Dataset) or name.startswith("#"):  # MATLAB's #refs#
            return
        names.append(name)
        cls = _decode(obj.attrs.get("MATLAB_class")) if mat else None
        numeric = np.issubdtype(obj.dtype, np.number) and cls not in ("char", "logical", "cell")
        unit = _decode(obj.attrs.get("unit", obj.attrs.get("units")))
        found[name] = _Channel(name, int(obj.size), tuple(obj.shape), numeric, unit,
                               read=functools.partial(lambda d: d[()], obj))

    f.visititems(visit)
    for name in list(found):
        found.setdefault("/" + name, found[name])
    return found, names


def _mat_channels(path: Path, stack) -> tuple[dict[str, _Channel], list[str]]:
    import scipy.io
    from scipy.io.matlab import matfile_version

    with open_input(path, "a MAT file") as fh:
        major, _ = matfile_version(fh)
    if major == 2:  # v7.3: HDF5 with a MATLAB header
        return _h5_channels(path, stack, mat=True)
    found: dict[str, _Channel] = {}
    names: list[str] = []
    for name, shape, cls in scipy.io.whosmat(path):
        names.append(name)
        numeric = cls in ("double", "single", "int8", "int16", "int32", "int64", "uint8",
                          "uint16", "uint32", "uint64")

        def read(name: str = name) -> np.ndarray:
            return scipy.io.loadmat(path, variable_names=[name])[name]

        found[name] = _Channel(name, int(np.prod(shape)), tuple(shape), numeric, None, read)
    return found, names


def _open(path: Path, fmt: str, stack) -> tuple[dict[str, _Channel], list[str]]:
    if fmt == "TDMS":
        return _tdms_channels(path, stack)
    if fmt == "MAT":
        return _mat_channels(path, stack)
    return _h5_channels(path, stack, mat=False)


# ---------------------------------------------------------------------------------------------


def _mat5_damage(path: Path) -> str | None:
    """Where a MAT v5 file (not v4, not the HDF5-based v7.3) ends inside a data element."""
    from scipy.io.matlab import matfile_version

    with open_input(path, "a MAT file") as fh:
        major, _ = matfile_version(fh)
    return mat5_damage(path) if major == 1 else None
