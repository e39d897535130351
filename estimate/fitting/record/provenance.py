"""Where a fit record comes from: the package and solver versions, the date, every case and
data file with its SHA-256, the command's options and the model specification as given."""

from __future__ import annotations

import datetime
import functools
import hashlib
import platform
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ...version import package_version

__all__ = ["file_sha256", "provenance", "versions"]

_CHUNK = 1 << 20


def file_sha256(path: str | Path) -> str | None:
    """Hex SHA-256 of the bytes of ``path``, or None when it cannot be read."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(_CHUNK):
                h.update(chunk)
    except OSError:
        return None
    return h.hexdigest()


@functools.cache
def _ipopt_version() -> str | None:
    """IPOPT's version as CasADi loads it: ``GetIpoptVersion`` of the library beside CasADi
    (IPOPT >= 3.14), else the version in the library's file name; None when not found."""
    import ctypes

    import casadi

    folder = Path(casadi.__file__).parent
    libs = sorted(p for pattern in ("libipopt.so*", "libipopt*.dylib", "*ipopt*.dll")
                  for p in folder.glob(pattern) if "sipopt" not in p.name)
    for lib in libs:
        try:
            handle = ctypes.CDLL(str(lib))
            numbers = [ctypes.c_int() for _ in range(3)]
            handle.GetIpoptVersion(*(ctypes.byref(n) for n in numbers))
            return ".".join(str(n.value) for n in numbers)
        except (OSError, AttributeError):
            continue
    for lib in libs:  # libipopt.so.3.14.19
        parts = lib.name.split(".so.")[-1].split(".")
        if len(parts) == 3 and all(p.isdigit() for p in parts):
            return ".".join(parts)
    return None


@functools.cache
def versions() -> dict[str, str | None]:
    """Versions of everything that can change a fit's numbers: this package, Python, NumPy,
    SciPy, SymPy, CasADi and the IPOPT it loads, and the platform."""
    from importlib.metadata import PackageNotFoundError, version

    def of(name: str) -> str | None:
        try:
            return version(name)
        except PackageNotFoundError:
            return None

    return {"slosh-analogs": package_version(), "python": platform.python_version(),
            "numpy": of("numpy"), "scipy": of("scipy"), "sympy": of("sympy"),
            "casadi": of("casadi"), "ipopt": _ipopt_version(),
            "platform": platform.platform()}


def _json_value(value: Any) -> Any:
    """An option's value as JSON holds it (paths and other objects as text)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    return str(value)


def provenance(cases: Sequence[Any], *, options: Mapping[str, Any] | None = None,
               model_spec: str | None = None, command: str | None = None) -> dict[str, Any]:
    """The provenance block of a fit record.

    Parameters
    ----------
    cases : sequence of Case
        The fitted cases (:class:`estimate.data.Case`), in fitting order: each case file and
        data file is named with its SHA-256 (null when it can no longer be read).
    options : mapping, optional
        The options of the command that made the fit (``--input``, ``--cost``, ...), by
        name; values that are not JSON numbers, strings or lists are written as text.
    model_spec : str, optional
        The model specification as the user gave it (``None``: the default model).
    command : str, optional
        The command that made the fit (``"slosh fit"``); None for a fit made in Python.

    Examples
    --------
    >>> block = provenance([], options={"input": "estimated"})
    >>> sorted(block)
    ['command', 'created_utc', 'files', 'model_spec_given', 'options', 'versions']
    """
    now = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
    files = [{"id": c.test.id, "case_file": str(c.path), "case_sha256": file_sha256(c.path),
              "data_file": str(c.data_path), "data_sha256": file_sha256(c.data_path)}
             for c in cases]
    return {"created_utc": now.isoformat().replace("+00:00", "Z"),
            "versions": dict(versions()), "command": command,
            "options": {str(k): _json_value(v) for k, v in (options or {}).items()},
            "model_spec_given": model_spec, "files": files}
