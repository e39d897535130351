"""The problem collector of a TOML document (:class:`Checker`: tables, keys, numbers
with units, each problem naming the file and key) and the physical ranges of numbers
(:func:`range_problem`), and the TOML type a problem names (:func:`type_name`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .case import PHYSICAL_RANGES

__all__ = ["Checker", "range_problem", "type_name"]


class Checker:
    """Collects problems while reading one TOML document."""

    def __init__(self, filename: str) -> None:
        self.filename = filename
        self.problems: list[str] = []

    def add(self, where: str, message: str) -> None:
        self.problems.append(f"{self.filename}: {where}: {message}")

    def table(self, doc: Mapping[str, Any], name: str, *, required: bool) -> Mapping[str, Any] | None:
        parts = name.split(".")
        node: Any = doc
        for part in parts:
            if not isinstance(node, Mapping) or part not in node:
                if required:
                    self.add(f"[{name}]", "missing table (expected a `[" + name + "]` section)")
                return None
            node = node[part]
        if not isinstance(node, Mapping):
            self.add(f"[{name}]", f"expected a table, found {type_name(node)} `{node!r}`")
            return None
        return node

    def string(self, table: Mapping[str, Any], tname: str, key: str, *,
               choices: tuple[str, ...] | None = None, required: bool = True) -> str | None:
        where = f"[{tname}] {key}"
        if key not in table:
            if required:
                self.add(where, "missing key (expected a string)")
            return None
        value = table[key]
        if not isinstance(value, str):
            self.add(where, f"expected a string, found {type_name(value)} `{value!r}`")
            return None
        if choices is not None and value not in choices:
            allowed = ", ".join(f'"{c}"' for c in choices)
            self.add(where, f'unknown value "{value}" (expected one of {allowed})')
            return None
        return value

    def boolean(self, table: Mapping[str, Any], tname: str, key: str) -> bool | None:
        where = f"[{tname}] {key}"
        if key not in table:
            self.add(where, "missing key (expected true or false)")
            return None
        value = table[key]
        if not isinstance(value, bool):
            self.add(where, f"expected true or false, found {type_name(value)} `{value!r}`")
            return None
        return value

    def number(self, table: Mapping[str, Any], tname: str, key: str, *, unit: str,
               positive: bool = False, nonnegative: bool = False,
               open_unit_interval: bool = False) -> float | None:
        where = f"[{tname}] {key}"
        if key not in table:
            self.add(where, f"missing key (expected a number in {unit})")
            return None
        value = table[key]
        # bool is an int subclass in Python; TOML true/false is never a valid number.
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.add(where, f"expected a number in {unit}, found {type_name(value)} `{value!r}`")
            return None
        number = float(value)
        if not math.isfinite(number):
            self.add(where, f"expected a finite number in {unit}, found {value!r}")
            return None
        if positive and not number > 0.0:
            self.add(where, f"expected a positive number in {unit}, found {value!r}")
            return None
        if nonnegative and not number >= 0.0:
            self.add(where, f"expected a number >= 0 in {unit}, found {value!r}")
            return None
        if open_unit_interval and not 0.0 < number < 1.0:
            self.add(where, f"expected a number strictly between 0 and 1, found {value!r}")
            return None
        why = range_problem(number, unit, positive=positive)
        if why:
            self.add(where, f"{why}, found {value!r}")
            return None
        return number


def range_problem(value: float, unit: str, *, positive: bool = False) -> str | None:
    """What a value of ``unit`` outside :data:`~estimate.data.case.PHYSICAL_RANGES` should
    have been (None: inside, or a unit without a range)."""
    if unit not in PHYSICAL_RANGES:
        return None
    low, high, what = PHYSICAL_RANGES[unit]
    if abs(value) > high or (positive and value < low):
        span = f"{low:g} to {high:g}" if positive else f"a magnitude up to {high:g}"
        article = "an" if what[0] in "aeiou" else "a"
        return f"expected {span} {unit} (the range accepted for {article} {what})"
    return None


def type_name(value: Any) -> str:
    """How a problem names the TOML type of ``value`` (``"a string"``, ``"a table"``)."""
    names = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    if isinstance(value, Mapping):
        return "a table"
    return names.get(type(value), type(value).__name__)
