"""Output files written as one transaction, and strict JSON.

A command declares all its outputs first (:class:`Outputs`), checks them before it computes
(the folder exists and is writable, a file is not a folder, nothing existing is replaced
without ``overwrite``, no output is also an input), writes each to a temporary name in the
folder it will end up in, and renames them all into place only when every one is complete.
A failure or an interrupt (:mod:`estimate.interrupts`) on the way removes the temporary
files; the previous outputs are left byte for byte.

Examples
--------
>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> out = Outputs(overwrite=False).file("--json", folder / "fit.json")
>>> out.check()
>>> with out.writing() as paths:
...     _ = paths["--json"].write_text(json_text({"rms": float("nan")}))
>>> (folder / "fit.json").read_text()
'{\\n  "rms": null,\\n  "non_finite": {\\n    "/rms": "NaN"\\n  }\\n}\\n'
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analogs.errors import InputError

from .inputs import file_kind
from .interrupts import deferred, temporary

__all__ = ["NON_FINITE_KEY", "OutputError", "Outputs", "committed", "json_text", "output_mode",
           "write_atomic"]

#: Key of the note that lists the values written as ``null`` because they were not finite.
NON_FINITE_KEY = "non_finite"


#: Outputs renamed into place since the command line cleared the list (it does so when a
#: command starts): a signal after that does not undo them.
committed: list[Path] = []


class OutputError(InputError):
    """An output path cannot be written (missing or read-only folder, a folder where a file
    is expected, an existing file without ``--overwrite``), or writing failed."""


@dataclass(frozen=True)
class _Item:
    option: str
    path: Path
    names: tuple[str, ...] | None  # None: one file; else a folder that receives these files
    new_folder: bool = False       # a file whose folder is created when missing


def _umask() -> int:
    """The process's umask, read without changing it where the system says it (Linux
    ``/proc/self/status``: no window in which another thread creates files under umask 0)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0)
    os.umask(mask)
    return mask


def output_mode(*, folder: bool = False) -> int:
    """The permission bits of a new output file (``0o666``) or folder (``0o777``) under the
    process's umask, as ``open`` and ``mkdir`` would give them: a temporary file made by
    :mod:`tempfile` is private (0600, 0700) and gets these before it is renamed into place.

    Examples
    --------
    >>> import os
    >>> old = os.umask(0o022); oct(output_mode()), oct(output_mode(folder=True))
    ('0o644', '0o755')
    >>> _ = os.umask(old)
    """
    return (0o777 if folder else 0o666) & ~_umask()


def write_atomic(path: str | os.PathLike[str], data: bytes | str) -> Path:
    """Write one file outside an :class:`Outputs` transaction (a store entry, a manifest):
    through a temporary file and a rename (:func:`derive.cache.write_atomic`), readers see
    the old file or the new one, never a part; the file gets the mode of any other output
    (:func:`output_mode`: 0644 under umask 022), not the temporary file's 0600.

    Parameters
    ----------
    path : path-like
        The file to write; its folder must exist.
    data : bytes or str
        The content (``str`` as UTF-8).

    Returns
    -------
    Path
        ``path``.
    """
    from derive.cache import write_atomic as write

    return write(path, data, mode=output_mode())


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


