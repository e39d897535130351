"""Over 100 noise draws the 95 % intervals cover the truth at least 90 times (slow)."""

import numpy as np
import pytest
import reference_models as ref
import reference_rig_records as rr
from synthetic_cases import make_case, pendulum, rig_record

from estimate import FitProblem, fit, model_from_spec


@pytest.mark.slow
def test_gauss_newton_intervals_cover_the_truth(tmp_path):
    truth = pendulum(1.30, 0.0553, 0.01)
    values = {"fixed.mass": 1.50, "p1.mass": truth.mass, "p1.length": truth.length,
              "p1.damping": truth.damping}
    hits = {k: 0 for k in values}
    n = 100
    for seed in range(n):
        # white force noise, fitted unfiltered: the Gauss-Newton covariance assumes
        # independent residuals (the report warns that filtered residuals are not)
        case, _ = make_case(tmp_path, f"C{seed}", ref.Sine(0.004, 1.9), pendulums=[truth],
                            fixed_mass=1.50, noise=0.01, displacement_noise=0.0, seed=seed,
                            duration=10.0)
        res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case),
                                   input="filtered", force_cutoff_hz=None), progress=False)
        for k, v in values.items():
            lo, hi = res.interval(k)
            hits[k] += lo <= v <= hi
    assert all(h >= 90 for h in hits.values()), hits


@pytest.mark.slow
@pytest.mark.parametrize("record", ["sine_0.9f1_2.5mm", "chirp_up_0.2mm"])
def test_estimated_input_intervals_cover_the_truth(tmp_path, record):
    """Records from rest with a ramp, both noises and a tone redrawn 100 times: every mass's
    95 % interval covers the truth at least 90 times, and the z-scores have a standard
    deviation within 20 % of 1 (the intervals are neither too narrow nor too wide)."""
    drive, opts = {
        "sine_0.9f1_2.5mm": (lambda f1: ref.Sine(0.0025, 0.9 * f1), {}),
        "chirp_up_0.2mm": (lambda f1: ref.LinearSweep(0.0002, 1.0, 5.0, 30.0), dict(ramp=1.0)),
    }[record]
    names = ("fixed.mass", "p1.mass")
    hits = {k: 0 for k in names}
    z = {k: [] for k in names}
    n = 100
    for seed in range(n):
        case, _, truth = rig_record(tmp_path, f"R{seed}", drive, seed=1000 + seed, **opts)
        res = fit(FitProblem.build(case, model_from_spec("fixed,p1:nospring", case)),
                  progress=False)
        for k in names:
            lo, hi = res.interval(k)
            hits[k] += lo <= truth[k] <= hi
            z[k].append((res.value(k) - truth[k]) / res.stderr[res.names.index(k)])
    assert all(h >= 90 for h in hits.values()), hits
    assert all(0.8 <= np.std(v) <= 1.2 for v in z.values()), {k: np.std(v) for k, v in z.items()}


def _rig_fit(tmp_path, seed: int, second_mode: float):
    """A transport record as a six-axis transducer and encoders record it
    (``tests/rig_cases.py``), fitted with the first mode only, the transducer's offset
    estimated, its internal filter's group delay given (the rig's dry mass is in the case)."""
    from rig_cases import rig_transport

    from estimate.fitting.measurement import ChannelOffsets, SensorDelay

    case, truth = rig_transport(tmp_path, f"T{seed}", seed=1000 + seed, second_mode=second_mode)
    problem = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case),
                               measurement=(ChannelOffsets(drift=False),
                                            SensorDelay(truth["delay"])))
    return fit(problem, progress=False), truth


@pytest.mark.slow
def test_robust_intervals_cover_the_truth_on_a_transducer_record(tmp_path):
    """A transport move recorded through a six-axis transducer (white and 1/f noise, lines,
    internal low-pass, quantisation), 100 noise draws: the robust 95 % intervals cover every
    parameter's truth at least 90 times. The residuals are coloured, so the Gauss-Newton
    intervals, which assume them independent, are optimistic: measured at 5-8 of 16 while
    building this test, so they must cover less often than the robust ones."""
    names = ("fixed.mass", "p1.mass", "p1.length", "p1.damping")
    robust = {k: 0 for k in names}
    gauss_newton = {k: 0 for k in names}
    for seed in range(100):
        res, truth = _rig_fit(tmp_path, seed, 0.0)
        gn = res.gauss_newton_stderr
        for k in names:
            lo, hi = res.interval(k)
            robust[k] += lo <= truth[k] <= hi
            i = res.names.index(k)
            gauss_newton[k] += abs(res.values[i] - truth[k]) <= 1.96 * gn[i]
    print(f"\nrobust {robust}\nGauss-Newton {gauss_newton}")  # the counts, with -s
    assert all(h >= 90 for h in robust.values()), robust
    assert all(gauss_newton[k] < robust[k] for k in names), (gauss_newton, robust)


