"""Compile CasADi functions to shared libraries with the system C compiler, cached on disk.

Generated C is keyed by a hash of the serialized function, so a library is built once per
function and reused across processes. When no compiler is available the CasADi virtual
machine function is returned unchanged, with a warning.
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

from .cache import cache_dir

__all__ = ["compiled", "c_compiler"]

_LOADED: dict[str, ca.Function] = {}


def c_compiler() -> str | None:
    """Path of the C compiler (``$CC``, ``cc`` or ``gcc``), or ``None``."""
    for name in (os.environ.get("CC"), "cc", "gcc"):
        if name and (path := shutil.which(name)):
            return path
    return None


def compiled(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to native code (``-O2``), or ``fn`` itself without a compiler."""
    key = hashlib.sha256(fn.serialize().encode()).hexdigest()[:24]
    if key in _LOADED:
        return _LOADED[key]
    folder = cache_dir() / "compiled"
    lib = folder / f"{fn.name()}_{key}.so"
    if not lib.exists():
        cc = c_compiler()
        if cc is None:
            warnings.warn("no C compiler found: using CasADi's virtual machine", RuntimeWarning,
                          stacklevel=3)
            return fn
        folder.mkdir(parents=True, exist_ok=True)
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
            os.replace(out, lib)
    ext = ca.external(fn.name(), str(lib))
    _LOADED[key] = ext
    return ext
