"""Test-case files: a TOML description plus a CSV of samples.

A case file describes one tank test (tank, liquid, rig, optional analog prediction) and names a
CSV file with the measured samples. The format is the one of the estimation issue::

    [test]
    id = "A1"
    rig = "lateral"              # "lateral" now; "spinning" later
    data = "A1.csv"              # CSV path relative to this file
    excitation = "measured"      # "measured": CSV has displacement; "crank": from [rig.crank]

    [tank]
    shape = "sphere"             # "sphere" | "cylinder"
    radius = 0.1016              # m
    fill_fraction = 0.6          # liquid depth / tank height
    diaphragm = false

    [liquid]
    density = 998.2              # kg/m^3
    kinematic_viscosity = 1.004e-6   # m^2/s

    [rig]
    dry_mass = 1.2               # kg
    gravity = 9.80665            # m/s^2

    [rig.crank]                  # only for excitation = "crank"
    radius = 0.01                # m
    rod_length = 0.15            # m
    frequency = 1.855            # Hz

    [prediction]                 # optional
    pendulum_mass = 1.338        # kg
    pendulum_length = 0.057      # m
    fixed_mass = 1.456           # kg
    damping_ratio = 0.00703      # fraction of critical

The CSV header is ``time,displacement,force`` (s, m, N); ``displacement`` may be absent when
``excitation = "crank"``. Keys not listed above are allowed and ignored (``[test] note`` is kept).

Spinning rig
------------
``rig = "spinning"`` describes the Spinning Slosh Test Rig (:class:`analogs.SpinningRig`): the
rig motion is prescribed by a ``[rig.spin]`` table, so ``[test] excitation`` may be omitted
(it is then ``"spin"``, the only value accepted for this rig)::

    [rig.spin]
    rate = 6.0                   # rad/s, table spin rate
    radius = 0.4                 # m, tank origin from the spin axis
    nutation_angle = 0.06        # rad, cone half-angle of the table axis
    nutation_frequency = 0.3     # Hz, coning frequency (either sign)
    height = 0.3                 # m, optional (default 0): tank origin above the pivot
    tank_axis = "spin"           # optional: "spin" (default) or "inward"
    gravity_on = true            # optional (default true): gravity acts

Its CSV has the columns ``time,force_x,force_y,force_z,torque_x,torque_y,torque_z`` (s, N,
N m; tank-frame components, torques about the mount point), in any order after ``time``;
extra columns (e.g. measured rig angles) are allowed, kept in :attr:`Case.channels` and
checked like the others.

:func:`load_case` validates everything and raises one :class:`CaseError` listing every problem;
input files are never modified. :func:`write_case` writes a case (TOML + CSV), e.g. for
generated data, and refuses to overwrite existing files unless asked to.

Validation limits
-----------------
* Time must increase strictly and be uniform: every step must be within
  :data:`TIME_STEP_RTOL` (1e-3) of the median step, relative. This admits timestamps printed
  with a few decimals and floating-point round-off, and rejects dropped or repeated samples
  (a dropped sample is a 100% step error).
* At least :data:`MIN_SAMPLES` (50) samples: fewer cannot hold a few periods of a 1-5 Hz drive at
  100 Hz sampling, nor the padding that zero-phase filters and Welch spectra need.
* CSV problems name the line of the file (the header is line 1).
"""

from __future__ import annotations

import csv
import math
import os
import shutil
import tempfile
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "KNOWN_EXCITATIONS",
    "KNOWN_RIGS",
    "KNOWN_SHAPES",
    "MIN_SAMPLES",
    "TIME_STEP_RTOL",
    "Case",
    "CaseError",
    "Crank",
    "Liquid",
    "Prediction",
    "Rig",
    "SPINNING_CHANNELS",
    "Spin",
    "Tank",
    "TestInfo",
    "load_case",
    "write_case",
]

KNOWN_RIGS: tuple[str, ...] = ("lateral", "spinning")
"""Values accepted for ``[test] rig``."""
KNOWN_EXCITATIONS: tuple[str, ...] = ("measured", "crank", "spin")
"""Values accepted for ``[test] excitation`` (``"spin"``: only, and by default, for the
spinning rig)."""
SPINNING_CHANNELS: tuple[str, ...] = ("force_x", "force_y", "force_z",
                                      "torque_x", "torque_y", "torque_z")
"""Columns a spinning-rig CSV must have besides ``time`` (N and N m)."""
TANK_AXES: tuple[str, ...] = ("spin", "inward")
"""Values accepted for ``[rig.spin] tank_axis``."""
KNOWN_SHAPES: tuple[str, ...] = ("sphere", "cylinder")
"""Values accepted for ``[tank] shape``."""
MIN_SAMPLES: int = 50
"""Minimum number of CSV samples (see the module docstring for why)."""
TIME_STEP_RTOL: float = 1e-3
"""Allowed deviation of each time step from the median step, relative to the median step."""

