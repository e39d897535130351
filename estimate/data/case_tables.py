"""The tables of a case file, one class each: ``[test]`` (:class:`TestInfo`), ``[tank]``
(:class:`Tank`), ``[liquid]``, ``[rig.crank]``, ``[rig.spin]``, ``[rig.limits]``,
``[rig.motion]``, ``[rig.transducer]``, ``[rig]`` and ``[prediction]``, in SI units.
:mod:`estimate.data.case` describes the file format and holds the
:class:`~estimate.data.case.Case` they make up; :mod:`estimate.data.reader` reads them."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LIMIT_UNITS", "SHAPE_KEYS", "SPIN_COLUMN_KEYS", "Crank", "Limits", "Liquid",
           "Motion", "Prediction", "Rig", "Spin", "Tank", "TestInfo", "Transducer"]

SPIN_COLUMN_KEYS: tuple[str, ...] = ("spin_angle", "spin_rate", "nutation_phase", "cone_angle")
"""Keys of ``[rig.spin]`` that name CSV columns of measured rig motion."""


@dataclass(frozen=True)
class TestInfo:
    """The ``[test]`` table.

    Attributes
    ----------
    id : str
        Test identifier, e.g. ``"A1"``.
    rig : str
        Rig kind, one of :data:`~estimate.data.case.KNOWN_RIGS`.
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
        ``[test] initial_state``, one of :data:`~estimate.data.case.KNOWN_INITIAL_STATES`: where the liquid
        (the analog's coordinates) starts; ``None`` (absent) means ``"rest"``.
    resample_hz : float or None
        ``[test] resample_hz``: the timestamps need not be uniform; the record is brought
        onto a uniform time base at this rate [Hz] (:mod:`estimate.data.timebase`).
    decimate : int or None
        ``[test] decimate``: the record is low-passed and every ``decimate``-th sample kept
        for the fit (:mod:`estimate.data.decimation`); ``None`` (absent): all samples.
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
    decimate: int | None = None


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
        One of :data:`~estimate.data.case.KNOWN_SHAPES`.
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
