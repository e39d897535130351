"""Parameters of analog components: dotted name, unit, default and physical bounds."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

__all__ = ["Param", "Parameter"]


@dataclass(frozen=True)
class Param:
    """Specification of a component parameter, before it is bound to a component name.

    Parameters
    ----------
    unit : str
        SI unit, e.g. ``"kg"``, ``"m"``, ``"N m/rad"``.
    default : float or None
        Value used when the user gives none; ``None`` means the value is required.
    lower, upper : float
        Physical bounds (inclusive); ``-inf``/``inf`` when unbounded.
    description : str
        One line saying what the parameter is.
    """

    unit: str
    default: float | None = None
    lower: float = -math.inf
    upper: float = math.inf
    description: str = ""


@dataclass(frozen=True)
class Parameter:
    """A parameter of an assembled model, with its full dotted name (``"p1.length"``).

    Attributes
    ----------
    name : str
        Dotted name ``"<component>.<local>"``.
    unit : str
        SI unit.
    default : float or None
        Default value, ``None`` when required.
    lower, upper : float
        Physical bounds (inclusive).
    description : str
        What the parameter is.
    """

    name: str
    unit: str
    default: float | None = None
    lower: float = -math.inf
    upper: float = math.inf
    description: str = field(default="", compare=False)

    @property
    def local_name(self) -> str:
        """The part after the component prefix (``"length"`` for ``"p1.length"``)."""
        return self.name.split(".", 1)[1]

    def with_default(self, value: float | None) -> "Parameter":
        """Return a copy whose default is ``value`` (None: required)."""
        return replace(self, default=None if value is None else float(value))

    def with_bounds(self, lower: float, upper: float) -> "Parameter":
        """Return a copy with the bounds ``lower`` and ``upper`` (in its unit)."""
        return replace(self, lower=float(lower), upper=float(upper))

    def check(self, value: float) -> str | None:
        """Return a problem description if ``value`` is not acceptable, else ``None``."""
        if not math.isfinite(value):
            return f"parameter `{self.name}` ({self.unit}) must be finite, got {value!r}"
        if value < self.lower or value > self.upper:
            return (
                f"parameter `{self.name}` = {value!r} {self.unit} is outside its bounds "
                f"[{self.lower!r}, {self.upper!r}]"
            )
        return None