_COLUMNS_FULL = ("time", "displacement", "force")
_COLUMNS_CRANK = ("time", "force")
_MAX_LISTED_ROWS = 10


class CaseError(ValueError):
    """A case file (TOML or CSV) is invalid.

    Parameters
    ----------
    problems : list of str
        One message per problem, each naming the file, the key or column and row, what was
        expected and what was found.

    Attributes
    ----------
    problems : list of str
        The individual problems, in the order they were found.
    """

    def __init__(self, problems: list[str]) -> None:
        self.problems: list[str] = list(problems)
        count = len(self.problems)
        head = f"{count} problem{'s' if count != 1 else ''} in case:"
        super().__init__("\n".join([head, *(f"  - {p}" for p in self.problems)]))


@dataclass(frozen=True)
class TestInfo:
    """The ``[test]`` table.

    Attributes
    ----------
    id : str
        Test identifier, e.g. ``"A1"``.
    rig : str
        Rig kind, one of :data:`KNOWN_RIGS`.
    data : str
        CSV path as written in the file (relative to the TOML file unless absolute).
    excitation : str
        ``"measured"`` (CSV has the carriage displacement) or ``"crank"`` (from
        ``[rig.crank]``).
    note : str or None
        Free text, e.g. that the data are synthetic.
    """

    __test__ = False  # not a pytest test class despite the name

    id: str
    rig: str
    data: str
    excitation: str
    note: str | None = None


@dataclass(frozen=True)
class Tank:
    """The ``[tank]`` table.

    Attributes
    ----------
    shape : str
        One of :data:`KNOWN_SHAPES`.
    radius : float
        Tank radius [m].
    fill_fraction : float
        Liquid depth / tank height, in (0, 1) [-].
    diaphragm : bool
        Whether the tank has an elastomeric diaphragm.
    """

    shape: str
    radius: float
    fill_fraction: float
    diaphragm: bool


@dataclass(frozen=True)
class Liquid:
    """The ``[liquid]`` table.

    Attributes
    ----------
    density : float
        [kg/m^3].
    kinematic_viscosity : float
        [m^2/s].
    """

    density: float
    kinematic_viscosity: float


@dataclass(frozen=True)
class Crank:
    """The ``[rig.crank]`` table: crank ("locomotive arm") drive of the carriage.

    The carriage displacement is ``x = r cos(phi) + sqrt(l^2 - r^2 sin(phi)^2) - l`` with
    flywheel angle ``phi = phi0 + (2 pi frequency + dOmega) t``.

    Attributes
    ----------
    radius : float
        Crank radius r [m].
    rod_length : float
        Connecting-rod length l [m], larger than ``radius``.
    frequency : float
        Nominal drive frequency [Hz].
    """

    radius: float
    rod_length: float
    frequency: float


@dataclass(frozen=True)
class Spin:
    """The ``[rig.spin]`` table: prescribed motion of the spinning rig
    (:class:`analogs.SpinningRig`).

    Attributes
    ----------
    rate : float
        Table spin rate [rad/s].
    radius : float
        Distance of the tank origin (mount point) from the spin axis [m], >= 0.
    nutation_angle : float
        Half-angle of the cone swept by the table axis [rad], in [0, pi/2).
    nutation_frequency : float
        Coning frequency of the table axis [Hz] (positive: with the spin).
    height : float, default 0
        Height of the tank origin above the nutation pivot along the spin axis [m].
    tank_axis : str, default "spin"
        ``"spin"`` or ``"inward"`` (see :class:`analogs.SpinningRig`).
    gravity_on : bool, default True
        Whether gravity acts (``[rig] gravity`` gives its value).
    """

    rate: float
    radius: float
    nutation_angle: float
    nutation_frequency: float
    height: float = 0.0
    tank_axis: str = "spin"
    gravity_on: bool = True


@dataclass(frozen=True)
class Rig:
    """The ``[rig]`` table.

    Attributes
    ----------
    dry_mass : float
        Mass moving with the tank and seen by the force transducer [kg].
    gravity : float
        Gravitational acceleration [m/s^2].
    crank : Crank or None
        The ``[rig.crank]`` table when present.
    spin : Spin or None
        The ``[rig.spin]`` table (spinning rig only).
    """

    dry_mass: float
    gravity: float
    crank: Crank | None = None
    spin: Spin | None = None


@dataclass(frozen=True)
class Prediction:
    """The optional ``[prediction]`` table: analog parameters a slosh code predicted.

    Attributes
    ----------
    pendulum_mass : float
        [kg].
    pendulum_length : float
        [m].
    fixed_mass : float
        [kg].
    damping_ratio : float
        Fraction of critical damping [-], >= 0.
    """

    pendulum_mass: float
    pendulum_length: float
    fixed_mass: float
    damping_ratio: float


