"""Open-ended diagnosis on records made as rig tests are: each starts at rest and ramps
its drive in over 1.5 s, with force noise (1.3 % of the RMS force), displacement noise
(2e-5 m), a motor tone and, in some, an offset, drift and pink noise. Every record comes from
the independent reference simulator (``reference_models``: hand-written hinge torques
integrated by SciPy), never from the project's own model code.

* dry (Coulomb) hinge friction, whose equivalent damping ratio halves each time the swing
  doubles: cause ``dry_friction`` first, friction torque within 15 %;
* a hardening hinge (cubic stiffness, frequency +6.5 or +8 % at a 0.3 rad swing), with and
  without ``diaphragm = true``: cause ``nonlinear_stiffness`` first, stiffness within 15 %;
* two effects at once: both named;
* clean controls, one with a force offset, drift and pink noise, one a full-size tank (4x
  the radius): no physical finding, verdict "explains the data";
* effects outside every family (an asymmetric hinge spring, a transducer that saturates):
  a library term or ``unexplained``, never "explains the data".

Tolerances: 15 % on the named parameter (issue acceptance); the records are built so the
hidden effect is well above the noise (the baseline residual is 2-10x the noise floor).
The friction torque's stated interval must hold the truth: within 2.5 standard errors (a
correct interval misses that by chance 1.2 % of the time; friction_b, seed 31, sits at
+2.2 se, the worst of 12 noise draws of that record, whose z-scores had mean +0.6 and
standard deviation 0.9). A finding's held-out gain must be real: no named physical family
on a record whose effect is outside every family.
Default run: an effect outside every family (the hardening hinge's family is screened and
fitted on the reference simulator in ``families/test_family_hinge.py``); ``pytest -m slow``
runs all (10-25 s each on 2 cores).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import G, make_case, pendulum

from estimate import diagnose
from estimate.data.case import Prediction

PARAM = 0.15
#: physical causes: a control may name only measurement effects (an offset)
PHYSICAL = {"slosh_mode", "nonlinear_damping", "diaphragm_stiffness", "dry_friction",
            "nonlinear_stiffness", "rotor", "hinge_torque"}
R = ref.Ramped
P1 = pendulum(1.30, 0.0553, 0.005)  # f1 2.12 Hz, the seed's 8-inch sphere at 60 %
P1_LOW = pendulum(1.30, 0.0553, 0.003)


def cubic_for(raise_: float, swing: float = 0.3, p=P1) -> float:
    """Cubic hinge stiffness [N m/rad^3] that raises the backbone frequency of ``p`` by
    ``raise_`` at the swing ``swing`` [rad] (harmonic balance: w^2 = g/L (1 - a^2/8) +
    3/4 k3 a^2 / (m L^2))."""
    mgl = p.mass * G * p.length
    return ((1 + raise_) ** 2 - 1 + swing**2 / 8) * mgl / (0.75 * swing**2)


def with_(p, **kw):
    return ref.Pendulum(p.mass, p.length, p.stiffness, p.damping, p.quadratic_damping, **kw)


def mode2(mass=0.06, f=3.8, zeta=0.01):
    return pendulum(mass, G / (2 * math.pi * f) ** 2, zeta)


@dataclass(frozen=True)
class Record:
    """A synthetic test record and what the diagnosis must say about it."""

    excitation: object
    pendulums: tuple
    causes: tuple[str, ...] = ()  # one: named first; two: both named
    truth: dict[str, float] = field(default_factory=dict)  # final parameter -> value
    outside: bool = False  # effect outside every family
    seed: int = 0
    effects: dict = field(default_factory=dict)
    scale: float = 1.0
    fixed_mass: float = 1.5
    diaphragm: bool = False
    #: final parameters whose stated standard error must cover the truth (``INTERVAL_SE``)
    interval: tuple[str, ...] = ()


#: Standard errors the truth may be from an estimate whose interval is checked.
INTERVAL_SE = 2.5

SWEEP = R(ref.LinearSweep(0.003, 1.0, 5.0, 30.0), 1.5, 0.0)
STEPS_A = R(ref.AmplitudeSteps((0.001, 0.002, 0.004), 1.9, 10.0), 1.5, 0.0)
STEPS_B = R(ref.AmplitudeSteps((0.0015, 0.003, 0.006), 1.8, 10.0), 1.5, 0.0)
STEPS_C = R(ref.AmplitudeSteps((0.0008, 0.0016, 0.003), 2.0, 10.0), 1.5, 0.0)
TONE = ref.Tone(0.05, 25.0)

RECORDS: dict[str, Record] = {
    "friction_a": Record(STEPS_A, (with_(P1, coulomb=4e-4),), ("dry_friction",),
                         {"p1.coulomb_friction": 4e-4}, seed=3, effects={"tone": TONE},
                         interval=("p1.coulomb_friction",)),
    "friction_b": Record(STEPS_B, (with_(P1_LOW, coulomb=6e-4),), ("dry_friction",),
                         {"p1.coulomb_friction": 6e-4}, seed=31,
                         effects={"tone": ref.Tone(0.08, 17.0)}, interval=("p1.coulomb_friction",)),
    "cubic_a": Record(STEPS_A, (with_(P1, cubic_stiffness=cubic_for(0.08)),),
                      ("nonlinear_stiffness",), {"p1.cubic_stiffness": cubic_for(0.08)},
                      seed=32, effects={"tone": TONE}),
    "cubic_b": Record(STEPS_C, (with_(P1, cubic_stiffness=cubic_for(0.065)),),
                      ("nonlinear_stiffness",), {"p1.cubic_stiffness": cubic_for(0.065)},
                      seed=33, effects={"tone": ref.Tone(0.05, 31.0)}, diaphragm=True),
    "mode_delay": Record(SWEEP, (P1, mode2()), ("slosh_mode", "sensor_delay"),
                         {"p2.mass": 0.06}, seed=34,
                         effects={"tone": TONE, "sensor_delay": 0.02}),
    "friction_mode": Record(SWEEP, (with_(P1, coulomb=4e-4), mode2(0.07, 3.6)),
                            ("slosh_mode", "dry_friction"),
                            {"p2.mass": 0.07, "p1.coulomb_friction": 4e-4}, seed=35,
                            effects={"tone": TONE}),
    "ctrl_steps": Record(STEPS_A, (P1,), seed=36, effects={"tone": TONE}),
    "ctrl_sweep": Record(SWEEP, (P1,), seed=37, effects={"tone": ref.Tone(0.1, 23.0)}),
    "ctrl_offset": Record(STEPS_B, (P1,), seed=38,
                          effects={"tone": TONE, "offset": 0.3, "drift": 0.01,
                                   "pink_noise": 0.01}),
    "ctrl_full_size": Record(R(ref.AmplitudeSteps((0.002, 0.004, 0.008), 0.95, 10.0), 2.0, 0.0),
                             (pendulum(1.30 * 64, 0.0553 * 4, 0.003),), seed=39,
                             effects={"tone": ref.Tone(3.0, 17.0)}, scale=4.0,
                             fixed_mass=1.5 * 64),
    "ctrl_down_chirp": Record(R(ref.LinearSweep(0.0015, 5.0, 1.0, 30.0), 1.0, 0.5), (P1,),
                              seed=40, effects={"tone": TONE}),
    # an asymmetric hinge spring (a sagging diaphragm): torque k2 th^2, 6 % of the gravity
    # torque at 0.3 rad; no family is even in the angle
    "outside_asymmetric": Record(STEPS_A, (with_(P1, extra=lambda th, thd: 0.13 * th**2),),
                                 outside=True, seed=41, effects={"tone": TONE}),
    # a transducer that reads ~12 % low at the peak force (soft saturation): not the analog
    "outside_saturation": Record(SWEEP, (P1,), outside=True, seed=42,
                                 effects={"tone": TONE, "saturation": 15.0}),
}
#: The default run: an effect outside every family; the hardening-hinge, friction and
#: control records run in the slow suite (the hinge families and the offset have default
#: tests of their own in ``families/``; the recall table has the controls).
DEFAULT = ("outside_asymmetric",)


def build(name: str, folder) -> tuple:
    rec = RECORDS[name]
    s = rec.scale
    pred = Prediction(1.338 * s**3, 0.057 * s, 1.456 * s**3, 0.007)
    return make_case(folder, name, rec.excitation, pendulums=list(rec.pendulums),
                     fixed_mass=rec.fixed_mass, dry_mass=1.2 * s**3, noise=0.013,
                     displacement_noise=2e-5 * s, seed=rec.seed, prediction=pred,
                     diaphragm=rec.diaphragm, radius=0.1016 * s, **rec.effects)


def check(rec: Record, d) -> None:
    data = d.to_dict()
    causes = [f.cause for f in d.findings]
    final = {k: v["value"] for k, v in data["final"]["parameters"].items()}
    stderr = {k: v["stderr"] for k, v in data["final"]["parameters"].items()}
    verdict, unexplained = data["verdict"], data["unexplained"]
    assert unexplained == (not verdict["explained"])
    if rec.outside:
        # a library term names the torque; a named family would misname it unless the
        # verdict still says the data are not explained
        assert unexplained or "hinge_torque" in causes, verdict["text"]
        # a named family would misname the effect, also under an "unexplained" verdict
        assert not set(causes) & (PHYSICAL - {"hinge_torque"}), [f.evidence for f in d.findings]
        assert "explains the data" not in verdict["text"] or "hinge_torque" in causes
        return
    if not rec.causes:
        assert not set(causes) & PHYSICAL, [f.evidence for f in d.findings]
        assert not unexplained, verdict["text"]
        return
    if len(rec.causes) == 1:
        assert causes[:1] == list(rec.causes), [f.evidence for f in d.findings]
    else:  # two effects at once: both named, in either order
        assert set(rec.causes) <= set(causes), [f.evidence for f in d.findings]
    for name, value in rec.truth.items():
        assert final[name] == pytest.approx(value, rel=PARAM), name
    for name in rec.interval:
        assert abs(final[name] - rec.truth[name]) <= INTERVAL_SE * stderr[name], \
            (name, final[name], stderr[name])
    assert not unexplained, verdict["text"]


@pytest.mark.parametrize("name", [pytest.param(n, marks=() if n in DEFAULT else pytest.mark.slow)
                                  for n in RECORDS])
def test_open_diagnosis(name, tmp_path):
    case, _ = build(name, tmp_path)
    d = diagnose(case)
    check(RECORDS[name], d)


@pytest.mark.slow  # 30 s: the reference integrates a friction sign sharpened to 1e-3 rad/s
def test_friction_records_halve_their_equivalent_damping():
    """The friction records do what they claim: the swing doubles from step to step (so the
    equivalent damping ratio of Coulomb friction, 2 Tc / (pi m L^2 w^2 a), halves)."""
    t = np.arange(3001) / 100.0
    for name in ("friction_a", "friction_b"):
        rec = RECORDS[name]
        sim = ref.simulate_lateral(t, rec.excitation, pendulums=list(rec.pendulums),
                                   fixed_mass=1.5, dry_mass=1.2)
        th = sim["theta"][0]
        swing = [np.max(np.abs(th[(t > a + 5) & (t < a + 10)])) for a in (0.0, 10.0, 20.0)]
        assert 1.7 < swing[1] / swing[0] < 2.3 and 1.7 < swing[2] / swing[1] < 2.3, swing


def test_cubic_records_raise_the_frequency_as_stated():
    """The backbone frequency of the reference hinge at 0.3 rad, measured from a free decay
    of the reference simulator, is 6-10 % above the small-swing frequency."""
    t = np.arange(4001) / 1000.0
    for name in ("cubic_a", "cubic_b"):
        p = RECORDS[name].pendulums[0]
        p = ref.Pendulum(p.mass, p.length, 0.0, 0.0, cubic_stiffness=p.cubic_stiffness)
        f = []
        for a in (0.01, 0.3):
            th = ref.simulate_lateral(t, ref.Sine(0.0, 1.0), pendulums=[p],
                                      initial_theta=[a])["theta"][0]
            up = np.flatnonzero((th[:-1] < 0) & (th[1:] >= 0))
            f.append((up.size - 1) / (t[up[-1]] - t[up[0]]))
        assert 1.06 <= f[1] / f[0] <= 1.10, f
