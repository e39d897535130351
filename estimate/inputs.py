"""Input files opened as what they claim to be, read within a size bound, parsed within a
nesting bound.

Every file a command reads (case files, data files, fit and parameter files, campaign files,
store entries) is checked to be a regular file before it is read: a folder, a named pipe
(FIFO), a device (``/dev/zero``) or a socket gives a one-line :class:`~analogs.errors.InputError`
naming the file and what it is, and nothing blocks - files are opened with ``O_NONBLOCK`` and
checked again on the open descriptor, so a pipe swapped in after the check is refused too.
Reads stop at a stated bound. JSON and TOML documents nested deeper than
:data:`MAX_NESTING` arrays or tables are refused before the parser sees them (the parsers
recurse, and a 50,000-deep document would end in a ``RecursionError``).

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "x.json"
>>> _ = p.write_text('{"a": [1, 2]}')
>>> load_json(p, "parameter file")
{'a': [1, 2]}
"""

from __future__ import annotations

import json
import os
import stat
import tomllib
from pathlib import Path
from typing import Any, BinaryIO

from analogs.errors import InputError

__all__ = ["MAX_JSON_BYTES", "MAX_NESTING", "file_kind", "load_json", "load_toml",
           "nesting_problem", "open_input", "read_input"]

#: Deepest nesting of arrays and tables (objects) accepted in a TOML or JSON input; the
#: files of this project nest at most 5 levels.
MAX_NESTING = 64
#: Largest JSON input read (fit results, parameter maps, store entries) [bytes].
MAX_JSON_BYTES = 64 * 2**20

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def _kind_of(mode: int) -> str | None:
    if stat.S_ISREG(mode):
        return None
    return next((what for test, what in _KINDS if test(mode)), "not a regular file")


def file_kind(path: str | os.PathLike[str]) -> str | None:
    """What ``path`` is when it exists and is not a regular file (``"a folder"``, ``"a named
    pipe (FIFO)"``, ``"a character device"``, ...); None for a regular file or nothing."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:  # ValueError: a NUL character in the path
        return f"a path that cannot be read ({getattr(exc, 'strerror', None) or exc})"
    return _kind_of(mode)


def _size_text(n: int) -> str:
    from .data.budget import size_text

    return size_text(n)


def open_input(path: str | os.PathLike[str], what: str) -> BinaryIO:
    """``path`` opened for binary reading when it is a regular file.

    Raises
    ------
    FileNotFoundError
        ``"<path> does not exist (expected <what>)"``.
    InputError
        ``"<path>: expected <what>, found a named pipe (FIFO)"`` (or a folder, a device...).
    """
    path = Path(path)
    kind = file_kind(path)
    if kind is None:
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
        except FileNotFoundError:
            raise FileNotFoundError(f"{path} does not exist (expected {what})") from None
        except IsADirectoryError:
            kind = "a folder"
        else:
            kind = _kind_of(os.fstat(fd).st_mode)  # what was opened, not what was checked
            if kind is None:
                os.set_blocking(fd, True)
                return os.fdopen(fd, "rb")
            os.close(fd)
    raise InputError(f"{path}: expected {what}, found {kind}")


def read_input(path: str | os.PathLike[str], what: str, *, limit: int) -> bytes:
    """The bytes of the regular file ``path`` (:func:`open_input`), at most ``limit``;
    a larger file is refused with the bound in the message."""
    with open_input(path, what) as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise InputError(f"{path}: larger than {_size_text(limit)}, the most read for {what}")
    return data


def nesting_problem(text: str, kind: str) -> str | None:
    """Why ``text`` (``kind`` "json" or "toml") nests too deep to be parsed (None: it does
    not), found in one pass over the text: brackets and braces outside strings (and TOML
    comments) are counted, and so are the dots of a TOML dotted key (``a.a.a...``, which
    nests without brackets and which tomllib reads in quadratic time: 20,000 parts take
    20 s)."""
    depth = dots = 0
    line = 1
    quote = ""           # the open string's delimiter: ", ', \"\"\" or '''
    i, n = 0, len(text)
    toml = kind == "toml"
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
        if quote:
            if c == "\\" and quote in ('"', '"""'):
                i += 2
                continue
            if text.startswith(quote, i):
                i += len(quote)
                quote = ""
                continue
            if c == "\n" and len(quote) == 1 and toml:
                quote = ""  # an unterminated one-line string: the parser says so
            i += 1
            continue
        if c in "\"'" and (toml or c == '"'):
            quote = c * 3 if toml and text.startswith(c * 3, i) else c
            i += len(quote)
            continue
        if c == "#" and toml:
            end = text.find("\n", i)
            i = n if end < 0 else end
            continue
        if toml and c == ".":  # a key of many dotted parts: tomllib takes quadratic time
            dots += 1
            if dots > MAX_NESTING:
                return (f"a key of more than {MAX_NESTING} dotted parts (line {line}); "
                        "not parsed")
        elif c in "=,\n[]{}":
            dots = 0
        if c in "[{":
            depth += 1
            if depth > MAX_NESTING:
                return (f"nested deeper than {MAX_NESTING} arrays or tables (line {line}); "
                        "not parsed")
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return None


def load_json(path: str | os.PathLike[str], what: str, *, limit: int = MAX_JSON_BYTES) -> Any:
    """The JSON document of ``path`` (a regular file within ``limit`` bytes and
    :data:`MAX_NESTING` levels); errors name the file and say what it should be."""
    raw = read_input(path, what, limit=limit)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: not valid JSON (undecodable bytes: {err})") from None
    why = nesting_problem(text, "json")
    if why:
        raise InputError(f"{path}: {why} (expected {what})")
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: not valid JSON ({err})") from None
    except RecursionError:  # pragma: no cover - MAX_NESTING keeps far below the limit
        raise InputError(f"{path}: nested too deep to be read") from None


def load_toml(path: str | os.PathLike[str], what: str, *, limit: int) -> dict[str, Any]:
    """The TOML document of ``path`` (a regular file within ``limit`` bytes and
    :data:`MAX_NESTING` levels, UTF-8 with or without a byte order mark)."""
    raw = read_input(path, what, limit=limit)
    return parse_toml(raw, Path(path).name)


def parse_toml(raw: bytes, name: str) -> dict[str, Any]:
    """``raw`` parsed as TOML; errors start with ``name``."""
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{name}: expected a UTF-8 TOML file, found undecodable bytes "
                         f"({exc})") from None
    why = nesting_problem(text, "toml")
    if why:
        raise InputError(f"{name}: {why}")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: invalid TOML: {exc}") from None
    except RecursionError:  # pragma: no cover - MAX_NESTING keeps far below the limit
        raise InputError(f"{name}: nested too deep to be read") from None
    if _deeper_than(doc, MAX_NESTING):  # dotted keys nest without brackets
        raise InputError(f"{name}: nested deeper than {MAX_NESTING} tables (dotted keys)")
    return doc


def _deeper_than(doc: Any, limit: int) -> bool:
    """Whether tables and arrays in ``doc`` nest deeper than ``limit`` (no recursion)."""
    stack = [(doc, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > limit:
            return True
        children = node.values() if isinstance(node, dict) else node
        stack.extend((c, depth + 1) for c in children if isinstance(c, (dict, list)))
    return False
