"""Unknown keys and tables of a TOML document, found from what its reader asks for.

The known keys are not kept in a list beside the reader: the document is wrapped in
:class:`Asked` tables that record every key the reader looks up (``t["radius"]``,
``"height" in t``, ``t.get("note")``), so the reader's own validation code is the schema and a
key added to it is known at once. What the document holds beyond that was never looked at:
a typo (``[predicton]``, ``radus``) or a key of another version. A table the reader iterates
over (``[data.columns]``) handles every key in it itself.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Mapping
from typing import Any

__all__ = ["Asked", "UnknownKey", "unknown_keys"]


class UnknownKey(UserWarning):
    """A case file holds a key or table that its reader does not know (a typo?)."""


class Asked(Mapping):
    """A read-only view of a TOML table that records the keys looked up in it; sub-tables
    are views too, sharing the record (by their dotted path)."""

    def __init__(self, data: Mapping[str, Any], path: tuple[str, ...] = (),
                 record: dict[tuple[str, ...], set[str]] | None = None,
                 iterated: set[tuple[str, ...]] | None = None) -> None:
        self._data, self._path = data, path
        self._record = {} if record is None else record
        self._iterated = set() if iterated is None else iterated
        self._record.setdefault(path, set())

    def _wrap(self, key: str, value: Any) -> Any:
        if isinstance(value, Mapping):
            return Asked(value, (*self._path, key), self._record, self._iterated)
        return value

    def __getitem__(self, key: str) -> Any:
        self._record[self._path].add(key)
        return self._wrap(key, self._data[key])

    def __contains__(self, key: object) -> bool:
        if isinstance(key, str):
            self._record[self._path].add(key)
        return key in self._data

    def __iter__(self) -> Iterator[str]:
        self._iterated.add(self._path)
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return repr(self._data)

    @property
    def data(self) -> Mapping[str, Any]:
        """The table as read (not a view: looking keys up in it is not recorded)."""
        return self._data

    def unknown(self) -> list[tuple[tuple[str, ...], str, list[str]]]:
        """``(table path, key, known keys of that table)`` of every key of the document not
        looked up, in document order; tables are entered only where the reader did."""
        out = []
        stack: list[tuple[tuple[str, ...], Mapping[str, Any]]] = [(self._path, self._data)]
        while stack:
            path, table = stack.pop(0)
            asked = self._record.get(path)
            if asked is None or path in self._iterated:
                continue
            for key, value in table.items():
                if key not in asked:
                    out.append((path, key, sorted(asked)))
                elif isinstance(value, Mapping):
                    stack.append(((*path, key), value))
        return out


def _name(path: tuple[str, ...], key: str, value_is_table: bool) -> str:
    if not path:
        return f"[{key}]"
    return f"[{'.'.join((*path, key))}]" if value_is_table else f"[{'.'.join(path)}] {key}"


def unknown_keys(doc: Asked, filename: str, *, ignored: bool = True) -> list[str]:
    """One line per key or table of ``doc`` its reader never looked up, naming the file,
    the key and the nearest known name (:func:`difflib.get_close_matches`); ``ignored``:
    say that it is ignored (a warning) rather than refused."""
    lines = []
    raw = doc.data
    for path, key, known in doc.unknown():
        table: Any = raw
        for part in path:
            table = table[part]
        is_table = isinstance(table[key], Mapping)
        what = "table" if is_table else "key"
        near = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
        if near:
            hint = f"did you mean `{_name(path, near[0], is_table)}`?"
        else:
            hint = ("known: " + ", ".join(f"`{k}`" for k in known)) if known else \
                "this table takes no keys"
        fate = " (ignored)" if ignored else ""
        lines.append(f"{filename}: unknown {what} `{_name(path, key, is_table)}`{fate}; {hint}")
    return lines
