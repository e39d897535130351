"""Test cases written from the independent reference simulator (``reference_models``).

The data are synthetic: hand-written equations integrated by SciPy, never the project's
own model code.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import reference_models as ref

from estimate.data import write_case
from estimate.data.case import Crank as CrankTable
from estimate.data.case import Liquid, Prediction, Rig, Tank, TestInfo

#: The seed's 8-inch sphere at 60 % fill (Table 8).
PREDICTION_60 = Prediction(pendulum_mass=1.338, pendulum_length=0.057, fixed_mass=1.456,
                           damping_ratio=0.00703)
G = 9.80665


def make_case(folder: Path, name: str, excitation, *, pendulums=(), fixed_mass=1.456,
              dry_mass=1.2, noise=0.01, displacement_noise=2e-5, duration=30.0, rate=100.0,
              seed=0, prediction: Prediction | None = PREDICTION_60, fill=0.6,
              diaphragm=False, radius=0.1016, **effects):
    """Simulate with ``reference_models.simulate_lateral`` and write ``name.toml``/``.csv``.

    ``excitation`` is a ``reference_models`` excitation; a ``ref.Crank`` writes a crank
    case without displacement column; ``radius`` is the sphere's radius [m]. Returns
    ``(case, simulation dict)``.
    """
    t = np.arange(int(round(duration * rate)) + 1) / rate
    crank = isinstance(excitation, ref.Crank)
    sim = ref.simulate_lateral(t, excitation, pendulums=pendulums, fixed_mass=fixed_mass,
                               dry_mass=dry_mass, gravity=G, noise=noise,
                               displacement_noise=0.0 if crank else displacement_noise,
                               seed=seed, **effects)
    rig = Rig(dry_mass=dry_mass, gravity=G,
              crank=CrankTable(excitation.radius, excitation.rod_length, excitation.frequency)
              if crank else None)
    case = write_case(
        Path(folder) / f"{name}.toml",
        test=TestInfo(id=name, rig="lateral", data=f"{name}.csv",
                      excitation="crank" if crank else "measured",
                      note="SYNTHETIC test data from tests/reference_models.py"),
        tank=Tank(shape="sphere", radius=radius, fill_fraction=fill, diaphragm=diaphragm),
        liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
        rig=rig, time=t, force=sim["force"],
        displacement=None if crank else sim["displacement"], prediction=prediction,
        comment="SYNTHETIC test case (tests/synthetic_cases.py)", overwrite=True)
    return case, sim


def pendulum(mass=1.30, length=0.0553, zeta=0.01, stiffness=0.0, quadratic_damping=0.0):
    """A reference pendulum with hinge damping from a damping ratio."""
    return ref.Pendulum(mass, length, stiffness,
                        ref.hinge_damping(mass, length, zeta, stiffness=stiffness, gravity=G),
                        quadratic_damping)


def sweep_record(folder: Path, name: str, duration: float, *, seed: int, rate: float = 500.0,
                 **kw):
    """A record from rest of a 1 mm sweep from 0.6 to 1.6 times the 8-inch sphere's first
    mode (a 1.30 kg, 55.3 mm pendulum, 1 % damping; 1.5 kg fixed, 1.2 kg dry mass) over
    ``duration`` s at ``rate`` Hz, with 1.3 % force noise and 20 um displacement noise:
    the records of ``benchmarks/bench_length.py`` (``kw``: more of :func:`make_case`'s
    arguments). Returns ``(case, pendulum)``."""
    p = pendulum(1.30, 0.0553, 0.01)
    f1 = ref.natural_frequency(p, G) / (2 * np.pi)
    drive = ref.Ramped(ref.LinearSweep(0.001, 0.6 * f1, 1.6 * f1, duration), 1.5, 0.0)
    case, _ = make_case(folder, name, drive, pendulums=[p], fixed_mass=1.5, dry_mass=1.2,
                        noise=0.013, displacement_noise=2e-5, duration=duration, rate=rate,
                        seed=seed, **kw)
    return case, p


def make_spinning_case(folder: Path, name: str, rig, *, pendulum=None, rotor=None,
                       oscillator=None, fixed_mass=0.0, fixed_height=0.0, noise=0.01,
                       tone=None, drift=0.0, duration=20.0, rate=100.0, seed=0, tank_radius=0.2, fill=0.6,
                       prediction: Prediction | None = None, steady: bool = False,
                       measured_angles: bool = False, angle_noise: float = 0.0):
    """Simulate with ``reference_spinning.simulate_spinning`` (six channels) and write
    ``name.toml``/``.csv`` for ``rig = "spinning"``. ``rig`` is a ``reference_spinning.Rig``;
    its spin-up and cone ramp become ``[rig.spin]`` schedules, or, with ``measured_angles``,
    CSV columns ``table_angle``, ``precession`` and ``cone`` (with ``angle_noise`` rad of
    noise) named by ``[rig.spin]``. ``steady``: the analog starts at its relative
    equilibrium (``[test] initial_state = "steady"``). Returns ``(case, simulation dict)``."""
    import reference_spinning as rs

    from estimate.data.case import Spin

    t = np.arange(int(round(duration * rate)) + 1) / rate
    sim = rs.simulate_spinning(t, rig, pendulum=pendulum, rotor=rotor, oscillator=oscillator,
                               fixed_mass=fixed_mass, fixed_height=fixed_height, noise=noise,
                               tone=tone, drift=drift, seed=seed, steady=steady, angle_noise=angle_noise)
    gravity_on = rig.gravity > 0
    channels = {c: sim[c] for c in rs.CHANNELS}
    motion: dict = {}
    if measured_angles:
        names = {"spin_angle": "table_angle", "nutation_phase": "precession",
                 "cone_angle": "cone"}
        channels |= {col: sim["angles"][key] for key, col in names.items()}
        motion = dict(names)
    else:
        motion = {"spin_up": rig.spin_up, "nutation_ramp": rig.nutation_ramp,
                  "nutation_start": rig.nutation_start if rig.nutation_ramp else None}
    case = write_case(
        Path(folder) / f"{name}.toml",
        test=TestInfo(id=name, rig="spinning", data=f"{name}.csv", excitation="spin",
                      note="SYNTHETIC test data from tests/reference_spinning.py",
                      initial_state="steady" if steady else None),
        tank=Tank(shape="sphere", radius=tank_radius, fill_fraction=fill, diaphragm=False),
        liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
        rig=Rig(dry_mass=rig.dry_mass, gravity=rig.gravity if gravity_on else G,
                spin=Spin(rate=rig.spin_rate, radius=rig.radius,
                          nutation_angle=rig.nutation_angle,
                          nutation_frequency=rig.nutation_frequency, height=rig.height,
                          gravity_on=gravity_on, **motion)),
        time=t, channels=channels, prediction=prediction,
        comment="SYNTHETIC test case (tests/synthetic_cases.py)", overwrite=True)
    return case, sim


def rig_record(folder: Path, name: str, drive, *, scale: float = 1.0, zeta: float = 0.01,
               noise: float = 0.013, tone: float = 0.05, tone_hz: float = 25.0,
               displacement_noise: float = 2e-5, seed: int = 0, ramp: float = 1.5,
               ramp_start: float = 0.0):
    """A lateral-rig record as a rig test makes it: the tank at rest, ``drive(f1)`` (a
    ``reference_models`` excitation built from the first-mode frequency f1 in Hz) faded in
    over ``ramp`` seconds from ``ramp_start``, force noise ``noise`` of its RMS plus a motor
    tone (``tone`` N at scale 1, at ``tone_hz``), displacement noise (m).

    ``scale`` scales the 8-inch sphere at 60 % fill geometrically (masses by scale^3,
    lengths by scale, the case file's tank radius too; 4 is a full-size tank near 1 Hz).
    Returns ``(case, sim, truth)`` with ``truth`` holding the masses (kg), length (m), f1
    (Hz) and damping ratio.
    """
    m_p, L, m_f, dry = 1.30 * scale**3, 0.0553 * scale, 1.5 * scale**3, 1.2 * scale**3
    p = pendulum(m_p, L, zeta)
    f1 = ref.natural_frequency(p, G) / (2 * np.pi)
    prediction = Prediction(1.338 * scale**3, 0.057 * scale, 1.456 * scale**3, 0.007)
    excitation = ref.Ramped(drive(f1), ramp, ramp_start)
    case, sim = make_case(folder, name, excitation, pendulums=[p], fixed_mass=m_f, dry_mass=dry,
                          noise=noise, displacement_noise=displacement_noise, seed=seed,
                          tone=ref.Tone(tone * scale**3, tone_hz) if tone else None,
                          prediction=prediction, radius=0.1016 * scale)
    truth = {"fixed.mass": m_f, "p1.mass": m_p, "p1.length": L, "f1": f1, "zeta": zeta,
             "pendulum": p, "excitation": excitation}
    return case, sim, truth