class Outputs:
    """The output files and folders of one command.

    Parameters
    ----------
    overwrite : bool
        Whether existing outputs may be replaced (``--overwrite``).
    inputs : iterable of paths, optional
        The command's input files: no output may be one of them.
    """

    def __init__(self, *, overwrite: bool, inputs: Iterable[str | os.PathLike] = ()) -> None:
        self.overwrite = overwrite
        self.inputs = tuple(Path(p) for p in inputs if p)
        self._items: list[_Item] = []

    def file(self, option: str, path: str | os.PathLike | None, *,
             new_folder: bool = False) -> "Outputs":
        """Add the file ``path`` written for ``option`` (skipped when None or empty);
        ``new_folder``: its folder is created when missing (its parent must exist)."""
        if path:
            self._items.append(_Item(option, Path(path), None, new_folder))
        return self

    def folder(self, option: str, path: str | os.PathLike | None,
               names: Iterable[str]) -> "Outputs":
        """Add the folder ``path`` (created when missing) that receives the files ``names``;
        other files in it are left alone."""
        if path:
            self._items.append(_Item(option, Path(path), tuple(names)))
        return self

    def _finals(self, item: _Item) -> list[Path]:
        return [item.path] if item.names is None else [item.path / n for n in item.names]

    def check(self) -> None:
        """Raise :class:`OutputError` listing every output that cannot be written."""
        problems, existing = [], []
        for it in self._items:
            where = f"{it.option} {it.path}"
            if it.names is None:
                folder = it.path.parent
                if it.new_folder and not folder.exists():
                    folder = folder.parent
            else:
                folder = it.path if it.path.is_dir() else it.path.parent
                if it.path.exists() and not it.path.is_dir():
                    problems.append(f"{where}: is a file; expected a folder")
                    continue
            if not folder.is_dir():
                problems.append(f"{where}: folder {folder} "
                                + ("is not a folder" if folder.exists() else "does not exist"))
                continue
            if not os.access(folder, os.W_OK | os.X_OK):
                problems.append(f"{where}: folder {folder} is not writable")
                continue
            if it.names is None and it.path.is_dir():
                problems.append(f"{where}: is a folder; expected a file name")
                continue
            special = [(p, kind) for p in self._finals(it) if (kind := _special(p))]
            if special:
                problems += [f"{it.option} {p}: is {kind}; expected a regular file (an output "
                             "is renamed into place, which would replace it)" for p, kind in special]
                continue
            existing += [str(p) for p in self._finals(it) if p.exists() or p.is_symlink()]
        seen: dict[Path, str] = {}
        for it in self._items:
            for p in self._finals(it):
                key = p.resolve()
                if key in seen:
                    problems.append(f"{seen[key]} and {it.option} both write {p}")
                seen.setdefault(key, it.option)
        for p in self.inputs:
            if p.resolve() in seen:
                problems.append(f"{seen[p.resolve()]} {p}: is an input of the command")
        if existing and not self.overwrite:
            problems.append(f"{', '.join(existing)} exist(s); pass --overwrite to replace")
        if problems:
            raise OutputError("; ".join(problems))

    @contextmanager
    def writing(self) -> Iterator[dict[str, Path]]:
        """Temporary paths to write, by option (a file, or an empty folder for
        :meth:`folder` outputs); renamed into place when the block ends without an
        exception, removed otherwise. OS errors become :class:`OutputError`."""
        created: list[Path] = []
        temps: dict[str, Path] = {}
        try:
            for it in self._items:
                if it.names is None:
                    folder = it.path.parent
                    if it.new_folder and not folder.exists():
                        folder.mkdir()
                        created.append(folder)
                    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{it.path.name}.",
                                               suffix=f".partial{it.path.suffix}")
                    os.close(fd)
                    temps[it.option] = Path(tmp)
                else:
                    parent = it.path if it.path.is_dir() else it.path.parent
                    temps[it.option] = Path(tempfile.mkdtemp(dir=parent,
                                                             prefix=f".{it.path.name}.",
                                                             suffix=".partial"))
            with temporary([*temps.values(), *created]):
                yield dict(temps)
                self._commit(temps)
        except OSError as err:
            raise OutputError(self._failure(err)) from None
        finally:
            for tmp in temps.values():
                _remove(tmp)
            for folder in reversed(created):
                if folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()

    def _failure(self, err: OSError) -> str:
        what = err.strerror or str(err)
        what = what[:1].lower() + what[1:]
        names = ", ".join(f"{it.option} {it.path}" for it in self._items)
        return f"could not write {names}: {what}; nothing was written, existing files unchanged"

    def _moves(self, temps: Mapping[str, Path]) -> list[tuple[Path, Path]]:
        moves = []
        for it in self._items:
            tmp = temps[it.option]
            if it.names is None:
                moves.append((tmp, it.path))
            elif not it.path.exists():
                moves.append((tmp, it.path))
            else:
                moves += [(f, it.path / f.name) for f in sorted(tmp.iterdir())]
        special = [f"{final} is {kind}" for _, final in moves if (kind := _special(final))]
        if special:  # appeared since the check
            raise OutputError(f"{'; '.join(special)}; expected a regular file")
        unexpected = [str(final) for _, final in moves if final.exists() and not self.overwrite]
        if unexpected:
            raise OutputError(f"{', '.join(unexpected)} exist(s); pass --overwrite to replace")
        return moves

    def _commit(self, temps: Mapping[str, Path]) -> None:
        moves = self._moves(temps)
        backups: list[tuple[Path, Path]] = []
        done: list[Path] = []
        with deferred():  # all renames happen, or none
            try:
                for tmp, final in moves:
                    mode = output_mode(folder=tmp.is_dir())
                    if final.exists() or final.is_symlink():
                        mode = final.stat().st_mode & 0o7777 if final.exists() else mode
                        backup = _placeholder(final, tmp.is_dir())
                        os.replace(final, backup)
                        backups.append((backup, final))
                    os.chmod(tmp, mode)
                    os.replace(tmp, final)
                    done.append(final)
            except BaseException:
                for final in done:
                    _remove(final)
                for backup, final in backups:
                    os.replace(backup, final)
                raise
            committed.extend(final for _, final in moves)
        for backup, _ in backups:
            _remove(backup)


def _special(path: Path) -> str | None:
    """What an existing output target is when it is neither a regular file nor a folder
    (a device such as ``/dev/full``, a pipe, a socket), else None."""
    kind = file_kind(path)
    return None if kind in (None, "a folder") else kind


def _placeholder(final: Path, folder: bool) -> Path:
    """A fresh name next to ``final`` to move the previous output to until the commit ends."""
    if folder:
        return Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.", suffix=".old"))
    fd, name = tempfile.mkstemp(dir=final.parent, prefix=f".{final.name}.", suffix=".old")
    os.close(fd)
    return Path(name)


def _finite(value: Any, pointer: str, found: dict[str, str]) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _finite(v, f"{pointer}/{_escape(str(k))}", found) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_finite(v, f"{pointer}/{i}", found) for i, v in enumerate(value)]
    if isinstance(value, (np.bool_, np.integer, np.floating)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        found[pointer] = "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
        return None
    return value


def _escape(key: str) -> str:
    return key.replace("~", "~0").replace("/", "~1")


def json_text(data: Mapping[str, Any], *, indent: int | None = 2) -> str:
    """``data`` as strict JSON (RFC 8259, ``allow_nan=False``), ending in a newline.

    NumPy scalars and arrays become numbers and lists. NaN and +/-inf, which strict parsers
    reject, become ``null`` and are listed under :data:`NON_FINITE_KEY` as JSON pointers
    (RFC 6901) with what they were: ``{"/findings/0/rms_after": "NaN"}``.
    """
    found: dict[str, str] = {}
    out = _finite(data, "", found)
    if found:
        out[NON_FINITE_KEY] = found
    return json.dumps(out, indent=indent, allow_nan=False) + "\n"
