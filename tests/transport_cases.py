"""Transport-move test cases as a robot-carried tank makes them (issue 25).

A tank at rest is moved by a jerk-limited rest-to-rest transport move (``TransportMove``),
really followed by a servo (``ServoFollow``: the command lagged and rippled), then left
to ring down. The force comes from a six-axis transducer (``force_sensor``: internal
2nd-order low-pass, quantisation, white + 1/f noise, lines, offset) on a stream that lags
the motion stream (``sensor_delay``); the motion is either the encoders' reading of the
true motion (``encoder_position``) or the planned path (the command). The container mass
is not written in the case (``dry_mass = "estimate"``).

Everything here is built from ``reference_models`` (hand-written equations, SciPy) and
``reference_rig_records``; the truth comes from closed-form tank results
(``cylinder_first_mode``, ``sphere_liquid_mass``) or from given values, never from the
project's tank code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import reference_models as ref
import reference_rig_records as rr

G = 9.80665
WATER = 998.2


@dataclass(frozen=True)
class TransportTank:
    """A tank for transport records: its case-file geometry (``shape``, ``radius`` m,
    ``fill`` depth fraction of a sphere or of a cylinder as tall as its diameter), the first
    mode's truth (``mode_mass`` kg, ``length`` m, ``zeta``), the liquid mass (kg), the
    container mass (kg) and the transducer's noise (``white``, ``pink``, ``quantum`` N;
    ``lines`` of (Hz, N))."""

    name: str
    shape: str
    radius: float
    fill: float
    liquid_mass: float
    mode_mass: float
    length: float
    zeta: float
    container: float
    white: float = 0.01
    pink: float = 0.01
    quantum: float = 0.005
    lines: tuple[tuple[float, float], ...] = ((17.3, 0.004), (50.0, 0.003))
    cutoff_hz: float = 60.0
    prediction: object = field(default=None, compare=False)

    @property
    def fixed_mass(self) -> float:
        """The liquid that moves with the tank: all of it but the first mode [kg]."""
        return self.liquid_mass - self.mode_mass

    @property
    def frequency(self) -> float:
        """The first mode's small-swing natural frequency [Hz]."""
        return math.sqrt(G / self.length) / (2 * math.pi)


def small_cylinder() -> TransportTank:
    """A small water cylinder a robot carries: radius 5 cm, 8 cm of water (80 % of a
    cylinder as tall as its diameter), closed-form first mode (about 3.0 Hz, 0.18 kg of
    0.63 kg), a 0.45 kg container, a small six-axis sensor (5 mN steps)."""
    R, fill = 0.05, 0.8
    mode = rr.cylinder_first_mode(R, fill * 2 * R, WATER, G)
    return TransportTank("cylinder_r50", "cylinder", R, fill, mode["liquid_mass"],
                         mode["mass"], mode["length"], 0.006, 0.45, cutoff_hz=60.0)


def sphere_8in() -> TransportTank:
    """The 8-inch test sphere at 60 % fill: liquid mass from the cap volume, the first mode
    of the seed's table (1.338 kg, 0.057 m, about 2.09 Hz), a 1.2 kg container, a sensor
    with 10 mN steps and a 40 Hz internal filter."""
    R, fill = 0.1016, 0.6
    return TransportTank("sphere_8in", "sphere", R, fill, rr.sphere_liquid_mass(R, fill, WATER),
                         1.338, 0.057, 0.008, 1.2, white=0.015, pink=0.015, quantum=0.010,
                         lines=((23.0, 0.006), (50.0, 0.004)), cutoff_hz=40.0)


def large_cylinder() -> TransportTank:
    """A metre-class water cylinder: radius 0.4 m, 0.48 m of water (60 % of 0.8 m), about
    1.05 Hz, 87 kg of 241 kg, a 60 kg container, a large sensor (0.2 N noise, 50 mN steps)."""
    R, fill = 0.4, 0.6
    mode = rr.cylinder_first_mode(R, fill * 2 * R, WATER, G)
    return TransportTank("cylinder_r400", "cylinder", R, fill, mode["liquid_mass"],
                         mode["mass"], mode["length"], 0.003, 60.0, white=0.2, pink=0.2,
                         quantum=0.05, lines=((11.0, 0.1), (50.0, 0.08)), cutoff_hz=80.0)


