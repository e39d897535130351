"""Test cases as real rigs record them, written from ``reference_rig_records``.

A transport move of the 8-inch sphere at 60 % fill (first mode 1.30 kg on 0.0553 m, damping
ratio 1 %, fixed liquid 1.5 kg, dry mass 1.2 kg given in the case file) by a robot arm: at
rest for ``rest`` seconds, 0.4 m in 0.8 s, then the free decay; 500 Hz, uniform timestamps.
The motion is read from joint encoders (1e-5 m noise, 5e-6 m steps); the force through a
six-axis transducer: white and 1/f noise, structural and mains lines, an offset, the sensor's
internal 2nd-order low-pass (60 Hz) and 5 mN quantisation. Optionally a second slosh mode
the fitted model lacks.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import reference_models as ref
import reference_rig_records as rr
from scipy import signal
from synthetic_cases import PREDICTION_60, G, pendulum

from estimate.data import write_case
from estimate.data.case import Liquid, Rig, Tank, TestInfo

#: The transducer's internal low-pass [Hz]: its group delay is a known lag of the force.
SENSOR_CUTOFF_HZ = 60.0
#: The band of the mechanics [Hz] in which the true noise is measured (slower is drift).
NOISE_BAND_LOW_HZ = 0.5


def rig_transport(folder: Path, name: str, *, seed: int = 0, second_mode: float = 0.0,
                  rest: float = 1.5, duration: float = 13.6, rate: float = 500.0):
    """Write ``name.toml``/``.csv``; return ``(case, truth)``.

    ``second_mode``: mass of a second slosh mode (at 1.9 times the first's frequency, 1 %
    damping) as a fraction of the first's. ``truth`` holds the first mode's and the fixed
    mass's parameters, the sensor's group delay (s) and ``noise``: the standard deviation
    [N] of what the transducer records besides the force (its output minus its noiseless
    output, offset removed) above :data:`NOISE_BAND_LOW_HZ` (4th-order zero-phase
    high-pass), lines included.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration * rate)) + 1) / rate
    move = rr.TransportMove(distance=0.4, duration=0.8, start=rest)
    p1 = pendulum(1.30, 0.0553, 0.01)
    pends = [p1]
    if second_mode:
        f1 = ref.natural_frequency(p1, G) / (2 * np.pi)
        pends.append(pendulum(second_mode * 1.30, G / (2 * np.pi * 1.9 * f1) ** 2, 0.01))
    sim = ref.simulate_lateral(t, move, pendulums=pends, fixed_mass=1.5, dry_mass=1.2, gravity=G)
    force = rr.force_sensor(t, sim["force_clean"], rng=rng, cutoff_hz=SENSOR_CUTOFF_HZ,
                            offset=0.02)
    noiseless = rr.force_sensor(t, sim["force_clean"], rng=np.random.default_rng(0),
                                cutoff_hz=SENSOR_CUTOFF_HZ, quantum=0.0, white=0.0, pink=0.0,
                                lines=(), offset=0.0)
    displacement = rr.encoder_position(sim["displacement_clean"], rng=rng)
    case = write_case(
        Path(folder) / f"{name}.toml",
        test=TestInfo(id=name, rig="lateral", data=f"{name}.csv", excitation="measured",
                      note="SYNTHETIC rig-like record from tests/reference_rig_records.py"),
        tank=Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False),
        liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
        rig=Rig(dry_mass=1.2, gravity=G), time=t, force=force, displacement=displacement,
        prediction=PREDICTION_60, comment="SYNTHETIC test case (tests/rig_cases.py)",
        overwrite=True)
    sos = signal.butter(4, NOISE_BAND_LOW_HZ, "highpass", fs=rate, output="sos")
    noise = signal.sosfiltfilt(sos, force - noiseless)
    truth = {"fixed.mass": 1.5, "p1.mass": 1.30, "p1.length": 0.0553, "p1.damping": p1.damping,
             "delay": rr.sensor_group_delay(SENSOR_CUTOFF_HZ), "noise": float(np.std(noise))}
    return case, truth
