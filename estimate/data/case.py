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
    decimate = 5                 # optional: fit every 5th sample after an anti-alias low-pass

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
``[test] decimate = 5`` (an integer, optional) fits a record sampled far above the slosh band
on every 5th sample, after a zero-phase anti-alias low-pass of every channel
(:mod:`estimate.data.decimation`): a 60 s, 500 Hz record in a third of the time and memory,
with the same estimates and standard errors. The record may then hold that many times more
samples than the memory budget allows a fit.

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
(:func:`estimate.data.motion_sign.sign_problems`).

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

from .case_tables import (
    LIMIT_UNITS,
    SHAPE_KEYS,
    SPIN_COLUMN_KEYS,
    Crank,
    Limits,
    Liquid,
    Motion,
    Prediction,
    Rig,
    Spin,
    Tank,
    TestInfo,
    Transducer,
)

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
    def recorded_rate(self) -> float:
        """The rate the record was taken at [Hz]: :attr:`sample_rate` times ``[test]
        decimate`` (the record is held decimated)."""
        return self.sample_rate * (self.test.decimate or 1)

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.time.size)