@dataclass(frozen=True, eq=False)
class Case:
    """A validated test case.

    The arrays are read-only copies.

    Attributes
    ----------
    path : pathlib.Path
        The TOML file, resolved.
    data_path : pathlib.Path
        The CSV file, resolved.
    test, tank, liquid, rig, prediction
        The tables of the TOML file (``prediction`` is None when absent).
    time : numpy.ndarray
        Sample times [s], strictly increasing and uniform.
    displacement : numpy.ndarray or None
        Carriage displacement [m]; None when the CSV has no displacement column.
    force : numpy.ndarray or None
        Measured lateral force [N] (lateral rig); None for the spinning rig.
    columns : mapping of str to numpy.ndarray
        The CSV columns besides ``time`` of a spinning-rig case (empty for a lateral case);
        read them through :attr:`channels`.
    """

    path: Path
    data_path: Path
    test: TestInfo
    tank: Tank
    liquid: Liquid
    rig: Rig
    prediction: Prediction | None
    time: NDArray[np.float64] = field(repr=False)
    displacement: NDArray[np.float64] | None = field(repr=False)
    force: NDArray[np.float64] | None = field(repr=False)
    columns: Mapping[str, NDArray[np.float64]] = field(default_factory=dict, repr=False)

    @property
    def channels(self) -> dict[str, NDArray[np.float64]]:
        """Measured signals by output name: ``{"force_x": force}`` for the lateral rig, the
        six force/torque channels (and any extra CSV columns) for the spinning rig."""
        if self.test.rig == "lateral":
            return {} if self.force is None else {"force_x": self.force}
        return dict(self.columns)

    @property
    def spin(self) -> Spin | None:
        """The ``[rig.spin]`` table, or None."""
        return self.rig.spin

    @property
    def crank(self) -> Crank | None:
        """The ``[rig.crank]`` table, or None."""
        return self.rig.crank

    @property
    def sample_interval(self) -> float:
        """Median time step [s]."""
        return float(np.median(np.diff(self.time)))

    @property
    def sample_rate(self) -> float:
        """Sampling rate [Hz]."""
        return 1.0 / self.sample_interval

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.time.size)


# ----------------------------------------------------------------------------------------------
# TOML validation


class _Checker:
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
            self.add(f"[{name}]", f"expected a table, found {_type_name(node)} `{node!r}`")
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
            self.add(where, f"expected a string, found {_type_name(value)} `{value!r}`")
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
            self.add(where, f"expected true or false, found {_type_name(value)} `{value!r}`")
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
            self.add(where, f"expected a number in {unit}, found {_type_name(value)} `{value!r}`")
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
        return number


def _type_name(value: Any) -> str:
    names = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    return names.get(type(value), type(value).__name__)


def _read_test(ck: _Checker, doc: Mapping[str, Any]) -> TestInfo | None:
    t = ck.table(doc, "test", required=True)
    if t is None:
        return None
    test_id = ck.string(t, "test", "id")
    rig = ck.string(t, "test", "rig", choices=KNOWN_RIGS)
    data = ck.string(t, "test", "data")
    spinning = rig == "spinning"
    excitation = ck.string(t, "test", "excitation",
                           choices=("spin",) if spinning else ("measured", "crank"),
                           required=not spinning)
    if spinning and "excitation" not in t:
        excitation = "spin"  # the spinning rig's motion comes from `[rig.spin]`
    note = ck.string(t, "test", "note", required=False)
    if data is not None and not data.strip():
        ck.add("[test] data", 'expected a CSV path, found an empty string ""')
        data = None
    if None in (test_id, rig, data, excitation):
        return None
    assert test_id is not None and rig is not None and data is not None
    assert excitation is not None
    return TestInfo(id=test_id, rig=rig, data=data, excitation=excitation, note=note)


def _read_tank(ck: _Checker, doc: Mapping[str, Any]) -> Tank | None:
    t = ck.table(doc, "tank", required=True)
    if t is None:
        return None
    shape = ck.string(t, "tank", "shape", choices=KNOWN_SHAPES)
    radius = ck.number(t, "tank", "radius", unit="m", positive=True)
    fill = ck.number(t, "tank", "fill_fraction", unit="-", open_unit_interval=True)
    diaphragm = ck.boolean(t, "tank", "diaphragm")
    if shape is None or radius is None or fill is None or diaphragm is None:
        return None
    return Tank(shape=shape, radius=radius, fill_fraction=fill, diaphragm=diaphragm)


def _read_liquid(ck: _Checker, doc: Mapping[str, Any]) -> Liquid | None:
    t = ck.table(doc, "liquid", required=True)
    if t is None:
        return None
    density = ck.number(t, "liquid", "density", unit="kg/m^3", positive=True)
    nu = ck.number(t, "liquid", "kinematic_viscosity", unit="m^2/s", positive=True)
    if density is None or nu is None:
        return None
    return Liquid(density=density, kinematic_viscosity=nu)


