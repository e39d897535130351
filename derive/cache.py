"""On-disk cache of derived models, keyed by a hash of the declaration.

A cache hit loads serialized CasADi functions and metadata and imports no SymPy.
The folder is ``$SLOSH_CACHE_DIR`` or ``~/.cache/slosh-analogs``.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import casadi as ca

__all__ = ["cache_dir", "cache_key", "load", "store"]

#: Bump when the derivation changes in a way the declaration hash cannot see.
_FORMAT = 1
_FUNCTIONS = ("rhs", "outputs", "mass_matrix", "forcing")


def cache_dir() -> Path:
    """The cache folder (created on first store)."""
    env = os.environ.get("SLOSH_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "slosh-analogs"


def cache_key(structure_key: str) -> str:
    """Key of a model structure for this derivation format and CasADi version."""
    text = f"{structure_key}|format={_FORMAT}|casadi={ca.__version__}"
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def load(key: str) -> tuple[dict[str, ca.Function], dict] | None:
    """Functions and metadata stored under ``key``, or ``None``."""
    path = cache_dir() / f"{key}.json"
    try:
        data = json.loads(path.read_text())
        fns = {name: ca.Function.deserialize(data["functions"][name]) for name in _FUNCTIONS}
    except (OSError, ValueError, KeyError, RuntimeError):
        return None
    return fns, data["meta"]


def store(key: str, functions: dict[str, ca.Function], meta: dict) -> Path:
    """Write functions and metadata atomically; return the file path."""
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    data = {"meta": meta, "functions": {n: functions[n].serialize() for n in _FUNCTIONS}}
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        json.dump(data, fh)
    path = folder / f"{key}.json"
    os.replace(tmp, path)
    return path
