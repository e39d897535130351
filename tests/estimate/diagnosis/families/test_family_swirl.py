"""The six-axis families (``estimate.diagnosis.families.swirl`` and the channel offsets of
``.measurement``) on 12 s, 100 Hz records of the independent reference simulator of a tank
moved in 3-D (``tests/reference_motion.py``: hand-written spherical-pendulum equations,
SciPy DOP853; the 8-inch sphere at 60 %, the transducer 45 mm below the tank turned by
180 deg, 1.5 % white noise, a 3 % tone at 27 Hz on every channel, the motion as encoders
give it):

* a planar drive along x at 1.01 f1 (1.6 mm, a 1 % cross-axis motion as a carriage's guide
  lets through): the planar swing reaches 0.6 rad and the liquid swirls within the record
  (the transverse swing passes 0.3 rad by 10 s);
* the same carriage at 0.4 f1 (4 mm): no swirl;
* a drive with 3 mm across at 1.27 f1: not planar, the liquid moves across by force.

Swirl is proposed on the first from the transverse channels' slosh band and its fit
(planar pendulum made spherical, same parameters) recovers the first mode: mass within 2 %
and frequency within 0.3 % (issue 29's tolerances); it is not proposed on the second, and the
third starts from a spherical pendulum. A force-only record of the first names swirl or
nothing, never a lateral family (none applies); the report shows the transverse channel.
The channel offsets are proposed on a record with known offsets and drifts and recover
them within 3 standard errors, and are not proposed on one without."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import reference_motion as rm
from diagnosis_checks import run_family
from motion_cases import PENDULUM, make_motion_case, truth

from analogs import Pendulum, SphericalPendulum
from estimate import diagnose
from estimate.diagnosis import before_after_figure, write_report
from estimate.diagnosis.families import FAMILIES
from estimate.diagnosis.families.swirl import (
    MIN_BAND_RATIO,
    PLANAR_DRIVE,
    transverse_drive,
)
from estimate.diagnosis.search import baseline_model

F1 = PENDULUM.frequency_hz()
#: Issue 29: masses within 2 %, the first mode's frequency within 0.3 %.
MASS_TOL, FREQ_TOL = 0.02, 0.003
#: Offsets and drifts within this many standard errors (0.3 % chance of a miss each).
SE = 3.0


def _planar(amp: float, ratio: float) -> rm.Motion:
    return rm.Motion(x=rm.RampedSine(amp, ratio * F1, ramp=1.0, start=0.3),
                     y=rm.RampedSine(amp / 100, ratio * F1, math.pi / 2, ramp=1.0, start=0.3))


def _record(folder, name, motion, seed, **kw):
    return make_motion_case(folder, name, motion, duration=12.0, rate=100.0, seed=seed, **kw)


@pytest.fixture(scope="module")
def swirling(tmp_path_factory):
    case, sim = _record(tmp_path_factory.mktemp("s"), "S", _planar(0.0016, 1.01), 11)
    beta = np.abs(sim["states"][:, 1])
    assert beta[sim["time"] < 4].max() < 0.05 and beta.max() > 0.3  # the record swirls
    return case


@pytest.fixture(scope="module")
def steady(tmp_path_factory):
    case, sim = _record(tmp_path_factory.mktemp("p"), "P", _planar(0.004, 0.4), 12)
    assert np.abs(sim["states"][:, 1]).max() < 1e-3
    return case


def test_a_planar_drive_is_planar_and_a_cross_axis_one_is_not(swirling, tmp_path):
    assert transverse_drive(swirling) == pytest.approx(0.01, rel=0.05)
    assert type(baseline_model(swirling).component("p1")) is Pendulum
    across = rm.Motion(x=rm.RampedSine(0.004, 0.77 * F1, ramp=1.0, start=0.3),
                       y=rm.RampedSine(0.003, 1.27 * F1, math.pi / 3, ramp=1.0, start=0.5))
    case, _ = _record(tmp_path, "B", across, 13)
    assert transverse_drive(case) > PLANAR_DRIVE
    assert type(baseline_model(case).component("p1")) is SphericalPendulum


def test_swirl_is_proposed_and_its_fit_recovers_the_first_mode(swirling):
    run = run_family(swirling, "swirl")
    assert run.proposed, run.context.evidence.channel_share
    assert run.proposals[0].score >= MIN_BAND_RATIO
    fit = run.fit
    assert fit.converged, fit.status
    assert type(fit.problem.model.component("p1")) is SphericalPendulum
    assert run.proposals[0].plausible(fit) is None
    tr = truth()
    assert fit.value("p1.mass") == pytest.approx(tr["p1.mass"], rel=MASS_TOL)
    assert fit.derived["p1.frequency_hz"][0] == pytest.approx(tr["f1"], rel=FREQ_TOL)
    assert fit.objective < 0.5 * run.baseline.objective


def test_swirl_is_not_proposed_far_from_resonance(steady):
    run = run_family(steady, "swirl", fit=False)
    assert not run.proposed
    fam = next(f for f in FAMILIES if f.cause == "swirl")
    assert "no slosh-band signal" in fam.why_not(run.context)


def test_the_diagnosis_names_swirl_and_no_lateral_family(swirling, tmp_path):
    d = diagnose(swirling, progress=False)
    assert d.findings and d.findings[0].cause == "swirl", [f.cause for f in d.findings]
    assert {f.cause for f in d.findings} <= {"swirl", "channel_offsets"}
    # the report shows the channel holding most of the baseline's residual (a transverse
    # one here), in its unit; the summary's residuals are in channel scales
    write_report(d, tmp_path / "report")
    fig = before_after_figure(d)
    assert fig.axes[0].get_ylabel() in ("force_y [N]", "torque_x [N m]"), fig.axes[0].get_ylabel()
    assert "(channel scales)" in (tmp_path / "report" / "summary.md").read_text()
    # the force along the drive alone: swirl or nothing, never a lateral family
    case, _ = _record(tmp_path, "X", _planar(0.0016, 1.01), 11, channels=("force_x",))
    d = diagnose(case, progress=False)
    assert {f.cause for f in d.findings} <= {"swirl", "channel_offsets"}
    # the issue allows "unexplained" here; the record's 1 % cross-axis drive seeds the
    # swirl in the model too, so it is named and the first mode recovered
    assert d.findings and d.findings[0].cause == "swirl", d.verdict.text
    assert d.final.value("p1.mass") == pytest.approx(truth()["p1.mass"], rel=MASS_TOL)


def _with_offsets(case, offsets: dict[str, tuple[float, float]]):
    t = case.time - case.time[0]
    cols = dict(case.columns)
    for c, (off, drift) in offsets.items():
        cols[c] = cols[c] + off + drift * t
    return replace(case, columns=cols)


def test_channel_offsets_are_proposed_and_recovered(steady, tmp_path):
    quiet = rm.Noise(drift=0.0, motion=(1e-6, 2e-5))
    case, _ = _record(tmp_path, "Z", _planar(0.004, 0.4), 14, noise=quiet)
    assert not run_family(case, "channel_offsets", fit=False).proposed
    # zero errors of a few per cent of each channel's swing (force_x 2.7 N RMS, torque_y
    # 0.43 N m); not on force_z, whose zero is the weight of the liquid: far below
    # resonance the liquid mass is read from it (an offset there trades with the masses)
    known = {"force_x": (0.15, 0.01), "torque_y": (0.02, -1e-3)}
    run = run_family(_with_offsets(case, known), "channel_offsets")
    assert run.proposed
    fit = run.fit
    assert fit.converged, fit.status
    for c, (off, drift) in known.items():
        for name, value in ((f"Z:rig.{c}_offset", off), (f"Z:rig.{c}_drift", drift)):
            se = fit.stderr[fit.names.index(name)]
            assert abs(fit.value(name) - value) <= SE * se, (name, fit.value(name), value, se)
