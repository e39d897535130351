"""Test-case files: a TOML description plus a CSV of samples.

A case file describes one tank test (tank, liquid, rig, optional analog prediction) and names a
CSV file with the measured samples. The format is the one of the estimation issue::

    [test]
    id = "A1"
    rig = "lateral"              # "lateral" now; "spinning" later
    data = "A1.csv"              # CSV path relative to this file
    excitation = "measured"      # "measured": CSV has displacement; "crank": from [rig.crank]
    starts_at_rest = true        # optional; absent: detected from the first 0.1 s
    resample_hz = 500.0          # optional: timestamps that jitter; see below

    [tank]
    shape = "sphere"             # "sphere" | "cylinder" | "capsule" | "rectangular"
    radius = 0.1016              # m (sphere, cylinder, capsule)
    fill_fraction = 0.6          # liquid depth / tank height
    diaphragm = false
    # length = 0.3               # m: cylinder inside height; rectangular: along the motion
    # cylinder_length = 0.1      # m: capsule, straight section between the domes
    # width = 0.2                # m: rectangular, across the motion
    # height = 0.3               # m: rectangular, inside height

    [liquid]
    density = 998.2              # kg/m^3
    kinematic_viscosity = 1.004e-6   # m^2/s

    [rig]
    dry_mass = 1.2               # kg; "estimate" (or absent): not weighed, estimated
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
``excitation = "crank"``. Keys not listed above are reported with the nearest known name
(a warning, an error under ``--strict``) and otherwise ignored (``[test] note`` is kept).

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

With these numbers alone the table spins at ``rate`` and cones at ``nutation_angle`` from the
first sample. A test as the SSTR runs it spins the table up and ramps the coning in; the rig
motion then comes from the record or from a schedule (optional keys of ``[rig.spin]``; the
numbers above stay the nominal, final values)::

    spin_angle = "table_angle"   # CSV column: the table's spin angle (rad), or
    spin_rate = "table_rate"     #   the table's spin rate (rad/s), integrated
    nutation_phase = "precession"  # CSV column: phase of the coning about the vertical (rad)
    cone_angle = "cone"          # CSV column: cone half-angle of the table axis (rad)
    spin_up = 12.0               # s: the rate rises smoothly from 0 to `rate` from t[0]
    nutation_ramp = 5.0          # s: the cone angle rises smoothly from 0 to `nutation_angle`
    nutation_start = 12.0        # s after t[0] (default: the end of the spin-up)

Measured angles are unwrapped, smoothed without phase lag and differentiated twice
(:func:`estimate.data.spin.rig_angle_derivatives`: a smoothing spline chosen by
cross-validation); a measured spin angle excludes ``spin_up`` and a measured cone angle
``nutation_ramp``.

``[test] initial_state`` says where the liquid starts: ``"rest"`` (default: at rest in the
tank), ``"steady"`` (at the relative equilibrium of the analog under the rig motion at the
first sample: the pendulum swung out on its cone, a rotor turning with the tank; the
record starts once the liquid has settled) or ``"free"`` (estimated with the parameters).

:func:`load_case` (:mod:`estimate.data.reader`) validates everything and raises one
:class:`CaseError` listing every problem; input files are never modified. :func:`write_case`
writes a case (TOML + CSV), e.g. for generated data, and refuses to overwrite existing files
unless asked to.

What the rig can run
--------------------
``slosh design`` (:mod:`estimate.design`) recommends the next test among drives the rig can
run; an optional ``[rig.limits]`` table says what that is (the keys a design on this rig
needs are required there, every key present must be a positive number)::

    [rig.limits]
    stroke = 0.1                 # m, total carriage travel (it stays within +/- stroke/2)
    velocity = 0.5               # m/s, largest carriage speed
    acceleration = 5.0           # m/s^2, largest carriage acceleration
    duration = 60.0              # s, longest record
    sample_rate = 100.0          # Hz, optional: rate of the drive file (default: the record's)
    spin_rate = 10.0             # rad/s, spinning rig: largest table spin rate
    nutation_frequency = 1.0     # Hz, spinning rig: largest coning frequency (either sign)
    cone_angle = 0.1             # rad, spinning rig: largest cone half-angle

Timestamps and the carriage motion's band
-----------------------------------------
``[test] resample_hz = 500.0`` accepts timestamps that are not uniform (receive times that
jitter, a polled logger) and brings the record onto a uniform time base at that rate
(:mod:`estimate.data.timebase`: receive times of a clocked stream are placed on the line
through them, truly irregular samples are interpolated); what was done is kept in
:attr:`Case.notes` and printed in the fit report. ``[test] motion_band_hz`` (Hz, optional)
gives the highest frequency of the carriage motion when the record cannot tell it (see
:func:`estimate.data.signals.motion_band`); ``slosh fit --motion-band`` sets it too.

Six-axis records of any tank motion
-----------------------------------
A lateral-rig case whose tank is moved and measured in 3-D (a carriage, shaker table,
hexapod or robot arm carrying the tank on a six-axis force/torque transducer) names its
motion columns in a ``[rig.motion]`` table; the case is then fitted on
:class:`analogs.MotionRig`::

    [rig.motion]                 # CSV columns of the measured motion (at least one)
    x = "x"                      # m, the tank origin's travel along the lab x axis
    y = "y"                      # m, along lab y
    z = "z"                      # m, vertical
    roll = "roll"                # rad, z-y-x attitude angles of the tank frame
    pitch = "pitch"              # rad
    yaw = "yaw"                  # rad

    [rig.transducer]             # optional: where the transducer measures (default 0)
    x = 0.0                      # m, its reference point in tank axes (torques about it)
    y = 0.0
    z = -0.05
    roll = 0.0                   # rad, its axes turned from the tank axes (z-y-x)
    pitch = 0.0
    yaw = 3.141592653589793      # a transducer mounted turned by 180 deg about the tank axis

Its CSV has ``time``, the motion columns and any non-empty subset of the six channels
``force_x,force_y,force_z,torque_x,torque_y,torque_z`` (N, N m, in the transducer's axes), in
any order; other columns are reported like unknown keys (a warning, an error under
``--strict``). Each motion column is smoothed without phase lag and differentiated twice
(:func:`estimate.data.signals.displacement_derivatives`), as the lateral carriage's
displacement is. Loading checks, for each force channel along a translation, that the
force has the sign of mass times acceleration during the large-motion part
(:func:`estimate.data.motion.sign_problems`).

Validation limits
-----------------
* Time must increase strictly and be uniform: every step must be within
  :data:`TIME_STEP_RTOL` (1e-3) of the median step, relative. This admits timestamps printed
  with a few decimals and floating-point round-off, and rejects dropped or repeated samples
  (a dropped sample is a 100% step error). ``[test] resample_hz`` lifts the uniformity
  check (see above).
* At least :data:`MIN_SAMPLES` (50) samples: fewer cannot hold a few periods of a 1-5 Hz drive at
  100 Hz sampling, nor the padding that zero-phase filters and Welch spectra need.
* At least :data:`MIN_DURATION` (0.1 s): a shorter record cannot hold one period of a slosh
  mode (those of test tanks lie below about 10 Hz); a record of nanoseconds is a time column
  in the wrong unit, and would ask the 10 Hz low-pass filter for a design at 1e12 Hz sampling.
* CSV problems name the line of the file (the header is line 1).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from analogs.errors import InputError

__all__ = [
    "KNOWN_EXCITATIONS",
    "KNOWN_INITIAL_STATES",
    "KNOWN_RIGS",
    "KNOWN_SHAPES",
    "LIMIT_UNITS",
    "MIN_DURATION",
    "MIN_SAMPLES",
    "PHYSICAL_RANGES",
    "TIME_STEP_RTOL",
    "Case",
    "CaseError",
    "DRY_MASS_ESTIMATE",
    "Crank",
    "Limits",
    "Liquid",
    "Motion",
    "Prediction",
    "Rig",
    "SPINNING_CHANNELS",
    "SHAPE_KEYS",
    "SPIN_COLUMN_KEYS",
    "Spin",
    "Tank",
    "TestInfo",
    "Transducer",
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
KNOWN_INITIAL_STATES: tuple[str, ...] = ("rest", "steady", "free")
"""Values accepted for ``[test] initial_state``."""
SPIN_COLUMN_KEYS: tuple[str, ...] = ("spin_angle", "spin_rate", "nutation_phase", "cone_angle")
"""Keys of ``[rig.spin]`` that name CSV columns of measured rig motion."""
KNOWN_SHAPES: tuple[str, ...] = ("sphere", "cylinder", "capsule", "rectangular")
"""Values accepted for ``[tank] shape``."""
MIN_SAMPLES: int = 50
"""Minimum number of CSV samples (see the module docstring for why)."""
MIN_DURATION: float = 0.1
"""Shortest record [s] (see the module docstring for why)."""
TIME_STEP_RTOL: float = 1e-3
"""Allowed deviation of each time step from the median step, relative to the median step."""
PHYSICAL_RANGES: dict[str, tuple[float, float, str]] = {
    "kg": (1e-6, 1e6, "mass"),
    "m": (1e-6, 1e3, "length"),
    "m/s^2": (1e-6, 1e3, "acceleration"),
    "kg/m^3": (1e-3, 1e5, "density"),
    "m^2/s": (1e-12, 1.0, "kinematic viscosity"),
    "Hz": (1e-6, 1e3, "frequency"),
    "rad/s": (1e-6, 1e3, "rate"),
    "s": (1e-6, 1e6, "duration"),
    "- (fraction of critical)": (0.0, 10.0, "damping ratio"),
    "N": (0.0, 1e9, "force"),
    "N m": (0.0, 1e9, "torque"),
    "kg m^2": (1e-12, 1e9, "moment of inertia"),
    "N m s/rad": (0.0, 1e9, "rotational damping"),
    "N m/rad": (0.0, 1e9, "rotational stiffness"),
}
"""Values accepted for a number of each unit in a case or spacecraft file: (smallest
positive value, largest magnitude, what it is). Wide enough for any tank test or spacecraft
(a milligram to a thousand tonnes, a micrometre to a kilometre, up to 1000 rad/s), narrow
enough that products and squares of them stay finite in double precision, and a value in
the wrong unit or with a slipped exponent (``dry_mass = 1e30``) is refused before any
computation; the smallest value applies to quantities that must be positive."""
DRY_MASS_ESTIMATE: str = "estimate"
"""``[rig] dry_mass`` of a container that was not weighed (lateral rig): the fit estimates
the rigid mass; also what an absent key means."""



class CaseError(InputError):
    """A case file (TOML or its data file) is invalid.

    Its message is the problem when there is one, else a count and one line per problem.

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
        if count == 1:  # one line, as every other input error
            super().__init__(self.problems[0])
            return
        head = f"{count} problems in case:"
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
    starts_at_rest : bool or None
        ``[test] starts_at_rest``: whether the tank and carriage are at rest at the first
        sample; ``None`` (absent) lets the estimation detect a quiet start.
    initial_state : str or None
        ``[test] initial_state``, one of :data:`KNOWN_INITIAL_STATES`: where the liquid
        (the analog's coordinates) starts; ``None`` (absent) means ``"rest"``.
    resample_hz : float or None
        ``[test] resample_hz``: the timestamps need not be uniform; the record is brought
        onto a uniform time base at this rate [Hz] (:mod:`estimate.data.timebase`).
    motion_band_hz : float or None
        ``[test] motion_band_hz``: the highest frequency of the carriage motion [Hz],
        which sets the displacement filter's cutoff (filtered input) and the carriage
        spline's knot spacing (estimated input); ``None``: chosen from the record
        (:func:`estimate.data.signals.motion_band`).
    """

    __test__ = False  # not a pytest test class despite the name

    id: str
    rig: str
    data: str
    excitation: str
    note: str | None = None
    starts_at_rest: bool | None = None
    initial_state: str | None = None
    resample_hz: float | None = None
    motion_band_hz: float | None = None


@dataclass(frozen=True)
class Tank:
    """The ``[tank]`` table.

    Which size keys a shape needs (m): ``sphere`` its ``radius``; ``cylinder`` (upright,
    flat bottom and top) its ``radius`` and inside height ``length``; ``capsule`` (a
    cylinder with hemispherical ends, upright) its ``radius`` and the length of its
    straight section ``cylinder_length`` (inside height ``cylinder_length + 2 radius``);
    ``rectangular`` (an upright box) its inside ``length`` along the motion, ``width``
    across it and ``height``.

    Attributes
    ----------
    shape : str
        One of :data:`KNOWN_SHAPES`.
    radius : float or None
        Tank radius [m] (sphere, cylinder, capsule); None for a rectangular tank.
    fill_fraction : float
        Liquid depth / tank height, in (0, 1) [-].
    diaphragm : bool
        Whether the tank has an elastomeric diaphragm.
    length : float or None
        Cylinder: inside height [m]; rectangular tank: inside length along the motion [m].
    cylinder_length : float or None
        Capsule: length of the cylindrical section between the domes [m] (>= 0).
    width, height : float or None
        Rectangular tank: inside width across the motion and inside height [m].
    """

    shape: str
    radius: float | None
    fill_fraction: float
    diaphragm: bool
    length: float | None = None
    cylinder_length: float | None = None
    width: float | None = None
    height: float | None = None

    def geometry(self):
        """The tank as an :mod:`analogs.tank` geometry (:class:`~analogs.tank.Sphere`,
        :class:`~analogs.tank.Cylinder`, :class:`~analogs.tank.Capsule` or
        :class:`~analogs.tank.Rectangular`): volumes, liquid mass and the modal prediction
        all come from it."""
        from analogs.tank import Capsule, Cylinder, Rectangular, Sphere

        if self.shape == "sphere":
            return Sphere(self.radius)
        if self.shape == "cylinder":
            return Cylinder(self.radius, self.length)
        if self.shape == "capsule":
            return Capsule(self.radius, self.cylinder_length)
        return Rectangular(self.length, self.width, self.height)

    def liquid_mass(self, density: float) -> float:
        """Mass of the liquid [kg] of ``density`` [kg/m^3] at :attr:`fill_fraction`."""
        return self.geometry().liquid_mass(self.fill_fraction, density)

    @property
    def depth(self) -> float:
        """Liquid depth [m] (``fill_fraction`` of the tank's height)."""
        return self.fill_fraction * self.geometry().height

    @property
    def size_text(self) -> str:
        """The tank's size as reports print it (``"sphere R = 0.1016 m"``,
        ``"rectangular 0.4 x 0.2 x 0.3 m"``)."""
        if self.shape == "rectangular":
            return f"rectangular {self.length:g} x {self.width:g} x {self.height:g} m"
        extra = (f", length {self.length:g} m" if self.shape == "cylinder" else
                 f", cylinder length {self.cylinder_length:g} m" if self.shape == "capsule"
                 else "")
        return f"{self.shape} R = {self.radius:g} m{extra}"


#: Size keys of ``[tank]`` by shape (m), besides ``fill_fraction`` and ``diaphragm``.
SHAPE_KEYS: dict[str, tuple[str, ...]] = {
    "sphere": ("radius",), "cylinder": ("radius", "length"),
    "capsule": ("radius", "cylinder_length"), "rectangular": ("length", "width", "height")}


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
    spin_angle, spin_rate, nutation_phase, cone_angle : str or None
        CSV columns of the measured rig motion: the table's spin angle [rad] or rate
        [rad/s] (not both), the nutation phase [rad] and the cone half-angle [rad].
    spin_up : float, default 0
        Time over which the spin rate rises from 0 to ``rate`` from the first sample [s].
    nutation_ramp : float, default 0
        Time over which the cone angle rises from 0 to ``nutation_angle`` [s].
    nutation_start : float or None
        Start of the cone-angle ramp after the first sample [s]; ``None``: the end of the
        spin-up.
    """

    rate: float
    radius: float
    nutation_angle: float
    nutation_frequency: float
    height: float = 0.0
    tank_axis: str = "spin"
    gravity_on: bool = True
    spin_angle: str | None = None
    spin_rate: str | None = None
    nutation_phase: str | None = None
    cone_angle: str | None = None
    spin_up: float = 0.0
    nutation_ramp: float = 0.0
    nutation_start: float | None = None

    @property
    def columns(self) -> dict[str, str]:
        """CSV columns of measured rig motion by key (``{"spin_angle": "table_angle"}``)."""
        return {k: getattr(self, k) for k in SPIN_COLUMN_KEYS if getattr(self, k) is not None}

    @property
    def motion(self) -> str:
        """``"constant"`` (rates and cone angle from the first sample, as parameters) or
        ``"input"`` (measured columns or schedules drive the rig's input signals); see
        :class:`analogs.SpinningRig`."""
        scheduled = self.spin_up > 0 or self.nutation_ramp > 0 or bool(self.nutation_start)
        return "input" if self.columns or scheduled else "constant"

    @property
    def ramp_start(self) -> float:
        """Start of the cone-angle ramp after the first sample [s]."""
        return self.spin_up if self.nutation_start is None else self.nutation_start


@dataclass(frozen=True)
class Motion:
    """The ``[rig.motion]`` table: the CSV columns of the tank's measured motion
    (:class:`analogs.MotionRig`), by axis; ``None`` for an axis that does not move.

    Attributes
    ----------
    x, y, z : str or None
        Columns of the tank origin's position along the lab axes [m].
    roll, pitch, yaw : str or None
        Columns of the tank frame's z-y-x attitude angles [rad].
    """

    x: str | None = None
    y: str | None = None
    z: str | None = None
    roll: str | None = None
    pitch: str | None = None
    yaw: str | None = None

    @property
    def columns(self) -> dict[str, str]:
        """CSV column by axis, in :data:`analogs.motion_rig.MOTION_AXES` order."""
        from analogs.motion_rig import MOTION_AXES

        return {a: getattr(self, a) for a in MOTION_AXES if getattr(self, a) is not None}

    @property
    def axes(self) -> tuple[str, ...]:
        """The axes that are measured (the rig's inputs)."""
        return tuple(self.columns)


@dataclass(frozen=True)
class Transducer:
    """The optional ``[rig.transducer]`` table: the six-axis transducer's reference point
    ``x, y, z`` [m, tank axes] and the turn of its axes from the tank axes ``roll, pitch,
    yaw`` [rad, z-y-x]; every value defaults to 0 (the tank origin, the tank axes)."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0


#: Keys of ``[rig.limits]`` with their units, in the order they are written.
LIMIT_UNITS: dict[str, str] = {"stroke": "m", "velocity": "m/s", "acceleration": "m/s^2",
                               "duration": "s", "sample_rate": "Hz", "spin_rate": "rad/s",
                               "nutation_frequency": "Hz", "cone_angle": "rad"}


@dataclass(frozen=True)
class Limits:
    """The optional ``[rig.limits]`` table: what the rig can run (see "What the rig can run"
    in the module docstring). Every value is positive; ``None`` when absent.

    Attributes
    ----------
    stroke : float or None
        Total carriage travel [m]; the carriage stays within +/- ``stroke / 2`` of its centre.
    velocity, acceleration : float or None
        Largest carriage speed [m/s] and acceleration [m/s^2].
    duration : float or None
        Longest record [s].
    sample_rate : float or None
        Rate of the rig's drive file [Hz].
    spin_rate, nutation_frequency, cone_angle : float or None
        Spinning rig: largest spin rate [rad/s], coning frequency [Hz] and cone half-angle
        [rad].
    """

    stroke: float | None = None
    velocity: float | None = None
    acceleration: float | None = None
    duration: float | None = None
    sample_rate: float | None = None
    spin_rate: float | None = None
    nutation_frequency: float | None = None
    cone_angle: float | None = None


@dataclass(frozen=True)
class Rig:
    """The ``[rig]`` table.

    Attributes
    ----------
    dry_mass : float or None
        Mass moving with the tank and seen by the force transducer [kg]; ``None`` when
        the container was not weighed (``dry_mass = "estimate"`` or absent, lateral rig
        only): the fit then estimates it.
    gravity : float
        Gravitational acceleration [m/s^2].
    crank : Crank or None
        The ``[rig.crank]`` table when present.
    spin : Spin or None
        The ``[rig.spin]`` table (spinning rig only).
    limits : Limits or None
        The ``[rig.limits]`` table when present.
    motion : Motion or None
        The ``[rig.motion]`` table (a six-axis record of a tank moved in 3-D) when present.
    transducer : Transducer or None
        The ``[rig.transducer]`` table when present (only with ``motion``).
    """

    dry_mass: float | None
    gravity: float
    crank: Crank | None = None
    spin: Spin | None = None
    limits: Limits | None = None
    motion: Motion | None = None
    transducer: Transducer | None = None


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
        Carriage displacement [m]; None when the CSV has no displacement column (and for a
        six-axis record, whose motion is in :attr:`columns`).
    force : numpy.ndarray or None
        Measured lateral force [N] (lateral rig); None for the spinning rig and a six-axis
        record.
    columns : mapping of str to numpy.ndarray
        The CSV columns besides ``time`` of a spinning-rig case or a six-axis record
        (``[rig.motion]``; empty for a lateral case); read them through :attr:`channels`.
    notes : tuple of str
        What loading did to the record (e.g. the new time base of ``[test] resample_hz``);
        fit reports print them.
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
    notes: tuple[str, ...] = ()

    @property
    def channels(self) -> dict[str, NDArray[np.float64]]:
        """Measured signals by output name: ``{"force_x": force}`` for the lateral rig, the
        six force/torque channels (and any extra CSV columns) for the spinning rig and for a
        six-axis record of a tank moved in 3-D (``[rig.motion]``: the channels it has, its
        motion columns and any other columns)."""
        if self.test.rig == "lateral" and self.rig.motion is None:
            return {} if self.force is None else {"force_x": self.force}
        return dict(self.columns)

    @property
    def spin(self) -> Spin | None:
        """The ``[rig.spin]`` table, or None."""
        return self.rig.spin

    @property
    def motion(self) -> Motion | None:
        """The ``[rig.motion]`` table (a six-axis record of a tank moved in 3-D), or None."""
        return self.rig.motion

    @property
    def crank(self) -> Crank | None:
        """The ``[rig.crank]`` table, or None."""
        return self.rig.crank

    @property
    def liquid_mass(self) -> float:
        """Mass of the liquid in the tank [kg]: density times the volume below the fill
        depth of :meth:`Tank.geometry`."""
        return self.tank.liquid_mass(self.liquid.density)

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