def _read_crank(ck: _Checker, doc: Mapping[str, Any], *, required: bool) -> tuple[bool, Crank | None]:
    """Return (table present, crank or None)."""
    rig = doc.get("rig")
    present = isinstance(rig, Mapping) and "crank" in rig
    if not present:
        if required:
            ck.add("[rig.crank]", 'missing table (expected `[rig.crank]` with radius, rod_length '
                   'and frequency because `[test] excitation = "crank"`)')
        return False, None
    t = ck.table(doc, "rig.crank", required=True)
    if t is None:
        return True, None
    radius = ck.number(t, "rig.crank", "radius", unit="m", positive=True)
    rod = ck.number(t, "rig.crank", "rod_length", unit="m", positive=True)
    freq = ck.number(t, "rig.crank", "frequency", unit="Hz", positive=True)
    if radius is not None and rod is not None and not rod > radius:
        ck.add("[rig.crank] rod_length",
               f"expected a rod longer than the crank radius ({radius!r} m), found {rod!r} m")
        rod = None
    if radius is None or rod is None or freq is None:
        return True, None
    return True, Crank(radius=radius, rod_length=rod, frequency=freq)


def _read_spin(ck: _Checker, doc: Mapping[str, Any], *, required: bool) -> tuple[bool, Spin | None]:
    """Return (table present, spin or None)."""
    rig = doc.get("rig")
    present = isinstance(rig, Mapping) and "spin" in rig
    if not present:
        if required:
            ck.add("[rig.spin]", 'missing table (expected `[rig.spin]` with rate, radius, '
                   'nutation_angle and nutation_frequency because `[test] rig = "spinning"`)')
        return False, None
    t = ck.table(doc, "rig.spin", required=True)
    if t is None:
        return True, None
    rate = ck.number(t, "rig.spin", "rate", unit="rad/s")
    radius = ck.number(t, "rig.spin", "radius", unit="m", nonnegative=True)
    angle = ck.number(t, "rig.spin", "nutation_angle", unit="rad", nonnegative=True)
    if angle is not None and not angle < math.pi / 2:
        ck.add("[rig.spin] nutation_angle",
               f"expected a cone half-angle below pi/2 rad, found {angle!r} rad")
        angle = None
    freq = ck.number(t, "rig.spin", "nutation_frequency", unit="Hz")
    height = ck.number(t, "rig.spin", "height", unit="m") if "height" in t else 0.0
    axis = ck.string(t, "rig.spin", "tank_axis", choices=TANK_AXES, required=False)
    gravity_on = ck.boolean(t, "rig.spin", "gravity_on") if "gravity_on" in t else True
    if None in (rate, radius, angle, freq, height, gravity_on) or ("tank_axis" in t and axis is None):
        return True, None
    assert rate is not None and radius is not None and angle is not None and freq is not None
    assert height is not None and gravity_on is not None
    return True, Spin(rate=rate, radius=radius, nutation_angle=angle, nutation_frequency=freq,
                      height=height, tank_axis=axis or "spin", gravity_on=gravity_on)


def _read_rig(ck: _Checker, doc: Mapping[str, Any], excitation: str | None,
              rig_kind: str | None = None) -> Rig | None:
    t = ck.table(doc, "rig", required=True)
    dry = grav = None
    if t is not None:
        dry = ck.number(t, "rig", "dry_mass", unit="kg", positive=True)
        grav = ck.number(t, "rig", "gravity", unit="m/s^2", positive=True)
    present, crank = _read_crank(ck, doc, required=(excitation == "crank" and t is not None))
    spinning = rig_kind == "spinning"
    spin_present, spin = _read_spin(ck, doc, required=spinning and t is not None)
    if dry is None or grav is None or (present and crank is None):
        return None
    if excitation == "crank" and crank is None:
        return None
    if spin_present and spin is None or (spinning and spin is None):
        return None
    return Rig(dry_mass=dry, gravity=grav, crank=crank, spin=spin if spinning else None)


def _read_prediction(ck: _Checker, doc: Mapping[str, Any]) -> tuple[bool, Prediction | None]:
    if "prediction" not in doc:
        return False, None
    t = ck.table(doc, "prediction", required=True)
    if t is None:
        return True, None
    pm = ck.number(t, "prediction", "pendulum_mass", unit="kg", positive=True)
    pl = ck.number(t, "prediction", "pendulum_length", unit="m", positive=True)
    fm = ck.number(t, "prediction", "fixed_mass", unit="kg", positive=True)
    zeta = ck.number(t, "prediction", "damping_ratio", unit="- (fraction of critical)",
                     nonnegative=True)
    if pm is None or pl is None or fm is None or zeta is None:
        return True, None
    return True, Prediction(pendulum_mass=pm, pendulum_length=pl, fixed_mass=fm,
                            damping_ratio=zeta)


