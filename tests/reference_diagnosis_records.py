"""Records of the diagnosis recall table: each hides one effect (or a compound of effects),
or none (controls), in data from the independent reference simulator (``reference_models``:
hand-written equations integrated by SciPy, nothing imported from the project).

Every record is made as a rig test is: the tank at rest, the drive faded in over 1.5 s,
force noise (1.3 % of the RMS mechanical force) plus a motor tone, displacement noise. The
tanks are 8-inch spheres (radius 0.1016 m) at 60 or 80 % fill and a full-size (4x) sphere;
the analog's masses and frequencies are near the tank's own modal analysis (for 80 % fill:
mode 1 0.873 kg at 2.563 Hz, mode 2 0.061 kg at 4.125 Hz, fixed 2.995 kg; the records move
them by a few per cent as a real tank does). The analog's masses never add up to more than
the liquid in the tank (a second mode's mass is taken from the fixed mass): the fits keep
them within it.

``RECORDS`` maps a record name to a :class:`Record`: how to make it and what the diagnosis
must name. ``build(name, folder)`` writes it and returns the case.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import reference_models as ref
from synthetic_cases import G, make_case, pendulum

from estimate.data.case import Prediction

__all__ = ["Record", "RECORDS", "build", "write", "mode", "short"]

R = ref.Ramped
#: 8-inch sphere at 60 % fill (the seed's tank) and at 80 % fill.
P60 = pendulum(1.30, 0.0553, 0.005)
PRED60 = Prediction(1.338, 0.057, 1.456, 0.007)


def mode(mass: float, f_hz: float, zeta: float = 0.01, **kw) -> ref.Pendulum:
    """A reference pendulum of ``mass`` kg at ``f_hz`` (small swing, no spring) with hinge
    damping ratio ``zeta`` and any other hinge torque of :class:`reference_models.Pendulum`."""
    L = G / (2 * math.pi * f_hz) ** 2
    return ref.Pendulum(mass, L, 0.0, ref.hinge_damping(mass, L, zeta, gravity=G), **kw)


def spring_mode(mass: float, length: float, raise_: float, zeta: float) -> ref.Pendulum:
    """A pendulum whose hinge spring raises its frequency by ``raise_`` (a diaphragm)."""
    k = mass * G * length * ((1 + raise_) ** 2 - 1)
    return ref.Pendulum(mass, length, k, ref.hinge_damping(mass, length, zeta, stiffness=k,
                                                           gravity=G))


def cubic_for(raise_: float, m: float, L: float, swing: float = 0.3) -> float:
    """Cubic hinge stiffness [N m/rad^3] that raises the backbone frequency of a pendulum
    (m, L) by ``raise_`` at ``swing`` rad (harmonic balance: w^2 = g/L (1 - a^2/8) +
    3/4 k3 a^2 / (m L^2))."""
    return ((1 + raise_) ** 2 - 1 + swing**2 / 8) * m * G * L / (0.75 * swing**2)


#: 80 % fill of the 8-inch sphere, modes as in the hidden record of issue 24.
M1_80 = mode(0.898, 2.59, 0.008)
M2_80 = mode(0.066, 4.21, 0.01)
FIXED80 = 3.929 - 0.898 - 0.066


@dataclass(frozen=True)
class Record:
    """A recall-table record: the reference simulation's drive, pendulums and effects, the
    tank (fill, scale, diaphragm flag), and what the diagnosis must say: ``causes`` all
    named (any order), none of ``forbidden`` named, ``truth`` final parameter values within
    ``tolerance`` (relative), and the effect in words for the table."""

    effect: str
    drive: object
    pendulums: tuple
    causes: tuple[str, ...] = ()
    truth: dict[str, float] = field(default_factory=dict)
    tolerance: float = 0.15
    seed: int = 0
    effects: dict = field(default_factory=dict)
    fill: float = 0.6
    scale: float = 1.0
    fixed_mass: float = 1.5
    diaphragm: bool = False
    #: [prediction] table of the case (``None``: the tank's own modal analysis)
    prediction: Prediction | None = None
    duration: float = 30.0
    displacement_noise: float = 2e-5
    #: a known failure: why the diagnosis does not name it yet (the recall test expects
    #: the failure, strictly: a fix shows up as an unexpected pass)
    known: str = ""


TONE = ref.Tone(0.05, 25.0)
SWEEP60 = R(ref.LinearSweep(0.003, 1.0, 5.0, 30.0), 1.5, 0.0)
SWEEP60_4HZ = R(ref.LinearSweep(0.003, 1.0, 4.0, 30.0), 1.5, 0.0)
STEPS60 = R(ref.AmplitudeSteps((0.001, 0.002, 0.004), 1.9, 10.0), 1.5, 0.0)
SPRING80 = spring_mode(0.898, G / (2 * math.pi * 2.59) ** 2, 0.15, 0.02)
SPRING60 = spring_mode(0.9 * 1.338, 0.057, 0.15, 0.07)
QUAD60 = ref.Pendulum(1.30, 0.0553, 0.0, ref.hinge_damping(1.30, 0.0553, 0.002, gravity=G), 2e-3)
CHIRP_02MM = R(ref.LinearSweep(0.0002, 1.0, 5.0, 30.0), 1.5, 0.0)
CHIRP_03MM = R(ref.LinearSweep(0.0003, 1.0, 5.0, 30.0), 1.5, 0.0)
#: Amplitude steps 11 % below the 80 % fill's first mode: swings of 0.05-0.3 rad.
STEPS80 = R(ref.AmplitudeSteps((0.0006, 0.0012, 0.0024), 2.3, 10.0), 1.5, 0.0)

RECORDS: dict[str, Record] = {
    # (a) the regression of issue 24: a second mode hidden in a small-amplitude chirp
    "chirp_mode2": Record("2nd mode 0.066 kg @ 4.21 Hz", CHIRP_02MM, (M1_80, M2_80),
                          ("slosh_mode",), {"p2.mass": 0.066}, fill=0.8, fixed_mass=FIXED80,
                          seed=101, effects={"tone": TONE}, displacement_noise=1e-5),
    # (b) second mode + sensor delay
    "chirp_mode2_delay": Record("2nd mode + 15 ms delay", CHIRP_03MM, (M1_80, M2_80),
                                ("slosh_mode", "sensor_delay"), {"p2.mass": 0.066}, fill=0.8,
                                fixed_mass=FIXED80, seed=102, displacement_noise=1e-5,
                                effects={"tone": TONE, "sensor_delay": 0.015}),
    # (c) a cubic-hardening hinge at 80 % fill
    "steps_cubic80": Record("cubic hinge, +7 % at 0.3 rad", STEPS80,
                            (mode(0.898, 2.59, 0.008,
                                  cubic_stiffness=cubic_for(0.07, 0.898, G / (2 * math.pi * 2.59) ** 2)),),
                            ("nonlinear_stiffness",),
                            {"p1.cubic_stiffness": cubic_for(0.07, 0.898,
                                                             G / (2 * math.pi * 2.59) ** 2)},
                            fill=0.8, fixed_mass=FIXED80 + 0.066, seed=103,
                            effects={"tone": TONE}),
    # (d) a diaphragm spring + a second mode on a chirp, with a force offset and drift
    "chirp_spring_mode2_offset": Record(
        "diaphragm spring + 2nd mode + offset/drift", CHIRP_03MM,
        (spring_mode(0.898, G / (2 * math.pi * 2.59) ** 2, 0.12, 0.02), M2_80),
        ("diaphragm_stiffness", "slosh_mode", "sensor_offset"),
        {"p2.mass": 0.066, "rig.force_offset": 0.2}, fill=0.8,
        fixed_mass=FIXED80, seed=104, displacement_noise=1e-5, diaphragm=True,
        effects={"tone": TONE, "offset": 0.2, "drift": 0.004}),
    # the run-time record of issue 24: amplitude steps, linear diaphragm spring
    "steps_spring80": Record("diaphragm spring +15 %", STEPS80, (SPRING80,),
                             ("diaphragm_stiffness",), {"p1.stiffness": SPRING80.stiffness},
                             fill=0.8, fixed_mass=FIXED80 + 0.066, seed=105, diaphragm=True,
                             effects={"tone": TONE}),
    # -- two records per family ---------------------------------------------------------------
    "sweep60_mode2": Record("2nd mode 0.06 kg @ 3.8 Hz", SWEEP60, (P60, mode(0.06, 3.8)),
                            ("slosh_mode",), {"p2.mass": 0.06}, seed=111, prediction=PRED60,
                            fixed_mass=1.5 - 0.06),
    "sweep60_spring": Record("diaphragm spring +15 %", SWEEP60_4HZ, (SPRING60,),
                             ("diaphragm_stiffness",), {"p1.stiffness": SPRING60.stiffness},
                             seed=112, prediction=PRED60, fixed_mass=1.6),
    "steps60_quad": Record("quadratic damping 2e-3", STEPS60, (QUAD60,), ("nonlinear_damping",),
                           {"p1.quadratic_damping": 2e-3}, seed=113, prediction=PRED60),
    "steps80_quad": Record("quadratic damping 1e-3", STEPS80,
                           (mode(0.898, 2.59, 0.002, quadratic_damping=1e-3),),
                           ("nonlinear_damping",), {"p1.quadratic_damping": 1e-3}, fill=0.8,
                           fixed_mass=FIXED80 + 0.066, seed=114),
    "steps60_friction": Record("hinge dry friction 4e-4 N m", STEPS60,
                               (ref.Pendulum(P60.mass, P60.length, 0.0, P60.damping, coulomb=4e-4),),
                               ("dry_friction",), {"p1.coulomb_friction": 4e-4}, seed=115,
                               prediction=PRED60),
    "steps80_friction": Record("hinge dry friction 3e-4 N m", STEPS80,
                               (mode(0.898, 2.59, 0.005, coulomb=3e-4),), ("dry_friction",),
                               {"p1.coulomb_friction": 3e-4}, fill=0.8,
                               fixed_mass=FIXED80 + 0.066, seed=116),
    "steps60_cubic": Record("cubic hinge, +8 % at 0.3 rad", STEPS60,
                            (ref.Pendulum(P60.mass, P60.length, 0.0, P60.damping,
                                          cubic_stiffness=cubic_for(0.08, P60.mass, P60.length)),),
                            ("nonlinear_stiffness",),
                            {"p1.cubic_stiffness": cubic_for(0.08, P60.mass, P60.length)},
                            seed=117, prediction=PRED60),
    "sweep60_delay": Record("sensor delay 30 ms", SWEEP60_4HZ, (P60,), ("sensor_delay",),
                            seed=118, prediction=PRED60, effects={"tone": TONE, "sensor_delay": 0.03}),
    # (a 20 ms delay on a 2.4 Hz sine at 80 % fill is not named either: at one frequency a
    # delay is a phase the pendulum's damping and frequency imitate; unexplained at 1.63 x)
    "chirp80_delay": Record("sensor delay 20 ms", CHIRP_03MM, (M1_80,), ("sensor_delay",),
                            fill=0.8, fixed_mass=FIXED80 + 0.066, seed=119,
                            displacement_noise=1e-5,
                            effects={"tone": TONE, "sensor_delay": 0.02}),
    # one drive frequency: the viscous and Coulomb parts, both in phase with the velocity,
    # trade (the tolerance is 20 %)
    "steps60_rigfriction": Record("rig friction 2 N s/m + 0.1 N", STEPS60, (P60,),
                                  ("rig_friction",), {"rig.friction_viscous": 2.0}, seed=127,
                                  prediction=PRED60, tolerance=0.2,
                                  effects={"tone": TONE, "friction": ref.Friction(0.1, 2.0)}),
    "sweep60_offset": Record("force offset 0.5 N + drift 0.01 N/s", SWEEP60, (P60,),
                             ("sensor_offset",), {"rig.force_offset": 0.5}, seed=120,
                             prediction=PRED60, effects={"tone": TONE, "offset": 0.5, "drift": 0.01}),
    "steps80_offset": Record("force offset -0.2 N + drift 0.005 N/s", STEPS80, (M1_80,),
                             ("sensor_offset",), {"rig.force_offset": -0.2}, fill=0.8,
                             fixed_mass=FIXED80 + 0.066, seed=121,
                             effects={"tone": TONE, "offset": -0.2, "drift": 0.005}),
    "sweep60_rigfriction": Record("rig friction 2 N s/m + 0.1 N", SWEEP60_4HZ, (P60,),
                                  ("rig_friction",), {"rig.friction_viscous": 2.0}, seed=122,
                                  prediction=PRED60,
                                  effects={"tone": TONE, "friction": ref.Friction(0.1, 2.0)}),
    # (rig friction of 1 N s/m + 0.05 N under a 2.2 Hz sine at 80 % fill was not named:
    # at one frequency a force in phase with the velocity is what the hinge damper near
    # resonance gives; unexplained at 1.27 x)
    "chirp80_rigfriction": Record("rig friction 1 N s/m + 0.05 N", CHIRP_03MM, (M1_80,),
                                  ("rig_friction",), {"rig.friction_viscous": 1.0}, fill=0.8,
                                  fixed_mass=FIXED80 + 0.066, seed=123, displacement_noise=1e-5,
                                  effects={"tone": TONE, "friction": ref.Friction(0.05, 1.0)},
                                  known="names rig_friction and explains the data (1.14 x the "
                                        "noise), but with the viscous part at 0 (interval "
                                        "[0, 0.40] N s/m) and the Coulomb part at 0.0567 N "
                                        "(+13 %): under a 0.3 mm chirp (carriage velocity "
                                        "< 7.5 mm/s) the viscous force is under the noise, and "
                                        "the fitted Coulomb term's tanh, smoothed over 1 mm/s, "
                                        "takes it up; a sharper tanh (0.1 mm/s) does not "
                                        "converge"),
    "steps60_asymmetric": Record("asymmetric hinge spring 0.13 th^2", STEPS60,
                                 (ref.Pendulum(P60.mass, P60.length, 0.0, P60.damping,
                                               extra=lambda th, thd: 0.13 * th**2),),
                                 ("hinge_torque",), {"p1.torque_angle_squared": 0.13}, seed=124,
                                 prediction=PRED60, tolerance=0.2),
    "steps80_asymmetric": Record("asymmetric hinge spring 0.05 th^2", STEPS80,
                                 (mode(0.898, 2.59, 0.008, extra=lambda th, thd: 0.05 * th**2),),
                                 ("hinge_torque",), {"p1.torque_angle_squared": 0.05}, fill=0.8,
                                 fixed_mass=FIXED80 + 0.066, seed=125, tolerance=0.2),
    # -- compounds ------------------------------------------------------------------------------
    "sweep60_friction_mode2": Record("hinge friction + 2nd mode", SWEEP60,
                                     (ref.Pendulum(P60.mass, P60.length, 0.0, P60.damping,
                                                   coulomb=4e-4), mode(0.07, 3.6)),
                                     ("dry_friction", "slosh_mode"), {"p2.mass": 0.07},
                                     seed=126, prediction=PRED60, fixed_mass=1.5 - 0.07),
    # -- controls: clean records of different drives and tank sizes -----------------------------
    "ctrl_sweep60": Record("none (chirp, 60 %)", SWEEP60, (P60,), seed=130, prediction=PRED60),
    "ctrl_steps60": Record("none (amplitude steps, 60 %)", STEPS60, (P60,), seed=131,
                           prediction=PRED60),
    "ctrl_chirp80": Record("none (0.2 mm chirp, 80 %)", CHIRP_02MM, (M1_80,), fill=0.8,
                           fixed_mass=FIXED80 + 0.066, seed=132, displacement_noise=1e-5),
    "ctrl_sine80": Record("none (sine, 80 %)", R(ref.Sine(0.0008, 2.3), 1.5, 0.0), (M1_80,),
                          fill=0.8, fixed_mass=FIXED80 + 0.066, seed=133),
    "ctrl_full_size": Record("none (full-size tank, 4x radius)",
                             R(ref.AmplitudeSteps((0.002, 0.004, 0.008), 0.95, 10.0), 2.0, 0.0),
                             (pendulum(1.30 * 64, 0.0553 * 4, 0.003),), seed=134, scale=4.0,
                             fixed_mass=1.5 * 64,
                             prediction=Prediction(1.338 * 64, 0.057 * 4, 1.456 * 64, 0.007),
                             effects={"tone": ref.Tone(3.0, 17.0)}),
    "ctrl_down_chirp": Record("none (down-chirp 5-1 Hz, 60 %)",
                              R(ref.LinearSweep(0.0015, 5.0, 1.0, 30.0), 1.0, 0.5), (P60,),
                              seed=135, prediction=PRED60),
}


def build(name: str, folder, rate: float = 100.0) -> tuple:
    """Write record ``name`` of :data:`RECORDS` into ``folder`` sampled at ``rate`` (Hz);
    returns ``(case, simulation dict)``."""
    return write(RECORDS[name], folder, name, rate)


def write(rec: Record, folder, name: str, rate: float = 100.0) -> tuple:
    """Write the record ``rec`` as ``name`` into ``folder`` sampled at ``rate`` (Hz; the
    noise levels are per sample at any rate); returns ``(case, simulation dict)``."""
    s = rec.scale
    return make_case(folder, name, rec.drive, pendulums=list(rec.pendulums),
                     fixed_mass=rec.fixed_mass, dry_mass=1.2 * s**3, noise=0.013,
                     displacement_noise=rec.displacement_noise * s, seed=rec.seed,
                     prediction=rec.prediction, fill=rec.fill, diaphragm=rec.diaphragm,
                     radius=0.1016 * s, duration=rec.duration, rate=rate, **rec.effects)


# -- short records of the per-family tests (tests/estimate/diagnosis/families/) ---------------
#: 15 s at 100 Hz of the 8-inch sphere at 60 % fill, from rest with a 1.5 s ramp.
SHORT_SWEEP = R(ref.LinearSweep(0.003, 1.0, 4.5, 15.0), 1.5, 0.0)
SHORT_STEPS = R(ref.AmplitudeSteps((0.001, 0.002, 0.004), 1.9, 5.0), 1.5, 0.0)


def short(name: str, drive, pendulums=(P60,), *, seed: int, **effects) -> Record:
    """A 15 s record of the per-family tests (60 % fill, 1.3 % force noise, a motor tone,
    2e-5 m displacement noise)."""
    return Record(name, drive, tuple(pendulums), seed=seed, prediction=PRED60, duration=15.0,
                  effects={"tone": TONE, **effects})
