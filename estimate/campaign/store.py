"""The campaign's result store: one JSON file per task, named by a key of its inputs.

A key is the SHA-256 of what determines a result: the task (fit or diagnosis), the bytes of
every case file and data file (by their SHA-256, in fitting order), the model specification,
the options and the package version. File names and folders are not part of it, so a
campaign folder can be moved or copied without refitting. A rerun finds the results whose
inputs have not changed and computes the others.

Entries are written to a hidden temporary file in the store folder and renamed into place,
so a reader never sees a partial entry; an interrupted run leaves at most hidden ``.tmp``
files, which are ignored. Each entry holds the SHA-256 of its outcome, and is read as any
input is (a regular file within :data:`MAX_ENTRY_BYTES`, :func:`estimate.inputs.load_json`):
an entry that cannot be read, is not a JSON object of this layout, names another key, fails
its checksum (an edited value) or fails the caller's check of the outcome is computed again,
with a warning naming the file and what is wrong.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from analogs.errors import InputError

from ..inputs import load_json
from ..outputs import write_atomic
from ..version import package_version

__all__ = ["MAX_ENTRY_BYTES", "STORE_SCHEMA", "Store", "outcome_checksum", "package_version",
           "task_key", "write_atomic"]

#: Version of the key and entry layout; raising it invalidates every stored result.
STORE_SCHEMA = 2
#: Largest store entry read [bytes] (an outcome is a few kilobytes).
MAX_ENTRY_BYTES = 16 * 2**20


def outcome_checksum(outcome: Mapping[str, Any]) -> str:
    """SHA-256 of an outcome's canonical JSON (sorted keys; NaN written as ``NaN``)."""
    text = json.dumps(outcome, sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()


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

    def _entry(self, key: str) -> dict[str, Any]:
        """The entry of ``key`` checked for layout, key and checksum; raises ValueError (or
        InputError, OSError) saying what is wrong."""
        entry = load_json(self._path(key), "a campaign store entry", limit=MAX_ENTRY_BYTES)
        if not isinstance(entry, dict):
            raise ValueError(f"expected a JSON object, found {type(entry).__name__}")
        if entry.get("key") != key:
            raise ValueError("the entry names another key")
        if entry.get("schema") != STORE_SCHEMA:
            raise ValueError(f"layout {entry.get('schema')!r}, expected {STORE_SCHEMA}")
        outcome = entry.get("outcome")
        if not isinstance(outcome, dict) or not outcome:
            raise ValueError(f"expected an outcome object, found {outcome!r}"[:200])
        if entry.get("sha256") != outcome_checksum(outcome):
            raise ValueError("the outcome does not match its checksum (edited or damaged)")
        return entry

    def get(self, key: str, check: Callable[[dict[str, Any]], str | None] | None = None
            ) -> dict[str, Any] | None:
        """The stored outcome of ``key``, or None (absent, or damaged: recompute).

        ``check(outcome)`` says what is wrong with an outcome that passed its checksum (None:
        nothing); a damaged entry is reported with a :class:`RuntimeWarning` naming it."""
        path = self._path(key)
        if not path.exists() and not path.is_symlink():
            return None
        try:
            outcome = self._entry(key)["outcome"]
            why = check(outcome) if check is not None else None
            if why:
                raise ValueError(why)
            return outcome
        except (OSError, ValueError, InputError) as err:
            warnings.warn(f"campaign store entry {path} is damaged ({err}); computing it again",
                          RuntimeWarning, stacklevel=2)
            return None

    def put(self, key: str, outcome: Mapping[str, Any], *, seconds: float = 0.0) -> Path:
        """Store ``outcome`` (JSON values; floats round-trip exactly) under ``key`` with its
        checksum; ``seconds`` is kept beside it for timing, not for results."""
        entry = {"key": key, "schema": STORE_SCHEMA, "seconds": seconds, "outcome": outcome,
                 "sha256": outcome_checksum(outcome)}
        return write_atomic(self._path(key), json.dumps(entry, indent=1, allow_nan=True).encode())

    def seconds(self, key: str) -> float | None:
        """How long the task stored under ``key`` took (s), or None."""
        try:
            return float(self._entry(key)["seconds"])
        except (OSError, ValueError, KeyError, TypeError, InputError):
            return None

    def keys(self) -> set[str]:
        return {p.stem for p in self.folder.glob("*.json") if not p.name.startswith(".")}