# ----------------------------------------------------------------------------------------------
# CSV validation


def _rows_text(lines: list[int]) -> str:
    shown = ", ".join(str(n) for n in lines[:_MAX_LISTED_ROWS])
    more = f" and {len(lines) - _MAX_LISTED_ROWS} more" if len(lines) > _MAX_LISTED_ROWS else ""
    return f"line{'s' if len(lines) != 1 else ''} {shown}{more}"


def _read_csv(path: Path, excitation: str | None, problems: list[str],
              rig_kind: str | None = "lateral") -> tuple[Any, ...] | None:
    """Read and check the CSV; append problems; return (time, displacement, force, columns)
    or None (``columns``: the non-time columns of a spinning-rig CSV, else empty)."""
    name = path.name
    try:
        with path.open("r", newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            rows = [(reader.line_num, row) for row in reader]
    except OSError as exc:
        problems.append(f"{name}: cannot read the CSV file ({exc.strerror or exc})")
        return None
    except (UnicodeDecodeError, csv.Error) as exc:
        problems.append(f"{name}: not a readable UTF-8 CSV file ({exc})")
        return None
    rows = [(n, r) for n, r in rows if r and any(c.strip() for c in r)]  # skip blank lines
    spinning = rig_kind == "spinning"
    spin_header = "`" + ",".join(("time",) + SPINNING_CHANNELS) + "`"
    if not rows:
        expected = spin_header if spinning else "`time,displacement,force`"
        problems.append(f"{name}: header: expected {expected}, found an empty file")
        return None
    header_line, header = rows[0]
    names = tuple(c.strip() for c in header)
    has_disp = False
    if spinning:
        missing = [c for c in SPINNING_CHANNELS if c not in names]
        repeated = sorted({c for c in names if names.count(c) > 1})
        if not names or names[0] != "time" or missing or repeated:
            found = []
            if not names or names[0] != "time":
                found.append(f"first column `{names[0] if names else ''}` instead of `time`")
            if missing:
                found.append("no column" + ("s " if len(missing) > 1 else " ")
                             + ", ".join(f"`{c}`" for c in missing))
            if repeated:
                found.append("repeated column(s) " + ", ".join(f"`{c}`" for c in repeated))
            problems.append(f"{name}: header (line {header_line}): expected {spin_header} "
                            f"(extra columns allowed) for `rig = \"spinning\"`, found "
                            f"`{','.join(header)}` ({'; '.join(found)})")
            return None
    elif names == _COLUMNS_FULL:
        has_disp = True
    elif names == _COLUMNS_CRANK:
        has_disp = False
    else:
        expected = "`time,displacement,force`"
        if excitation == "crank":
            expected += " or `time,force`"
        problems.append(f"{name}: header (line {header_line}): expected {expected}, "
                        f"found `{','.join(header)}`")
        return None
    if not spinning and not has_disp and excitation != "crank":
        problems.append(
            f"{name}: column `displacement`: missing, but `[test] excitation = \"measured\"` "
            "needs the carriage displacement (expected header `time,displacement,force`; "
            "use `excitation = \"crank\"` with a `[rig.crank]` table otherwise)")

    ncol = len(names)
    data = np.full((len(rows) - 1, ncol), np.nan)
    lines = np.empty(len(rows) - 1, dtype=int)
    bad_fields: list[str] = []
    skip_lines: set[int] = set()  # rows already reported; not reported again as NaN
    bad_numbers: dict[str, list[tuple[int, str]]] = {c: [] for c in names}
    for i, (line, row) in enumerate(rows[1:]):
        lines[i] = line
        if len(row) != ncol:
            bad_fields.append(f"line {line} ({len(row)} fields)")
            skip_lines.add(line)
            continue
        for j, text in enumerate(row):
            try:
                data[i, j] = float(text)
            except ValueError:
                bad_numbers[names[j]].append((line, text))
    if bad_fields:
        shown = "; ".join(bad_fields[:_MAX_LISTED_ROWS])
        more = (f" and {len(bad_fields) - _MAX_LISTED_ROWS} more"
                if len(bad_fields) > _MAX_LISTED_ROWS else "")
        problems.append(f"{name}: rows: expected {ncol} comma-separated fields per row, found "
                        f"{len(bad_fields)} row(s) with a different count: {shown}{more}")
    for j, col in enumerate(names):
        bad = bad_numbers[col]
        if bad:
            shown = ", ".join(f"line {ln} `{txt}`" for ln, txt in bad[:_MAX_LISTED_ROWS])
            more = f" and {len(bad) - _MAX_LISTED_ROWS} more" if len(bad) > _MAX_LISTED_ROWS else ""
            problems.append(f"{name}: column `{col}`: expected numbers, found {len(bad)} "
                            f"non-numeric value(s): {shown}{more}")
        skip = skip_lines | {ln for ln, _ in bad}
        nonfinite = [int(lines[i]) for i in np.flatnonzero(~np.isfinite(data[:, j]))
                     if int(lines[i]) not in skip]
        if nonfinite:
            problems.append(f"{name}: column `{col}`: expected finite numbers, found "
                            f"{len(nonfinite)} NaN or inf value(s) at {_rows_text(nonfinite)}")

    n = data.shape[0]
    if n < MIN_SAMPLES:
        problems.append(f"{name}: rows: expected at least {MIN_SAMPLES} samples, found {n}")

    t = data[:, 0]
    finite_t = np.isfinite(t)
    if n >= 2 and finite_t.all():
        dt = np.diff(t)
        nonincreasing = np.flatnonzero(dt <= 0.0)
        if nonincreasing.size:
            where = [int(lines[i + 1]) for i in nonincreasing]
            problems.append(f"{name}: column `time`: expected strictly increasing times, found "
                            f"{nonincreasing.size} decrease(s) or repeat(s) at {_rows_text(where)}")
        else:
            step = float(np.median(dt))
            off = np.flatnonzero(np.abs(dt - step) > TIME_STEP_RTOL * step)
            if off.size:
                where = [int(lines[i + 1]) for i in off]
                worst = int(off[np.argmax(np.abs(dt[off] - step))])
                problems.append(
                    f"{name}: column `time`: expected a uniform step (median {step:.6g} s, "
                    f"tolerance {TIME_STEP_RTOL:g} relative), found {off.size} step(s) off at "
                    f"{_rows_text(where)} (worst: a step of {dt[worst]:.6g} s ending at line "
                    f"{lines[worst + 1]})")
    if len(problems) > 0:
        return None
    if spinning:
        columns = {c: data[:, j].copy() for j, c in enumerate(names) if j > 0}
        return t.copy(), None, None, columns
    force = data[:, -1].copy()
    disp = data[:, 1].copy() if has_disp else None
    return t.copy(), disp, force, {}


# ----------------------------------------------------------------------------------------------
# Public API


def load_case(path: str | os.PathLike[str]) -> Case:
    """Load and validate a test case (TOML file plus the CSV it names).

    Parameters
    ----------
    path : str or path-like
        The TOML case file.

    Returns
    -------
    Case
        Frozen case with read-only arrays ``time`` [s], ``displacement`` [m] (or None) and
        ``force`` [N].

    Raises
    ------
    CaseError
        Listing every problem found in the TOML and CSV files at once.

    Examples
    --------
    >>> from estimate.case import load_case
    >>> case = load_case("examples/A1.toml")            # doctest: +SKIP
    >>> case.rig.dry_mass, case.n_samples               # doctest: +SKIP
    (1.2, 3001)
    """
    toml_path = Path(path)
    fname = toml_path.name
    try:
        raw = toml_path.read_bytes()
    except FileNotFoundError:
        raise CaseError([f"{fname}: case file not found (expected a TOML file at "
                         f"`{toml_path}`)"]) from None
    except OSError as exc:
        raise CaseError([f"{fname}: cannot read the case file ({exc.strerror or exc})"]) from None
    try:
        doc = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise CaseError([f"{fname}: expected a UTF-8 TOML file, found undecodable bytes "
                         f"({exc})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{fname}: invalid TOML: {exc}"]) from None

    ck = _Checker(fname)
    test = _read_test(ck, doc)
    excitation = None
    t_table = doc.get("test")
    if isinstance(t_table, Mapping) and t_table.get("excitation") in KNOWN_EXCITATIONS:
        excitation = t_table["excitation"]
    rig_kind = t_table.get("rig") if isinstance(t_table, Mapping) else None
    rig_kind = rig_kind if rig_kind in KNOWN_RIGS else None
    tank = _read_tank(ck, doc)
    liquid = _read_liquid(ck, doc)
    rig = _read_rig(ck, doc, excitation, rig_kind)
    pred_present, prediction = _read_prediction(ck, doc)

    problems = ck.problems
    arrays = None
    data_path: Path | None = None
    data_name = t_table.get("data") if isinstance(t_table, Mapping) else None
    if isinstance(data_name, str) and data_name.strip():
        data_path = Path(data_name)
        if not data_path.is_absolute():
            data_path = toml_path.parent / data_path
        if not data_path.is_file():
            problems.append(f"{fname}: [test] data: data file not found (expected a CSV file "
                            f"at `{data_path}`)")
        else:
            csv_problems: list[str] = []
            arrays = _read_csv(data_path, excitation, csv_problems, rig_kind)
            problems.extend(csv_problems)

    if problems:
        raise CaseError(problems)
    assert test is not None and tank is not None and liquid is not None and rig is not None
    assert arrays is not None and data_path is not None
    assert not (pred_present and prediction is None)
    time, disp, force, columns = arrays
    for arr in (time, disp, force, *columns.values()):
        if arr is not None:
            arr.flags.writeable = False
    return Case(path=toml_path.resolve(), data_path=data_path.resolve(), test=test, tank=tank,
                liquid=liquid, rig=rig, prediction=prediction, time=time, displacement=disp,
                force=force, columns=columns)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        number = float(value)
        if not math.isfinite(number):
            raise ValueError(f"cannot write a non-finite number {value!r} to a case file")
        return repr(number)
    if isinstance(value, str):
        # JSON string escapes are valid TOML basic-string escapes.
        import json
        return json.dumps(value, ensure_ascii=False)
    raise TypeError(f"cannot write {type(value).__name__} `{value!r}` to a case file")


def _toml_text(test: TestInfo, tank: Tank, liquid: Liquid, rig: Rig,
               prediction: Prediction | None, comment: str) -> str:
    out: list[str] = []
    for line in comment.splitlines():
        out.append(f"# {line}".rstrip())
    if out:
        out.append("")

    def table(name: str, rows: list[tuple[str, Any, str]]) -> None:
        out.append(f"[{name}]")
        width = max((len(k) + 3 + len(_toml_value(v)) for k, v, n in rows if n), default=0)
        for key, value, note in rows:
            text = f"{key} = {_toml_value(value)}"
            out.append(f"{text:<{width}}   # {note}" if note else text)
        out.append("")

    rows: list[tuple[str, Any, str]] = [
        ("id", test.id, ""), ("rig", test.rig, ""),
        ("data", test.data, "CSV path relative to this file"),
        ("excitation", test.excitation, ""),
    ]
    if test.note is not None:
        rows.append(("note", test.note, ""))
    table("test", rows)
    table("tank", [("shape", tank.shape, ""), ("radius", tank.radius, "m"),
                   ("fill_fraction", tank.fill_fraction, "liquid depth / tank height"),
                   ("diaphragm", tank.diaphragm, "")])
    table("liquid", [("density", liquid.density, "kg/m^3"),
                     ("kinematic_viscosity", liquid.kinematic_viscosity, "m^2/s")])
    table("rig", [("dry_mass", rig.dry_mass, "kg moving with the tank, seen by the transducer"),
                  ("gravity", rig.gravity, "m/s^2")])
    if rig.spin is not None:
        sp = rig.spin
        table("rig.spin", [("rate", sp.rate, "rad/s, table spin rate"),
                           ("radius", sp.radius, "m, tank origin from the spin axis"),
                           ("nutation_angle", sp.nutation_angle, "rad, cone half-angle"),
                           ("nutation_frequency", sp.nutation_frequency, "Hz, coning frequency"),
                           ("height", sp.height, "m, tank origin above the nutation pivot"),
                           ("tank_axis", sp.tank_axis, ""),
                           ("gravity_on", sp.gravity_on, "")])
    if rig.crank is not None:
        table("rig.crank", [("radius", rig.crank.radius, "m"),
                            ("rod_length", rig.crank.rod_length, "m"),
                            ("frequency", rig.crank.frequency, "Hz, nominal drive")])
    if prediction is not None:
        table("prediction", [("pendulum_mass", prediction.pendulum_mass, "kg"),
                             ("pendulum_length", prediction.pendulum_length, "m"),
                             ("fixed_mass", prediction.fixed_mass, "kg"),
                             ("damping_ratio", prediction.damping_ratio, "fraction of critical")])
    return "\n".join(out).rstrip("\n") + "\n"


def _csv_text(time: NDArray[np.float64], displacement: NDArray[np.float64] | None,
              force: NDArray[np.float64] | None,
              channels: Mapping[str, NDArray[np.float64]] | None = None) -> str:
    if channels is not None:
        cols = [time, *channels.values()]
        header = ",".join(["time", *channels])
    else:
        assert force is not None
        cols = [time] if displacement is None else [time, displacement]
        cols.append(force)
        header = "time,force" if displacement is None else "time,displacement,force"
    body = np.column_stack(cols)
    lines = [header]
    lines.extend(",".join(format(float(v), ".12g") for v in row) for row in body)
    return "\n".join(lines) + "\n"


def write_case(path: str | os.PathLike[str], *, test: TestInfo, tank: Tank, liquid: Liquid,
               rig: Rig, time: ArrayLike, force: ArrayLike | None = None,
               displacement: ArrayLike | None = None, prediction: Prediction | None = None,
               channels: Mapping[str, ArrayLike] | None = None,
               comment: str = "", overwrite: bool = False) -> Case:
    """Write a case file (TOML) and its CSV, then load them back.

    The CSV goes to ``test.data`` relative to the TOML file. Both files are first written to a
    temporary folder and validated with :func:`load_case`; only a valid case is moved into
    place, so an invalid one leaves no files behind.

    Parameters
    ----------
    path : str or path-like
        The TOML file to write.
    test, tank, liquid, rig, prediction
        The tables to write (``prediction`` optional).
    time : array_like
        Sample times [s].
    force : array_like, optional
        Lateral force [N] (lateral rig; required there).
    displacement : array_like, optional
        Carriage displacement [m]; omit for ``excitation = "crank"`` without a measured
        displacement.
    channels : mapping of str to array_like, optional
        Spinning rig (required there): the six channels of :data:`SPINNING_CHANNELS`
        (N, N m) and any extra columns, written in this order after ``time``.
    comment : str, optional
        Text written as ``#`` comment lines at the top of the TOML file.
    overwrite : bool, default False
        Replace existing files. When False and either file exists, nothing is written.

    Returns
    -------
    Case
        The case as loaded back from the written files.

    Raises
    ------
    FileExistsError
        If a target file exists and ``overwrite`` is False.
    CaseError
        If the written case does not validate (no files are left in place).

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.case import TestInfo, Tank, Liquid, Rig, write_case
    >>> t = np.arange(100) * 0.01
    >>> case = write_case(
    ...     "/tmp/demo.toml", overwrite=True,
    ...     test=TestInfo(id="demo", rig="lateral", data="demo.csv", excitation="measured"),
    ...     tank=Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False),
    ...     liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
    ...     rig=Rig(dry_mass=1.2, gravity=9.80665),
    ...     time=t, displacement=0.005 * np.sin(2 * np.pi * 2 * t),
    ...     force=np.sin(2 * np.pi * 2 * t))                                # doctest: +SKIP
    """
    toml_path = Path(path)
    csv_rel = Path(test.data)
    csv_path = csv_rel if csv_rel.is_absolute() else toml_path.parent / csv_rel
    if not overwrite:
        existing = [str(p) for p in (toml_path, csv_path) if p.exists()]
        if existing:
            raise FileExistsError(f"refusing to overwrite existing file(s) {', '.join(existing)}; "
                                  "pass `overwrite=True` to replace them")
    t = np.asarray(time, dtype=float)
    if test.rig == "spinning":
        if channels is None or force is not None or displacement is not None:
            raise ValueError("a spinning-rig case takes `channels` (time series of "
                             + ", ".join(SPINNING_CHANNELS) + "), not `force` or `displacement`")
        ch = {str(k): np.asarray(v, dtype=float) for k, v in channels.items()}
        bad = {k: v.shape for k, v in ch.items() if v.shape != t.shape}
        if t.ndim != 1 or bad:
            raise ValueError(f"expected 1-D `time` and channels of its length {t.shape}, found "
                             + ", ".join(f"`{k}` {v}" for k, v in bad.items()))
        toml_text = _toml_text(test, tank, liquid, rig, prediction, comment)
        csv_text = _csv_text(t, None, None, ch)
    else:
        if force is None or channels is not None:
            raise ValueError("a lateral-rig case takes `force` (and `displacement`), "
                             "not `channels`")
        f = np.asarray(force, dtype=float)
        d = None if displacement is None else np.asarray(displacement, dtype=float)
        if t.ndim != 1 or f.shape != t.shape or (d is not None and d.shape != t.shape):
            raise ValueError(f"expected 1-D `time`, `force` (and `displacement`) of equal "
                             f"length, found shapes {t.shape}, {f.shape}"
                             + ("" if d is None else f", {d.shape}"))
        toml_text = _toml_text(test, tank, liquid, rig, prediction, comment)
        csv_text = _csv_text(t, d, f)

    toml_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=toml_path.parent, prefix=".case-") as tmp:
        tmp_toml = Path(tmp) / toml_path.name
        tmp_csv = Path(tmp) / (csv_rel.name if csv_rel.is_absolute() else csv_rel)
        tmp_csv.parent.mkdir(parents=True, exist_ok=True)
        tmp_toml.write_text(toml_text, encoding="utf-8")
        tmp_csv.write_text(csv_text, encoding="utf-8")
        if csv_rel.is_absolute():
            # load_case reads the absolute path; validate the temporary copy instead.
            tmp_toml.write_text(toml_text.replace(_toml_value(test.data),
                                                  _toml_value(tmp_csv.name)), encoding="utf-8")
        load_case(tmp_toml)  # raises CaseError; the temporary folder is then removed
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(str(tmp_csv), str(csv_path))
        tmp_toml.write_text(toml_text, encoding="utf-8")
        shutil.move(str(tmp_toml), str(toml_path))
    return load_case(toml_path)
