"""Six-axis records of a tank moved in 3-D, written from the independent reference
simulator (``reference_motion``: hand-written equations integrated by SciPy, never the
project's own model code), as a rig test makes them: from rest, the drive faded in, noise,
a tone and a drift on every channel, the motion recorded with noise.

The tank is the 8-inch sphere (radius 0.1016 m) at 60 % fill with water (2.84 kg); the truth
(:data:`TRUTH`) lies a few per cent off the tank module's prediction, so a fit must move.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import reference_motion as rm

from estimate.data import write_case
from estimate.data.case import Liquid, Motion, Rig, Tank, TestInfo
from estimate.data.case import Transducer as TransducerTable

G = rm.STANDARD_GRAVITY
RADIUS = 0.1016
FILL = 0.6

#: The analog the records are made with: a spherical pendulum (first mode; damping ratio
#: 1.04 %) and a fixed mass with inertias, a weighed container of 1.2 kg.
PENDULUM = rm.SphericalPendulum(mass=1.30, length=0.0553, hinge_height=0.112, damping=0.0011)
FIXED = rm.FixedMass(mass=1.50, height=0.088, inertia=0.004, axial_inertia=0.0)
DRY_MASS = 1.2
#: The motion as a hexapod's (or a robot's) joint encoders give it through the kinematics:
#: 1 um and 20 urad of white noise at 500 Hz. An LVDT's 2e-5 m on the translations drives
#: the analog in the filtered-input fit (errors in variables) and biases the frequency and
#: damping by 5-17 of their standard errors on these records (see the closing note of
#: issue 29): that needs the estimated input, which the lateral carriage alone has.
ENCODERS = rm.Noise(motion=(1e-6, 2e-5))

#: A transducer 45 mm below the tank bottom, its axes turned by 180 deg about the tank axis
#: (as a lab may mount it).
TRANSDUCER = rm.Transducer((0.0, 0.0, -0.045), yaw=np.pi)


def truth(pendulum: rm.SphericalPendulum = PENDULUM, fixed: rm.FixedMass = FIXED) -> dict:
    """The parameters by model name, with the first mode's frequency (Hz)."""
    return {"p1.mass": pendulum.mass, "p1.length": pendulum.length,
            "p1.hinge_height": pendulum.hinge_height, "p1.damping": pendulum.damping,
            "fixed.mass": fixed.mass, "fixed.height": fixed.height,
            "fixed.inertia": fixed.inertia, "f1": pendulum.frequency_hz(G)}


def make_motion_case(folder: Path, name: str, motion: rm.Motion, *,
                     pendulum: rm.SphericalPendulum = PENDULUM, fixed: rm.FixedMass = FIXED,
                     dry_mass: float = DRY_MASS, transducer: rm.Transducer = TRANSDUCER,
                     noise: rm.Noise | None = ENCODERS, channels=rm.CHANNELS,
                     duration: float = 30.0, rate: float = 500.0, seed: int = 0,
                     declared: rm.Transducer | None = None, weighed: bool = True):
    """Simulate ``motion`` and write ``name.toml``/``name.csv`` (``[rig.motion]`` naming the
    moving axes, ``channels`` of the six). ``declared`` is the transducer the case file
    states (default: the true one). Returns ``(case, simulation dict)``."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    sim = rm.simulate_motion(t, motion, pendulum=pendulum, fixed=fixed, dry_mass=dry_mass,
                             transducer=transducer, noise=noise, seed=seed)
    cols = {a: sim["motion"][a] for a in motion.axes}
    cols |= {c: sim[c] for c in channels}
    tr = declared or transducer
    table = TransducerTable(*tr.position, roll=tr.roll, pitch=tr.pitch, yaw=tr.yaw)
    case = write_case(
        Path(folder) / f"{name}.toml",
        test=TestInfo(id=name, rig="lateral", data=f"{name}.csv", excitation="measured",
                      note="SYNTHETIC six-axis record from tests/reference_motion.py"),
        tank=Tank(shape="sphere", radius=RADIUS, fill_fraction=FILL, diaphragm=False),
        liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
        rig=Rig(dry_mass=dry_mass if weighed else None, gravity=G,
                motion=Motion(**{a: a for a in motion.axes}), transducer=table),
        time=t, channels=cols, comment="SYNTHETIC test case (tests/motion_cases.py)",
        overwrite=True)
    return case, sim
