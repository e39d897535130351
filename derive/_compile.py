"""Compile CasADi functions to shared libraries with the system C compiler, cached on disk.

Generated C is keyed by a hash of the serialized function, so a library is built once per
function and reused across processes. The SHA-256 of every library is stored beside it
(``<lib>.sha256``) and checked before the library is loaded: a truncated or altered library
is rebuilt (with a warning), never loaded. Libraries and their hashes live in the cache's
``compiled/`` folder, used only while it and every folder above it up to the cache root,
the library and its hash belong to the user and nobody else can write to them
(:func:`derive.cache.cache_folder`): the hash proves nothing when another user could write
both, so such a folder is not read at all and the library is built in a private temporary
folder instead. When no compiler is available the CasADi virtual machine function is
returned unchanged, with a warning.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import casadi as ca

from .cache import UntrustedCache, building, cache_folder, file_problem

__all__ = ["compiled", "c_compiler"]

_LOADED: dict[str, ca.Function] = {}


def c_compiler() -> str | None:
    """Path of the C compiler (``$CC``, ``cc`` or ``gcc``), or ``None``."""
    for name in (os.environ.get("CC"), "cc", "gcc"):
        if name and (path := shutil.which(name)):
            return path
    return None


def _file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _trusted(lib: Path) -> bool:
    """The library exists, belongs to the user, nobody else can write to it or to its hash,
    and it matches its stored hash."""
    stamp = lib.with_name(lib.name + ".sha256")
    if not lib.exists():
        return False
    why = file_problem(lib) or file_problem(stamp)
    if why:
        warnings.warn(f"compiled library not loaded: {why}; rebuilding it", UntrustedCache,
                      stacklevel=4)
        return False
    try:
        ok = stamp.read_text().strip() == _file_digest(lib)
    except OSError:
        ok = False
    if not ok:
        warnings.warn(f"compiled library {lib} does not match its stored hash (truncated or "
                      "altered); rebuilding it", RuntimeWarning, stacklevel=4)
    return ok


def compiled(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to native code (``-O2``), or ``fn`` itself without a compiler."""
    key = hashlib.sha256(fn.serialize().encode()).hexdigest()[:24]
    if key in _LOADED:
        return _LOADED[key]
    folder = cache_folder("compiled")
    lib = folder / f"{fn.name()}_{key}.so"
    with building(lib):  # another process compiling the same function: wait for it
        if not _trusted(lib):
            cc = c_compiler()
            if cc is None:
                warnings.warn("no C compiler found: using CasADi's virtual machine", RuntimeWarning,
                              stacklevel=3)
                return fn
            with tempfile.TemporaryDirectory(dir=folder) as tmp:
                src = f"{fn.name()}_{key}.c"
                gen = ca.CodeGenerator(src, {"with_header": False})
                gen.add(fn)
                gen.generate(tmp + os.sep)
                out = Path(tmp) / lib.name
                proc = subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(out), str(Path(tmp) / src)],
                                      capture_output=True, text=True)
                if proc.returncode != 0:
                    warnings.warn(f"compiling {fn.name()} failed, using CasADi's virtual machine:\n"
                                  f"{proc.stderr[-2000:]}", RuntimeWarning, stacklevel=3)
                    return fn
                stamp = Path(tmp) / (lib.name + ".sha256")
                stamp.write_text(_file_digest(out))
                # the library first, then its hash: a reader between the two sees a mismatch
                # and rebuilds instead of loading a library without a matching hash
                os.replace(out, lib)
                os.replace(stamp, lib.with_name(lib.name + ".sha256"))
    ext = ca.external(fn.name(), str(lib))
    _LOADED[key] = ext
    return ext
