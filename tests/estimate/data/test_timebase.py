"""``[test] resample_hz``: receive-time timestamps that jitter, samples taken at irregular
times, and what cannot be done soundly (a coarser grid)."""

from __future__ import annotations

import re

import numpy as np
import pytest
import reference_rig_records as rig

from estimate.data import load_case, write_case
from estimate.data.case import CaseError, Liquid, Rig, Tank, TestInfo

RATE = 500.0
F_HZ = 1.7


def _case_files(tmp_path, time, values, extra: str):
    toml = f"""[test]
id = "j"
rig = "lateral"
data = "j.csv"
excitation = "measured"
{extra}

[tank]
shape = "sphere"
radius = 0.1
fill_fraction = 0.5
diaphragm = false

[liquid]
density = 998.2
kinematic_viscosity = 1.0e-6

[rig]
dry_mass = 1.0
gravity = 9.81
"""
    (tmp_path / "j.toml").write_text(toml)
    rows = "\n".join(f"{t:.9f},{0.01 * v:.12g},{v:.12g}" for t, v in zip(time, values))
    (tmp_path / "j.csv").write_text("time,displacement,force\n" + rows + "\n")
    return tmp_path / "j.toml"


def _uniform(n=3000):
    return np.arange(n) / RATE


def test_receive_times_are_placed_on_their_clock(tmp_path):
    """Samples taken on a uniform clock, stamped on arrival (+/- 1 ms at 500 Hz): the values
    stay as recorded, the times come back within 0.05 ms of the true ones (the line
    through 3000 stamps of 0.58 ms RMS jitter is good to ~0.02 ms; one stamp is 1 ms off)."""
    t = _uniform()
    values = np.sin(2 * np.pi * F_HZ * t)
    stamps = rig.receive_times(t, jitter=1e-3, rng=np.random.default_rng(3))
    case = load_case(_case_files(tmp_path, stamps, values, "resample_hz = 500.0"))
    assert np.max(np.abs(case.time - t)) < 5e-5
    assert np.allclose(case.force, values, rtol=0, atol=1e-11)  # not interpolated
    (note,) = case.notes
    assert re.search(r"j.csv: \[test\] resample_hz = 500: timestamps jitter by up to 1\.0\d ms .*"
                     r"receive times of uniformly taken samples, which were placed on the "
                     r"least-squares line through the timestamps, their values kept", note)


def test_jittered_stamps_without_resample_hz_name_the_key(tmp_path):
    t = _uniform()
    stamps = rig.receive_times(t, jitter=1e-3, rng=np.random.default_rng(3))
    path = _case_files(tmp_path, stamps, np.sin(t), "")
    with pytest.raises(CaseError, match=r"j.csv: column `time`: expected a uniform step .*"
                                        r"give `\[test\] resample_hz` \(Hz\)"):
        load_case(path)


def test_irregular_samples_are_interpolated(tmp_path):
    """Samples taken at irregular times (a polled logger: steps 1-3 ms): every channel is
    interpolated at the 500 Hz grid by a cubic spline; a 1.7 Hz sine comes back to 1e-8 of
    its amplitude (a cubic spline's error is ~(2 pi f h)^4 / 384: 1e-10 at a 3 ms step)."""
    rng = np.random.default_rng(0)
    times = np.cumsum(rng.uniform(1e-3, 3e-3, 3000))
    values = np.sin(2 * np.pi * F_HZ * times)
    case = load_case(_case_files(tmp_path, times, values, "resample_hz = 500.0"))
    assert np.allclose(np.diff(case.time), 1 / RATE, rtol=1e-9)
    assert case.time[0] == pytest.approx(times[0]) and case.time[-1] <= times[-1]
    assert np.max(np.abs(case.force - np.sin(2 * np.pi * F_HZ * case.time))) < 1e-8
    assert np.max(np.abs(case.displacement - 0.01 * case.force)) < 1e-12  # same interpolation
    (note,) = case.notes
    assert "timestamps irregular" in note and "one not-a-knot cubic spline each" in note


def test_a_dropped_sample_is_not_taken_for_jitter(tmp_path):
    """A uniform clock with one sample missing is not one clock: placing the later samples
    on a line would move them by a step; they are interpolated instead."""
    t = np.delete(_uniform(), 1500)
    values = np.sin(2 * np.pi * F_HZ * t)
    case = load_case(_case_files(tmp_path, t, values, "resample_hz = 500.0"))
    assert case.n_samples == 3000
    assert np.max(np.abs(case.force - np.sin(2 * np.pi * F_HZ * case.time))) < 1e-8
    assert "timestamps irregular" in case.notes[0]


def test_a_coarser_grid_is_refused(tmp_path):
    t = _uniform()
    path = _case_files(tmp_path, t, np.sin(t), "resample_hz = 100.0")
    with pytest.raises(CaseError, match=r"j.csv: \[test\] resample_hz: expected a rate at or "
                                        r"above the record's mean rate 500 Hz, found 100 Hz"):
        load_case(path)


@pytest.mark.parametrize("value, found", [("0.0", "0.0"), ('"fast"', "a string `'fast'`")])
def test_bad_resample_hz(tmp_path, value, found):
    t = _uniform()
    path = _case_files(tmp_path, t, np.sin(t), f"resample_hz = {value}")
    with pytest.raises(CaseError, match=re.escape("j.toml: [test] resample_hz: expected a ")
                       + ".*" + re.escape(found)):
        load_case(path)


def test_resample_hz_is_written_and_read_back(tmp_path):
    t = _uniform()
    stamps = rig.receive_times(t, jitter=1e-3, rng=np.random.default_rng(1))
    case = write_case(tmp_path / "w.toml", test=TestInfo("w", "lateral", "w.csv", "measured",
                                                         resample_hz=500.0, motion_band_hz=3.0),
                      tank=Tank("sphere", 0.1, 0.5, False), liquid=Liquid(998.2, 1.0e-6),
                      rig=Rig(1.0, 9.81), time=stamps, force=np.sin(t),
                      displacement=0.01 * np.sin(t))
    assert case.test.resample_hz == 500.0 and case.test.motion_band_hz == 3.0
    assert np.max(np.abs(case.time - t)) < 5e-5