@pytest.mark.slow
def test_robust_intervals_cover_the_first_mode_when_a_second_is_missing(tmp_path):
    """The record holds a second slosh mode of 5 % of the first's mass (at 1.9 times its
    frequency) that the fitted model lacks: over 100 noise draws the robust intervals cover
    the first mode's parameters at least 85 times, while the fit reports the Gauss-Newton
    ones as optimistic (``FitResult.optimistic``, in the report's note) in at least 85.

    Without the model-error widening (``FitResult.model_error``, the residual over its noise
    figure: 2.6-3.0 here) the robust intervals covered p1.mass 15, p1.length 0 and
    p1.damping 36 times: the missing mode biases the first mode coherently with the move."""
    names = ("p1.mass", "p1.length", "p1.damping")
    robust = {k: 0 for k in names}
    flagged = 0
    for seed in range(100):
        res, truth = _rig_fit(tmp_path, seed, 0.05)
        for k in names:
            lo, hi = res.interval(k)
            robust[k] += lo <= truth[k] <= hi
        flagged += bool(set(names) & set(res.optimistic())) and "optimistic" in res.report()
    print(f"\nrobust {robust}, flagged optimistic {flagged}")  # the counts, with -s
    assert all(h >= 85 for h in robust.values()), robust
    assert flagged >= 85, flagged


@pytest.mark.slow
def test_intervals_cover_a_weak_spring_the_fit_may_hold_at_zero(tmp_path):
    """A true hinge spring of 0.1 N m/rad (an elastomeric diaphragm's share) driven by a
    light sine near resonance (20 s, 100 Hz, 0.2 mm at 2.0 Hz; f1 2.26 Hz) with force noise
    and a motor tone, 40 draws. The lateral force fixes the frequency, not the length and
    the spring apart, so in about a third of the draws the spring ends on 0 and is held
    there; the intervals then reach off that bound. The masses', the length's and the
    frequency's 95 % intervals cover the truth at least 34 times of 40 (a 95 % interval
    falls below 34 with probability 0.3 %). Measured: 38, 35, 40 and 38; without the reach
    the length's covered 28 (the 12 draws with the spring held at 0 all missed), and in one
    draw the fixed mass, on the liquid budget as well, missed by 7 standard errors."""
    p = pendulum(stiffness=0.1)
    f1 = float(np.sqrt(9.80665 / p.length + p.stiffness / (p.mass * p.length**2)) / (2 * np.pi))
    truth = {"fixed.mass": 1.456, "p1.mass": p.mass, "p1.length": p.length}
    hits = dict.fromkeys([*truth, "p1.frequency_hz"], 0)
    held = 0
    n = 40
    for seed in range(n):
        case, _ = make_case(tmp_path, f"K{seed}", ref.Ramped(ref.Sine(0.0002, 2.0), 1.0, 0.0),
                            pendulums=[p], duration=20.0, rate=100.0, seed=seed,
                            tone=ref.Tone(0.05, 25.0))
        res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)), progress=False)
        held += res.at_bound[res.names.index("p1.stiffness")] == "lower"
        for k, v in truth.items():
            lo, hi = res.interval(k)
            hits[k] += lo <= v <= hi
        lo, hi = res.derived_interval("p1.frequency_hz")
        hits["p1.frequency_hz"] += lo <= f1 <= hi
    assert held >= 5, held  # the case this test is about
    assert all(h >= 34 for h in hits.values()), hits


@pytest.mark.slow
@pytest.mark.parametrize("decimate", [1, 5])
def test_intervals_cover_the_masses_of_long_sine_records_through_a_transducer(tmp_path,
                                                                              decimate):
    """60 s at 500 Hz from rest, a 2 mm sine at 0.9 f1, the force through a six-axis
    transducer's model (``reference_rig_records.force_sensor``: white and 1/f noise, lines,
    internal low-pass, quantisation) 15 ms behind the displacement, ``fixed,p1`` with the
    lag estimated; 30 draws, fitted at 500 Hz and decimated to 100 Hz (``[test] decimate =
    5``). The estimated carriage motion absorbs the force noise inside its band, where a
    sine's information is, so the residuals understate it there: before the spectral floor
    (:mod:`estimate.fitting.spectral_sandwich`) the masses' intervals covered 32 and 33 of
    41 such draws (z-scores' spread 1.48). Now each mass's 95 % interval covers the truth at
    least 26 times of 30 (below 26 with probability 2 % at 95 %) and the z-scores spread by
    at most 1.25."""
    from estimate import load_case

    p = pendulum()
    f1 = float(np.sqrt(9.80665 / p.length) / (2 * np.pi))
    truth = {"fixed.mass": 1.456, "p1.mass": p.mass}
    hits = dict.fromkeys(truth, 0)
    z = {k: [] for k in truth}
    n = 30
    for seed in range(200, 200 + n):
        drive = ref.Ramped(ref.Sine(0.002, 0.9 * f1), 1.0, 0.0)
        case, sim = make_case(tmp_path, f"L{seed}", drive, pendulums=[p], duration=60.0,
                              rate=500.0, seed=seed, noise=0.0, sensor_delay=0.015)
        rr.force_through_sensor(tmp_path / f"L{seed}.csv", sim, seed)
        toml = tmp_path / f"L{seed}.toml"
        toml.write_text(toml.read_text().replace("[test]\n", f"[test]\ndecimate = {decimate}\n"))
        res = fit(FitProblem.build(load_case(toml), model_from_spec("fixed,p1", case)),
                  progress=False)
        for k, v in truth.items():
            lo, hi = res.interval(k)
            hits[k] += lo <= v <= hi
            z[k].append((res.value(k) - v) / res.stderr[res.names.index(k)])
    spread = {k: float(np.std(v)) for k, v in z.items()}
    print(f"\ncovered {hits}, z spread {spread}")  # the counts, with -s
    assert all(h >= 26 for h in hits.values()), hits
    assert all(s <= 1.25 for s in spread.values()), spread


