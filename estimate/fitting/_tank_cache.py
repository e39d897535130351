"""Tank modal analyses kept on disk: the raw modes of a tank, depth and solver are computed
once (0.02-0.3 s each) and read back by every later fit, diagnosis or check of the same tank.

Entries live in the derivation cache folder under ``tank/``
(:func:`derive.cache.cache_folder`: read only while nobody but the user can change it or the
entry), keyed by the solver, the tank, the liquid depth, the number of modes and a hash of
the source of the ``analogs.tank`` package and the library versions; each holds a SHA-256 of
its content and is written to a temporary file then renamed. A missing, damaged or
unreadable entry, or one another user could have written, is computed anew (and rewritten);
a folder that cannot be written leaves the result uncached.
"""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["CachedSolver"]

_FIELDS = ("lam", "a", "b", "u_wall", "moment")


@functools.cache
def _source_digest() -> str:
    import analogs.tank
    from derive.cache import cache_key

    h = hashlib.sha256()
    for path in sorted(Path(analogs.tank.__file__).parent.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(f"numpy={np.__version__}".encode())
    return cache_key(f"tank-modes|{h.hexdigest()}")


def _checksum(data: dict) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


@dataclass(frozen=True)
class CachedSolver:
    """A tank modal solver (:class:`analogs.tank.Exact`, ``Ritz``, ...) whose results are
    kept on disk; ``predict(..., method=CachedSolver(Exact()))`` gives the same prediction."""

    solver: Any

    @property
    def name(self) -> str:
        return self.solver.name

    def _path(self, tank, depth: float, n_modes: int) -> Path:
        from derive.cache import cache_folder

        key = hashlib.sha256(f"{self.solver!r}|{tank!r}|{depth!r}|{n_modes}|"
                             f"{_source_digest()}".encode()).hexdigest()[:32]
        return cache_folder("tank") / f"{key}.json"

    def solve(self, tank, depth: float, n_modes: int):
        from analogs.tank._modes import RawModes
        from derive.cache import file_problem

        path = self._path(tank, depth, n_modes)
        try:
            if file_problem(path):  # written by someone else: computed anew below
                raise ValueError("not private")
            data = json.loads(path.read_text())
            if data.pop("sha256") == _checksum(data):
                return RawModes(**{k: np.asarray(data[k], float) for k in _FIELDS},
                                size=int(data["size"]))
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            pass  # absent or damaged: computed anew below
        raw = self.solver.solve(tank, depth, n_modes)
        data = {k: np.asarray(getattr(raw, k), float).tolist() for k in _FIELDS}
        data["size"] = int(raw.size)
        data["sha256"] = _checksum(data)
        _write(path, data)
        return raw


def _write(path: Path, data: dict) -> None:
    from derive.cache import write_atomic

    try:
        write_atomic(path, json.dumps(data))
    except OSError:
        pass  # a cache that cannot be written only costs time
