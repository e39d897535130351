"""Issue 25: records as a robot-carried tank makes them (``tests/transport_cases.py``).

A jerk-limited transport move from rest then a free decay, a six-axis sensor (internal
low-pass, quantisation, white + 1/f noise, lines) on a stream that lags the motion stream,
the container not weighed; the displacement is the encoders' reading of the true motion,
or the planned path (the command the servo followed with a lag and a ripple). Truth from
the closed-form cylinder mode and the sphere's cap volume, never from the project.

Tolerances are the issue's acceptance: every mass within 3 %, the frequency within 0.3 %,
the lag within 2 ms.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import transport_cases as tc
from synthetic_cases import make_case, pendulum

from estimate import FitProblem, fit, model_from_spec

#: The issue's acceptance bounds.
MASS, FREQUENCY, LAG = 0.03, 0.003, 0.002
#: The planned-path and the measured fits of one test must agree within their intervals:
#: the difference within z of the combined standard error, z = 2.87 making the 95 % level
#: family-wise over the 12 comparisons (Bonferroni: 3 tanks x 4 quantities).
AGREEMENT_Z = 2.87

TANKS = {"small_cylinder": tc.small_cylinder, "sphere_8in": tc.sphere_8in,
         "large_cylinder": tc.large_cylinder}
SLOW = {"large_cylinder"}


def _fit(record):
    problem = FitProblem.build(record.case, model_from_spec("fixed,p1:nospring", record.case))
    return fit(problem, progress=False)


def _quantities(res) -> dict[str, tuple[float, float]]:
    """Masses, frequency and lag with standard errors."""
    lag = next(n for n in res.names if n.endswith("rig.lag"))
    tied = res.tied()
    out = {n: (res.value(n), res.stderr[res.names.index(n)])
           for n in ("rig.dry_mass", "p1.mass")}
    out["fixed.mass"] = tied["fixed.mass"][:2]
    out["frequency"] = res.derived["p1.frequency_hz"]
    out["lag"] = (res.value(lag), res.stderr[res.names.index(lag)])
    return out


@pytest.fixture(scope="module", params=[pytest.param(k, marks=pytest.mark.slow) if k in SLOW
                                        else k for k in TANKS])
def fits(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    tank = TANKS[request.param]()
    # 13.6 s at 500 Hz: 1 s at rest, a 0.8 s move of 0.4 m, 11.8 s of decay
    common = dict(distance=0.4, duration=0.8, start=1.0, decay=11.8, sensor_delay=0.018,
                  seed=3)
    measured = tc.transport_record(folder, tank, **common)
    planned = tc.transport_record(folder, tank, planned=True, **common)
    return measured, _fit(measured), planned, _fit(planned)


def test_a_transport_record_gives_the_analog_and_the_lag(fits):
    for record, res in (fits[0], fits[1]), (fits[2], fits[3]):
        truth = record.truth
        assert res.converged and not res.bounds_reached, res.verdict
        q = _quantities(res)
        for name in ("rig.dry_mass", "fixed.mass", "p1.mass"):
            assert q[name][0] == pytest.approx(truth[name], rel=MASS), name
        assert q["frequency"][0] == pytest.approx(truth["frequency"], rel=FREQUENCY)
        assert abs(q["lag"][0] - truth["lag"]) < LAG


@pytest.mark.parametrize("name", ["small_cylinder", "sphere_8in"])
def test_receive_time_stamps_keep_the_analog_and_the_lag(name, tmp_path):
    """The same measured record with its samples stamped by their receive times (+/- 1 ms,
    `[test] resample_hz = 500`): every mass within 3 %, the frequency within 0.3 %, the lag
    within 2 ms."""
    rec = tc.transport_record(tmp_path, TANKS[name](), distance=0.4, duration=0.8, start=1.0,
                              decay=11.8, sensor_delay=0.018, seed=3, jitter=1e-3)
    res = _fit(rec)
    assert res.converged and not res.bounds_reached, res.verdict
    assert any("receive times" in n for n in res.problem.notes), res.problem.notes
    q = _quantities(res)
    for key in ("rig.dry_mass", "fixed.mass", "p1.mass"):
        assert q[key][0] == pytest.approx(rec.truth[key], rel=MASS), key
    assert q["frequency"][0] == pytest.approx(rec.truth["frequency"], rel=FREQUENCY)
    assert abs(q["lag"][0] - rec.truth["lag"]) < LAG


def test_the_planned_path_reaches_the_measured_analog(fits):
    _, measured, _, planned = fits
    a, b = _quantities(measured), _quantities(planned)
    for name in ("rig.dry_mass", "p1.mass", "fixed.mass", "frequency"):
        (va, sa), (vb, sb) = a[name], b[name]
        assert abs(va - vb) <= AGREEMENT_Z * math.hypot(sa, sb), (name, va, sa, vb, sb)
    # the two descriptions differ by the servo's lag, and the fits say so
    assert b["lag"][0] - a["lag"][0] == pytest.approx(0.012, abs=LAG)


def test_the_first_stage_needs_no_good_start(tmp_path):
    """The linear identification finds the mode from predictions 40 % low and 60 % high
    (spectral peaks start the search), and the lag, on a gentle move (0.1 m: swings of
    0.05 rad, where a linear mode holds)."""
    from estimate.fitting.carriage import carriage_input
    from estimate.fitting.first_stage import identify

    tank = tc.small_cylinder()
    rec = tc.transport_record(tmp_path, tank, distance=0.1, duration=0.8, decay=8.0, seed=5)
    c = rec.case
    ci, rn = carriage_input(c.time, c.displacement, force=c.force)

    def acc(t):
        return ci.values(ci.coefficients, t)[2]

    for factor in (0.6, 1.6):
        stage = identify([(c.time, acc, rn.force, None)], frequency_hz=factor * tank.frequency,
                         gravity=tc.G, noise=[rn.force_noise])
        # frequency within 0.5 %; masses within 15 % (the acceleration is differentiated
        # from the encoder reading: its noise biases a regression low); lag within 2 ms
        assert stage.frequency_hz == pytest.approx(tank.frequency, rel=0.005)
        assert stage.slosh_mass == pytest.approx(tank.mode_mass, rel=0.15)
        assert stage.rigid_mass == pytest.approx(tank.container + tank.fixed_mass, rel=0.15)
        assert abs(stage.lags[0] - rec.lag) < LAG
        assert stage.lag_identified


def test_an_unweighed_container_ties_the_fixed_liquid(fits, tmp_path):
    record, res = fits[0], fits[1]
    liquid = record.case.liquid_mass
    assert "fixed.mass" not in res.names and "rig.dry_mass" in res.names
    data = res.to_dict()
    fixed = data["parameters"]["fixed.mass"]
    assert fixed["estimated"] is False and "liquid mass" in fixed["tied"]
    assert fixed["value"] == pytest.approx(liquid - res.value("p1.mass"), rel=1e-12)
    assert data["at_bound"] == [] and data["verdict"].startswith("converged (")


def test_a_slosh_mass_beyond_the_liquid_ends_on_the_named_bound(tmp_path):
    """A constructed case: the record holds 2.76 kg of fixed and sloshing liquid (and a
    weighed 1.2 kg container; the 60 % fill's [prediction]) but the case file says 30 %
    fill, 0.95 kg of water. The fit must end on the liquid mass bound and say so, never a
    bare "converged"."""
    import reference_models as ref

    f1 = math.sqrt(tc.G / 0.0553) / (2 * math.pi)
    case, _ = make_case(tmp_path, "overfull", ref.Ramped(ref.Sine(0.004, 0.9 * f1), 1.5),
                        pendulums=[pendulum()], fill=0.3, duration=20.0)
    liquid = case.liquid_mass
    assert liquid < 1.0
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case), lag="none"),
              progress=False)
    _named_at_the_liquid_bound(res)
    assert res.value("fixed.mass") + res.value("p1.mass") <= liquid * (1 + 1e-6)
    # held on the bound: the sum of the two masses has no variance left
    c = np.array([1.0 if n in ("fixed.mass", "p1.mass") else 0.0 for n in res.names])
    assert c @ res.covariance @ c < 1e-12  # kg^2


def test_an_unweighed_tank_keeps_the_slosh_mass_within_the_liquid(tmp_path):
    """The same record with the container not weighed: the rigid mass is free, the 1.3 kg
    pendulum the data ask for is more than the 0.95 kg of water the case file holds."""
    import reference_models as ref

    from estimate.data import load_case

    f1 = math.sqrt(tc.G / 0.0553) / (2 * math.pi)
    case, _ = make_case(tmp_path, "overfull", ref.Ramped(ref.Sine(0.004, 0.9 * f1), 1.5),
                        pendulums=[pendulum()], fill=0.3, duration=20.0)
    case.path.write_text(case.path.read_text().replace(
        "dry_mass = 1.2", 'dry_mass = "estimate"'))
    case = load_case(case.path)
    res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case), lag="none"),
              progress=False)
    _named_at_the_liquid_bound(res)
    assert res.value("p1.mass") <= case.liquid_mass * (1 + 1e-6)
    assert res.tied()["fixed.mass"][0] >= -1e-6 * case.liquid_mass


def _named_at_the_liquid_bound(res) -> None:
    assert res.active_bounds and "liquid mass" in res.active_bounds[0]
    assert res.verdict.startswith("converged at a bound") or not res.converged
    assert "liquid mass" in res.verdict or not res.converged
    data = json.loads(json.dumps(res.to_dict()))
    assert any("liquid mass" in b for b in data["at_bound"])


@pytest.mark.slow
def test_diagnose_names_the_lag_and_no_physical_cause(tmp_path):
    """`slosh diagnose` on a transport record starts from the fit's first stage and liquid
    budget, names the lag (the sensor-delay candidate, screened by its profile, no longer
    by a dF/dt correlation) and accepts no physical cause; no model it reports leaves the
    liquid budget."""
    from estimate.diagnosis.search import diagnose

    record = tc.transport_record(tmp_path, tc.small_cylinder(), decay=11.8, seed=3)
    d = diagnose(record.case, progress=False)
    assert [f.cause for f in d.findings] == ["sensor_delay"]
    lag = d.to_dict()["final"]["measurement"]["sensor_delay_s"]
    assert abs(lag - record.lag) < LAG
    assert d.final.converged and not d.final.bounds_reached
    assert d.final.value("p1.mass") == pytest.approx(record.truth["p1.mass"], rel=MASS)
    assert not d.baseline.bounds_reached