@pytest.mark.slow
def test_the_fixed_mass_is_covered_when_a_mode_the_record_lacks_is_fitted(tmp_path):
    """6 s sine records from rest (0.9 f1, one mode, fixed mass 1.5 kg), fitted with
    ``fixed,p1,p2``: in about half the draws ``p2`` hunts the noise near its frequency and
    ends 4-12 times its mode's predicted mass, the fixed mass its partner (correlation
    -0.98), and the fixed mass's local intervals missed the truth in 13 of 18 draws (seeds
    2-19). With the intervals reaching to ``p2`` at its prediction
    (``FitResult.mode_shifts``) they missed 3 (all by under 1 %, with ``p2`` near its
    prediction). Unseen seeds 40-51: at least 9 of 12 (measured 10; the local intervals
    alone cover 4)."""
    hits, spurious = 0, 0
    for seed in range(40, 52):
        case, _, truth = rig_record(tmp_path, f"m{seed}",
                                    lambda f1: ref.Sine(0.0025, 0.9 * f1), seed=seed)
        res = fit(FitProblem.build(case, model_from_spec("fixed,p1,p2", case)), progress=False)
        lo, hi = res.interval("fixed.mass")
        hits += lo <= truth["fixed.mass"] <= hi
        spurious += bool(res.mode_shifts)
    print(f"\nfixed mass covered {hits} of 12; p2 above 3x its prediction in {spurious}")
    assert hits >= 9, (hits, spurious)


@pytest.mark.slow
def test_intervals_cover_an_unweighed_container_through_a_transducer_with_large_swings(
        tmp_path):
    """Several hardware effects at once: 20 s at 500 Hz from rest, a 1.5 mm downward sweep
    1.5 -> 0.7 f1 faded in over 1.5 s (the pendulum swings to 0.52 rad through resonance),
    the force through the six-axis transducer's model (coloured noise, lines, low-pass,
    quantisation) 20 ms behind the displacement, and the container not weighed
    (``dry_mass = "estimate"``: only the liquid mass is known). ``fixed,p1`` with the lag
    estimated; 12 draws. Each 95 % interval of the dry mass, the slosh mass and the
    pendulum length covers the truth at least 10 times of 12 (below 10 with probability 2 %
    at 95 %). Measured: 12 of 12 each (seeds 300-311, and 1-12 while writing the test); the
    Gauss-Newton intervals alone (white residuals assumed) cover 7, 5 and 11 of 12."""
    from estimate import load_case

    p = pendulum(1.30, 0.0553, 0.01)
    f1 = ref.natural_frequency(p, 9.80665) / (2 * np.pi)
    liquid = 2.842  # kg: the 8-inch sphere at 60 % (make_case's tank), split as below
    truth = {"rig.dry_mass": 1.2, "p1.mass": p.mass, "p1.length": p.length}
    hits = dict.fromkeys(truth, 0)
    for seed in range(300, 312):
        drive = ref.Ramped(ref.LinearSweep(0.0015, 1.5 * f1, 0.7 * f1, 20.0), 1.5, 0.0)
        case, sim = make_case(tmp_path, f"U{seed}", drive, pendulums=[p],
                              fixed_mass=liquid - p.mass, dry_mass=1.2, duration=20.0,
                              rate=500.0, seed=seed, noise=0.0, sensor_delay=0.02)
        rr.force_through_sensor(tmp_path / f"U{seed}.csv", sim, seed)
        toml = tmp_path / f"U{seed}.toml"
        text = toml.read_text()
        assert "dry_mass = 1.2" in text
        toml.write_text(text.replace("dry_mass = 1.2", 'dry_mass = "estimate"'))
        case = load_case(toml)
        res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)), progress=False)
        assert res.converged, (seed, res.status)
        for k, v in truth.items():
            lo, hi = res.interval(k)
            hits[k] += lo <= v <= hi
    print(f"\ncovered {hits} of 12")  # the counts, with -s
    assert all(h >= 10 for h in hits.values()), hits
