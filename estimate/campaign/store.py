"""The campaign's result store: one JSON file per task, named by a key of its inputs.

A key is the SHA-256 of what determines a result: the task (fit or diagnosis), the bytes of
every case file and data file (by their SHA-256, in fitting order), the model specification,
the options and the package version. File names and folders are not part of it, so a
campaign folder can be moved or copied without refitting. A rerun finds the results whose
inputs have not changed and computes the others.

Entries are written to a hidden temporary file in the store folder and renamed into place,
so a reader never sees a partial entry; an interrupted run leaves at most hidden ``.tmp``
files, which are ignored. An entry that cannot be read is computed again.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["STORE_SCHEMA", "Store", "package_version", "task_key", "write_atomic"]

#: Version of the key and entry layout; raising it invalidates every stored result.
STORE_SCHEMA = 1


def package_version() -> str:
    """The installed version of slosh-analogs ("unknown" when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("slosh-analogs")
    except PackageNotFoundError:  # pragma: no cover - running from an uninstalled checkout
        return "unknown"


def task_key(task: str, files: Sequence[tuple[str | None, str | None]], model: str | None,
             options: Mapping[str, Any]) -> str:
    """The store key of a task: hex SHA-256 of its inputs.

    Parameters
    ----------
    task : str
        ``"fit"`` or ``"diagnosis"``.
    files : sequence of (str or None, str or None)
        Per case, in fitting order: SHA-256 of the case file and of its data file.
    model : str or None
        Model specification (None when the task chooses its own, as the diagnosis does).
    options : mapping
        Options that change the result (e.g. ``{"input": "estimated"}``); JSON values.
    """
    doc = {"schema": STORE_SCHEMA, "version": package_version(), "task": task,
           "files": [list(f) for f in files], "model": model, "options": dict(options)}
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def write_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` through a hidden temporary file in the same folder and a
    rename: readers see the old file or the new one, never a part."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


class Store:
    """Results by key in ``folder`` (created when missing).

    Examples
    --------
    >>> store = Store("campaign_out/store")                    # doctest: +SKIP
    >>> store.put(key, {"status": "ok"}); store.get(key)        # doctest: +SKIP
    {'status': 'ok'}
    """

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)

    def _path(self, key: str) -> Path:
        return self.folder / f"{key}.json"

    def get(self, key: str) -> dict[str, Any] | None:
        """The stored outcome of ``key``, or None (absent or unreadable: recompute)."""
        path = self._path(key)
        if not path.is_file():
            return None
        try:
            entry = json.loads(path.read_text())
            if entry.get("key") != key:
                raise ValueError("the entry names another key")
            return entry["outcome"]
        except (OSError, ValueError, KeyError, TypeError) as err:
            warnings.warn(f"campaign store entry {path} is damaged ({err}); computing it again",
                          RuntimeWarning, stacklevel=2)
            return None

    def put(self, key: str, outcome: Mapping[str, Any], *, seconds: float = 0.0) -> Path:
        """Store ``outcome`` (JSON values; floats round-trip exactly) under ``key``;
        ``seconds`` is kept beside it for timing, not for results."""
        entry = {"key": key, "schema": STORE_SCHEMA, "seconds": seconds, "outcome": outcome}
        return write_atomic(self._path(key), json.dumps(entry, indent=1, allow_nan=True).encode())

    def seconds(self, key: str) -> float | None:
        """How long the stored task took (s), or None."""
        try:
            return float(json.loads(self._path(key).read_text())["seconds"])
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def keys(self) -> set[str]:
        return {p.stem for p in self.folder.glob("*.json") if not p.name.startswith(".")}
