"""On-disk cache of derived models, keyed by everything that can change the equations.

A key holds the model's structure (component classes with the source of their MRO and
modules, names, options; :meth:`analogs.Model.structure_key`), the source of the derivation
code (every module of the ``analogs`` and ``derive`` packages), the package version and the
SymPy and CasADi versions. A model whose source cannot be read is derived without the cache.

Entries are JSON files holding serialized CasADi functions, metadata and a SHA-256 of both;
a truncated, empty or altered entry fails the check and is rebuilt. Entries are written to a
temporary file in the cache folder and renamed into place, so concurrent writers never leave
a half-written entry, and a process about to derive or compile what another is deriving
waits for it on a lock file (:func:`building`) and loads its result instead of repeating
minutes of SymPy. A cache hit imports no SymPy. The folder is ``$SLOSH_CACHE_DIR`` or
``~/.cache/slosh-analogs``, created private to the user (mode 0700). It is used only while
it, every folder below it on the way to an entry, and the entry itself belong to the user
and nobody else can write to them (symlinks resolved; :mod:`derive._trust`); otherwise the
command says so once and caches in a private temporary folder for the run.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import tempfile
import warnings
from importlib import metadata
from pathlib import Path

import casadi as ca

from ._trust import UntrustedCache, file_problem, folder_problem, private_folder

__all__ = ["UntrustedCache", "building", "write_atomic", "cache_dir", "cache_key", "cache_folder",
           "configured_dir", "ensure_private_dir", "file_problem", "load", "store"]

_FUNCTIONS = ("rhs", "outputs", "mass_matrix", "forcing")


def configured_dir() -> Path:
    """The configured cache folder: ``$SLOSH_CACHE_DIR`` or ``~/.cache/slosh-analogs``."""
    env = os.environ.get("SLOSH_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "slosh-analogs"


def cache_folder(*parts: str) -> Path:
    """The sub-folder ``parts`` of the cache in use, created private to the user: of
    :func:`configured_dir` when it and everything on the way is private to the user, else
    of a private temporary folder of this process (with one :class:`UntrustedCache`
    warning)."""
    return private_folder(configured_dir(), *parts)


def cache_dir() -> Path:
    """The cache folder in use (see :func:`cache_folder`)."""
    return cache_folder()


def ensure_private_dir(folder: Path) -> Path:
    """Create ``folder`` (mode 0700) if needed and check that nobody else can change it or
    a folder above it.

    Raises ``PermissionError`` naming the folder that is not private: native code and
    serialized functions are loaded from it."""
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    why = folder_problem(folder)
    if why:
        raise PermissionError(f"the derivation cache folder {folder} cannot be trusted: {why}; "
                              f"run `chmod go-w {folder}` or set SLOSH_CACHE_DIR to a private "
                              "folder")
    return folder


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "unknown"


@functools.cache
def _code_digest() -> str:
    """Hash of every module of the ``analogs`` and ``derive`` packages (the declaration API,
    Lagrange's method, the CasADi translation) and of the versions that shape the result."""
    import analogs

    h = hashlib.sha256()
    for package in (Path(analogs.__file__).parent, Path(__file__).parent):
        for path in sorted(package.glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    for dist in ("slosh-analogs", "sympy"):
        h.update(f"{dist}={_version(dist)}".encode())
    h.update(f"casadi={ca.__version__}".encode())
    return h.hexdigest()


def cache_key(structure_key: str) -> str:
    """Key of a model structure for this derivation code and these library versions."""
    text = f"{structure_key}|code={_code_digest()}"
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _checksum(meta: dict, functions: dict[str, str]) -> str:
    text = json.dumps({"meta": meta, "functions": functions}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def load(key: str) -> tuple[dict[str, ca.Function], dict] | None:
    """Functions and metadata stored under ``key``, or ``None`` when there is no entry or it
    fails its checksum (the caller then derives anew and overwrites it)."""
    path = cache_dir() / f"{key}.json"
    if not path.exists():
        return None
    why = file_problem(path)
    if why:
        warnings.warn(f"derivation cache entry not read: {why}; deriving anew", UntrustedCache,
                      stacklevel=3)
        return None
    try:
        data = json.loads(path.read_text())
        if data.get("sha256") != _checksum(data["meta"], data["functions"]):
            raise ValueError("checksum mismatch")
        fns = {name: ca.Function.deserialize(data["functions"][name]) for name in _FUNCTIONS}
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RuntimeError) as err:
        warnings.warn(f"derivation cache entry {path} is damaged ({err}); deriving anew",
                      RuntimeWarning, stacklevel=3)
        return None
    return fns, data["meta"]


def write_atomic(path: str | os.PathLike[str], data: bytes | str, *,
                 mode: int | None = None) -> Path:
    """Write ``data`` to ``path`` through a hidden temporary file in the same folder, synced
    and then renamed: readers see the old file or the new one, never a part, and a failure
    or an interrupt leaves the old file and no temporary one. The project's one such writer
    (:func:`estimate.outputs.write_atomic` gives it the outputs' mode).

    Parameters
    ----------
    path : path-like
        The file to write; its folder must exist.
    data : bytes or str
        The content (``str`` is written as UTF-8).
    mode : int, optional
        Permission bits of the new file. Default: the temporary file's, 0600 (private, as
        the cache's entries are).

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_atomic(pathlib.Path(tempfile.mkdtemp()) / "a.txt", "done")
    >>> p.read_text()
    'done'
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data.encode() if isinstance(data, str) else data)
            fh.flush()
            os.fsync(fh.fileno())
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


@contextlib.contextmanager
def building(path: str | os.PathLike[str]):
    """Hold an exclusive lock on ``path`` + ``.lock`` while the block builds ``path``: a
    second process building the same entry (two test workers, a campaign's workers)
    waits, then finds it built. Without ``fcntl`` (Windows) there is no lock and both
    build; the atomic writes keep the entry whole either way."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    lock = Path(f"{os.fspath(path)}.lock")
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing releases the lock


def store(key: str, functions: dict[str, ca.Function], meta: dict) -> Path:
    """Write functions and metadata atomically; return the file path."""
    serialized = {n: functions[n].serialize() for n in _FUNCTIONS}
    data = {"meta": meta, "functions": serialized, "sha256": _checksum(meta, serialized)}
    return write_atomic(cache_dir() / f"{key}.json", json.dumps(data))
