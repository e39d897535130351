"""Which cache folders and files may be read: only those nobody but the user can change.

The cache holds serialized CasADi functions and native libraries that are loaded into the
process, so a file there is as trusted as the least private folder on its way. A path is
used only when, after resolving symlinks, the cache root and every folder below it down to
the file (and the file) belong to the user and are not writable by group or others, and no
folder above the root can be replaced by another user (writable by others without the
sticky bit, or owned by another account than the user or root). Otherwise the command says
so once (:class:`UntrustedCache`, one line) and works in a private temporary folder made for
the process and removed at its exit.
"""

from __future__ import annotations

import atexit
import os
import shutil
import stat
import tempfile
import threading
import warnings
from pathlib import Path

__all__ = ["UntrustedCache", "file_problem", "folder_problem", "private_folder"]

_WRITABLE = stat.S_IWGRP | stat.S_IWOTH


class UntrustedCache(RuntimeWarning):
    """The configured cache folder is not private to the user and is not used."""


def _mode(st: os.stat_result) -> str:
    return f"mode {stat.S_IMODE(st.st_mode):o}"


def _private(label: str, st: os.stat_result) -> str | None:
    """Why a cache folder or file with status ``st`` is not private to the user."""
    if st.st_uid != os.geteuid():
        return f"{label} belongs to another user (uid {st.st_uid})"
    if st.st_mode & _WRITABLE:
        return f"{label} is writable by group or others ({_mode(st)})"
    return None


def _above(label: str, st: os.stat_result) -> str | None:
    """Why a folder above the cache root lets another user replace what is below it."""
    if st.st_uid not in (os.geteuid(), 0):
        return f"{label}, a folder above the cache, belongs to another user (uid {st.st_uid})"
    if st.st_mode & stat.S_IWOTH and not st.st_mode & stat.S_ISVTX:
        return (f"{label}, a folder above the cache, is writable by others without the sticky "
                f"bit ({_mode(st)})")
    return None


def folder_problem(root: Path, *parts: str) -> str | None:
    """Why the folder ``root/parts...`` cannot be trusted (None: it can, or the part of it
    that exists can: what is missing is created private by :func:`private_folder`)."""
    prefixes = [root, *(root.joinpath(*parts[:i + 1]) for i in range(len(parts)))]
    seen: set[Path] = set()
    for prefix in prefixes:
        try:
            real = prefix.resolve(strict=True)
            st = os.stat(real)
        except FileNotFoundError:
            return None
        except (OSError, RuntimeError) as err:  # RuntimeError: a symlink loop
            return f"{prefix} cannot be resolved ({getattr(err, 'strerror', None) or err})"
        label = str(prefix) if real == prefix else f"{prefix} (-> {real})"
        if not stat.S_ISDIR(st.st_mode):
            return f"{label} is not a folder"
        why = _private(label, st)
        if why:
            return why
        for above in real.parents:
            if above in seen:
                continue
            seen.add(above)
            try:
                why = _above(str(above), os.stat(above))
            except OSError as err:
                why = f"{above} cannot be read ({err.strerror})"
            if why:
                return why
    return None


def file_problem(path: Path) -> str | None:
    """Why the cache file ``path`` (in a trusted folder) cannot be read: not a regular file,
    owned by another user, writable by group or others. None when absent or fine."""
    try:
        st = os.stat(path.resolve(strict=True))
    except FileNotFoundError:
        return None
    except (OSError, RuntimeError) as err:
        return f"{path} cannot be resolved ({getattr(err, 'strerror', None) or err})"
    if not stat.S_ISREG(st.st_mode):
        return f"{path} is not a regular file"
    return _private(str(path), st)


_lock = threading.Lock()
_fallback: list[Path] = []


def _private_temporary() -> Path:
    """A folder of this process only (mode 0700), removed when the process exits."""
    with _lock:
        if not _fallback:
            folder = Path(tempfile.mkdtemp(prefix="slosh-private-cache-"))
            atexit.register(shutil.rmtree, folder, ignore_errors=True)
            _fallback.append(folder)
        return _fallback[0]


def _make(root: Path, parts: tuple[str, ...]) -> str | None:
    """Create the missing folders of ``root/parts`` private to the user."""
    folder = root
    try:
        if not root.exists():
            root.parent.mkdir(parents=True, exist_ok=True)
            root.mkdir(mode=0o700, exist_ok=True)
        for part in parts:
            folder = folder / part
            folder.mkdir(mode=0o700, exist_ok=True)
    except OSError as err:
        return f"{folder} cannot be created ({err.strerror or err})"
    return None


def private_folder(root: Path, *parts: str) -> Path:
    """``root/parts...`` created private to the user when it can be trusted
    (:func:`folder_problem`); otherwise, with a one-line :class:`UntrustedCache` warning,
    the same sub-folder of a private temporary folder of this process."""
    why = folder_problem(root, *parts) or _make(root, parts) or folder_problem(root, *parts)
    if why is None:
        return root.joinpath(*parts)
    warnings.warn(f"the cache is not used: {why}; working in a private temporary folder for "
                  "this run instead (make it private with `chmod go-w`, or set SLOSH_CACHE_DIR "
                  "to a folder only you can write)", UntrustedCache, stacklevel=3)
    folder = _private_temporary().joinpath(*parts)
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    return folder