@dataclass(frozen=True)
class TransportRecord:
    """What a transport record was made of: the case, the true analog and lags."""

    case: object
    tank: TransportTank
    #: The lag between the case's displacement column and its force column [s]: the
    #: stream lag plus the sensor filter's group delay (plus the servo lag for a planned
    #: path).
    lag: float
    sim: dict = field(repr=False)

    @property
    def truth(self) -> dict[str, float]:
        t = self.tank
        return {"rig.dry_mass": t.container, "fixed.mass": t.fixed_mass, "p1.mass": t.mode_mass,
                "p1.length": t.length, "frequency": t.frequency, "zeta": t.zeta,
                "lag": self.lag, "liquid_mass": t.liquid_mass,
                "rigid_mass": t.container + t.fixed_mass}


def transport_record(folder: Path, tank: TransportTank, *, distance: float = 0.4,
                     duration: float = 0.8, start: float = 1.0, decay: float = 12.0,
                     rate: float = 500.0, sensor_delay: float = 0.018,
                     servo_lag: float = 0.012, ripple: float = 2e-5,
                     ripple_frequency: float = 18.0, planned: bool = False, seed: int = 0,
                     name: str | None = None, dry_mass: float | str = "estimate",
                     encoder_noise: float = 1e-5, encoder_resolution: float = 5e-6,
                     jitter: float = 0.0, **case_options) -> TransportRecord:
    """Write a transport record of ``tank`` to ``folder``: at rest for ``start`` s, a move
    of ``distance`` m in ``duration`` s, then ``decay`` s of free decay, sampled at ``rate``
    Hz on a uniform grid; the force stream lags by ``sensor_delay`` s (plus its filter's
    group delay); the displacement column is the encoder reading of the true motion, or
    with ``planned`` the commanded path (which leads the true motion by ``servo_lag``).
    ``dry_mass`` is what the case file says (default ``"estimate"``: unknown); ``jitter``
    (s): the time column holds receive times +/- ``jitter`` about the sampling instants
    (:func:`reference_rig_records.receive_times`) and the case asks for ``resample_hz``."""
    from estimate.data import write_case
    from estimate.data.case import Liquid, Rig, Tank, TestInfo

    rng = np.random.default_rng(seed)
    n = int(round((start + duration + decay) * rate)) + 1
    t = np.arange(n) / rate
    move = rr.TransportMove(distance, duration, start)
    true = rr.ServoFollow(move, lag=servo_lag, ripple=ripple, ripple_frequency=ripple_frequency)
    c = ref.hinge_damping(tank.mode_mass, tank.length, tank.zeta, gravity=G)
    sim = ref.simulate_lateral(t, true, pendulums=[ref.Pendulum(tank.mode_mass, tank.length,
                                                                damping=c)],
                               fixed_mass=tank.fixed_mass, dry_mass=tank.container, gravity=G,
                               sensor_delay=sensor_delay)
    force = rr.force_sensor(t, sim["force_clean"], rng=rng, cutoff_hz=tank.cutoff_hz,
                            quantum=tank.quantum, white=tank.white, pink=tank.pink,
                            lines=tank.lines, offset=0.0)
    lag = sensor_delay + rr.sensor_group_delay(tank.cutoff_hz)
    if planned:
        x = move(t)[0]
        lag += servo_lag
    else:
        x = rr.encoder_position(sim["displacement_clean"], rng=rng, noise=encoder_noise,
                                resolution=encoder_resolution)
    name = name or f"{tank.name}_{'planned' if planned else 'measured'}_{seed}"
    stamps = t
    if jitter > 0:
        stamps = rr.receive_times(t, jitter=jitter, rng=rng)
        case_options = {"resample_hz": rate, **case_options}
    case = write_case(
        Path(folder) / f"{name}.toml",
        test=TestInfo(id=name, rig="lateral", data=f"{name}.csv", excitation="measured",
                      note="SYNTHETIC transport record (tests/transport_cases.py)",
                      **case_options),
        tank=Tank(shape=tank.shape, radius=tank.radius, fill_fraction=tank.fill,
                  diaphragm=False,
                  length=2 * tank.radius if tank.shape == "cylinder" else None),
        liquid=Liquid(density=WATER, kinematic_viscosity=1.004e-6),
        rig=Rig(dry_mass=None if dry_mass == "estimate" else dry_mass, gravity=G), time=stamps,
        force=force, displacement=x,
        prediction=tank.prediction,
        comment="SYNTHETIC transport record (tests/transport_cases.py)", overwrite=True)
    return TransportRecord(case, tank, lag, sim)
