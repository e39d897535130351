"""Damaged lab files told apart from missing channels.

A TDMS file cut short still opens: npTDMS logs a warning ("less data than expected") and
returns shorter channels, and a MAT v5 file cut short lists only the variables before the
cut - so a damaged file would be reported as "channel not found" or "channels of different
lengths". Here the damage itself is found: npTDMS's warnings are captured while the file
is read, and the data elements of a MAT v5 file are walked (tag by tag, the layout of the
MAT-file format) to see whether the file ends inside one.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["captured_warnings", "mat5_damage"]

_MAT5_HEADER = 128
_COMPRESSED = 15  # miCOMPRESSED: not padded to 8 bytes


class _Collect(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


@contextmanager
def captured_warnings(logger: str) -> Iterator[list[str]]:
    """Within the block, warnings that ``logger`` and its children log are collected in the
    list yielded instead of going to their handlers (npTDMS gives each module logger its
    own stream handler)."""
    import importlib

    try:  # the library's loggers exist once its modules are imported
        importlib.import_module(logger)
    except ImportError:
        pass
    handler = _Collect()
    names = [logger, *(n for n in logging.Logger.manager.loggerDict if n.startswith(logger + "."))]
    saved = []
    for name in names:
        log = logging.getLogger(name)
        saved.append((log, log.handlers[:], log.propagate))
        log.handlers[:] = [handler]
        log.propagate = False
    try:
        yield handler.messages
    finally:
        for log, handlers, propagate in saved:
            log.handlers[:] = handlers
            log.propagate = propagate


def mat5_damage(path: Path) -> str | None:
    """Where a MAT v5 file ends inside a data element (None: every element is whole)."""
    with path.open("rb") as fh:
        data = fh.read()
    if len(data) < _MAT5_HEADER:
        return f"{len(data)} bytes, shorter than the {_MAT5_HEADER}-byte header"
    order = "<" if data[126:128] == b"IM" else ">"
    pos, index = _MAT5_HEADER, 0
    while pos < len(data):
        if pos + 8 > len(data):
            return f"the file ends inside the tag of data element {index + 1} (byte {pos})"
        kind, size = struct.unpack_from(order + "II", data, pos)
        if kind >> 16:  # small data element: type and size in 4 bytes, data in the next 4
            pos += 8
        else:
            padded = size if kind == _COMPRESSED else -(-size // 8) * 8
            if pos + 8 + size > len(data):
                return (f"the file ends inside data element {index + 1}: it declares {size} "
                        f"bytes from byte {pos + 8}, the file has {len(data) - pos - 8}")
            pos += 8 + padded
        index += 1
    return None
