"""``[test] decimate = k``: a record sampled far above the slosh band fitted on every k-th
sample after a zero-phase anti-alias low-pass (issue 27)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from estimate.data import CaseError, load_case
from estimate.data.decimation import FLAT, ORDER, PASSBAND, decimate_record

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def _amplitude(t: np.ndarray, y: np.ndarray, hz: float) -> tuple[float, float]:
    """Amplitude and phase [rad] of the ``hz`` sinusoid in ``y`` (least squares with an
    offset)."""
    w = 2 * math.pi * hz
    A = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t)])
    c, *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(np.hypot(c[0], c[1])), float(np.arctan2(-c[1], c[0]))


def test_the_slosh_band_is_kept_exactly_and_the_rest_is_filtered_as_documented():
    """A 2.1 Hz swing, a 45 Hz line and 150 Hz noise at 500 Hz, decimated by 5 (100 Hz): away
    from the ends the swing keeps its amplitude and phase to 1e-6 (the forward-backward
    Butterworth's gain ``1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^16)``, the bilinear
    transform's, is 1 - 1e-19 there, and it shifts nothing); the 45 Hz line (above the flat
    band, 0.3 of the new rate) keeps that gain, 0.122 (to 1 %), and the 150 Hz component, which
    would alias to 50 Hz, is gone (gain 1e-12)."""
    t = np.arange(10001) / 500.0
    swing = 0.3 * np.cos(2 * math.pi * 2.1 * t + 0.7)
    line = 0.01 * np.cos(2 * math.pi * 45.0 * t)
    high = 0.2 * np.cos(2 * math.pi * 150.0 * t + 0.3)
    problems: list[str] = []
    kept, out, note = decimate_record("r.csv", t, {"force": swing + line + high,
                                                   "displacement": swing}, 5, problems)
    assert problems == [] and kept.size == 2001 and np.allclose(np.diff(kept), 0.01)
    assert "500 -> 100 Hz, 10001 -> 2001 samples" in note and "every 5th sample" in note
    inner = slice(100, -100)  # 1 s from the ends, past the filter's start-up
    tk = kept[inner]
    exact = 0.3 * np.cos(2 * math.pi * 2.1 * tk + 0.7)
    assert np.max(np.abs(out["displacement"][inner] - exact)) < 1e-6 * 0.3
    rest = out["force"][inner] - out["displacement"][inner]  # the line and what is left above
    def gain(f, new_rate=100.0, factor=5):
        fs, fc = new_rate * factor, PASSBAND * new_rate
        return 1.0 / (1.0 + (math.tan(math.pi * f / fs) / math.tan(math.pi * fc / fs)) ** (2 * ORDER))

    amp, _ = _amplitude(tk, rest, 45.0)
    assert amp == pytest.approx(0.01 * gain(45.0), rel=0.01)
    assert np.std(rest - amp * np.cos(2 * math.pi * 45.0 * tk + _amplitude(tk, rest, 45.0)[1])) \
        < 1e-6 * 0.2
    # the flat band: at least 95 % of the power passes up to FLAT of the new rate, whatever
    # the factor (the bilinear transform only steepens the fall)
    for factor in (2, 5, 10, 100):
        assert gain(FLAT * 100.0, factor=factor) ** 2 >= 0.95


def _case(folder: Path, test_lines: str, csv: bytes | None = None) -> Path:
    if csv is not None:
        (folder / "A1.csv").write_bytes(csv)
    else:
        (folder / "A1.csv").write_bytes((EXAMPLES / "A1.csv").read_bytes())
    toml = (EXAMPLES / "A1.toml").read_text().replace("[test]\n", f"[test]\n{test_lines}\n", 1)
    (folder / "A1.toml").write_text(toml)
    return folder / "A1.toml"


def test_a_case_file_decimates_its_record_and_says_so(tmp_path):
    full = load_case(EXAMPLES / "A1.toml")
    case = load_case(_case(tmp_path, "decimate = 2"))
    assert case.test.decimate == 2
    assert case.time.size == math.ceil(full.time.size / 2)
    assert np.allclose(case.time, full.time[::2])
    problems: list[str] = []
    _, out, _ = decimate_record("A1.csv", full.time, {"force": full.force,
                                                      "displacement": full.displacement},
                                2, problems)
    assert np.array_equal(case.force, out["force"])
    assert np.array_equal(case.displacement, out["displacement"])
    assert any("A1.csv: decimated by 2 for the fit ([test] decimate): 100 -> 50 Hz" in n
               for n in case.notes)


@pytest.mark.parametrize("value, expected", [
    ("0", "[test] decimate: expected an integer >= 1 (keep every k-th sample after an "
          "anti-alias low-pass), found an integer `0`"),
    ("2.5", "found a float `2.5`"),
    ('"5"', "found a string `'5'`"),
    ("true", "found a boolean `True`"),
    ("3", "A1.csv: [test] decimate = 3: the record's 100 Hz would become 33.3 Hz; expected at "
          "least 40 Hz (a passband to 16 Hz, above the slosh modes and the carriage's motion): "
          "decimate by at most 2"),
    ("2\nmotion_band_hz = 25.0", "A1.csv: [test] decimate = 2: the passband would end at 20 Hz, "
                                 "below [test] motion_band_hz = 25 Hz; decimate by at most 1"),
])
def test_a_decimation_the_record_cannot_take_is_refused(tmp_path, value, expected):
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, f"decimate = {value}"))
    assert expected in str(info.value)


def test_too_few_samples_left_are_refused(tmp_path):
    rows = (EXAMPLES / "A1.csv").read_bytes().splitlines(keepends=True)[:151]  # 1.5 s
    with pytest.raises(CaseError, match=r"150 samples would become 75; expected at least 100"):
        load_case(_case(tmp_path, "decimate = 2", b"".join(rows)))


def test_a_record_over_the_budget_is_read_when_it_is_decimated(tmp_path, monkeypatch):
    """32 MiB admit 2048 samples: A1's 3001 are refused, with the case key that decimates
    them; decimated by 2 (1501 samples) they are read."""
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "32M")
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, ""))
    assert "3001 samples" in str(info.value) and "`[test] decimate = 2`" in str(info.value)
    case = load_case(_case(tmp_path, "decimate = 2"))
    assert case.time.size == 1501


def test_slosh_fit_decimates_on_request_and_says_so(tmp_path, capsys):
    """``--decimate 2`` fits A1's 3001 samples at 100 Hz as 1501 at 50 Hz, with the note in
    the output and the JSON."""
    import json

    from estimate.cli import main

    out = tmp_path / "fit.json"
    assert main(["fit", str(EXAMPLES / "A1.toml"), "--decimate", "2", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "note: A1.csv: decimated by 2 for the fit (--decimate): 100 -> 50 Hz, 3001 -> 1501" \
        in printed
    data = json.loads(out.read_text())
    assert any("decimated by 2 for the fit (--decimate): 100 -> 50 Hz, 3001 -> 1501 samples" in n
               for n in data["notes"])


@pytest.mark.parametrize("value", ["0", "two"])
def test_slosh_fit_refuses_a_decimation_that_is_not_a_factor(value, capsys):
    from estimate.cli import main

    with pytest.raises(SystemExit) as info:
        main(["fit", str(EXAMPLES / "A1.toml"), "--decimate", value])
    assert info.value.code == 2
    assert f"--decimate: expected an integer >= 1, found '{value}'" in capsys.readouterr().err


def test_slosh_fit_refuses_a_decimation_the_record_cannot_take(capsys):
    from estimate.cli import main

    assert main(["fit", str(EXAMPLES / "A1.toml"), "--decimate", "3"]) == 2
    assert ("A1.csv: --decimate 3: the record's 100 Hz would become 33.3 Hz"
            in capsys.readouterr().err)


@pytest.mark.parametrize("again", ["2", "1"])
def test_a_case_decimated_twice_is_refused(tmp_path, capsys, again):
    """``--decimate 2`` or ``--decimate 1`` (every sample) on a case that says ``[test]
    decimate = 2``: refused, not one of them silently kept."""
    from estimate.cli import main

    assert main(["fit", str(_case(tmp_path, "decimate = 2")), "--decimate", again]) == 2
    assert (f"A1.toml: --decimate {again}: the case decimates its record by 2 already ([test] "
            "decimate); give one of them") in capsys.readouterr().err



def _fast_record(tmp_path):
    """20 s at 500 Hz from rest (10,001 samples): ``synthetic_cases.sweep_record``."""
    from synthetic_cases import sweep_record

    return sweep_record(tmp_path, "F", 20.0, seed=21)[0]


def test_slosh_fit_decimates_a_long_fast_record_by_default_and_says_so(tmp_path, capsys):
    """10,001 samples at 500 Hz: ``slosh fit`` fits them at 100 Hz (the fit record's noise
    at 100 Hz, a note naming the default and how to keep every sample); ``--decimate 1``
    fits every sample at 500 Hz (asked for: not told to decimate); the slosh mass's estimates
    agree within a standard error. A1 itself (3,001 samples at 100 Hz) is fitted as it is
    (``test_slosh_fit_decimates_on_request_and_says_so``, the README's quick start)."""
    import json

    from estimate.cli import main

    case = _fast_record(tmp_path)
    fits = {}
    for extra, rate in (([], 100.0), (["--decimate", "1"], 500.0)):
        out = tmp_path / f"fit{rate:g}.json"
        assert main(["fit", str(case.path), "--json", str(out), *extra]) == 0
        data = fits[rate] = json.loads(out.read_text())
        assert [n["sample_rate_hz"] for n in data["noise"]] == [pytest.approx(rate)]
        said = [n for n in data["notes"] if "F.csv: decimated by 5 for the fit (by default" in n]
        told = [n for n in data["notes"] if "far above the slosh band: `[test] decimate = 5`" in n]
        assert (len(said), len(told)) == ((1, 0) if rate == 100.0 else (0, 0)), data["notes"]
        assert data["converged"]
    capsys.readouterr()
    dec, full = (fits[r]["parameters"]["p1.mass"] for r in (100.0, 500.0))
    assert abs(dec["value"] - full["value"]) < full["stderr"], (dec, full)
    assert abs(dec["value"] - 1.30) < 2 * dec["stderr"], dec


def test_the_budget_counts_the_samples_slosh_fit_keeps(tmp_path, monkeypatch, capsys):
    """64 MiB admit 4096 samples. The 10,001-sample, 500 Hz record: ``slosh fit`` decimates
    it to 2,001 by default, so it is read and fitted; ``--decimate 1`` (every sample) and
    ``slosh diagnose`` (its final fit takes every sample) refuse it before reading a row,
    naming the factor that would fit; ``--decimate 5`` reads it."""
    from estimate.cli import main

    case = _fast_record(tmp_path)
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "64M")
    assert main(["fit", str(case.path), "--decimate", "1"]) == 2
    assert "F.csv: rows: 10001 samples; " in capsys.readouterr().err
    assert main(["diagnose", str(case.path), "--json", str(tmp_path / "d.json")]) == 2
    assert "`[test] decimate = 3`" in capsys.readouterr().err
    out = tmp_path / "fit.json"
    for extra in ([], ["--decimate", "5"]):
        assert main(["fit", str(case.path), "--json", str(out), "--overwrite", *extra]) == 0
        assert "10001 -> 2001 samples" in capsys.readouterr().out


def test_a_campaign_fits_a_long_fast_record_as_slosh_fit_does(tmp_path):
    """A campaign's fit of the 10,001-sample, 500 Hz record fits its 2,001 samples at
    100 Hz, as ``slosh fit`` does, and finds the slosh mass within two standard errors."""
    from estimate.campaign.tasks import Task, run_task

    case = _fast_record(tmp_path)
    out = run_task(Task("fit", "k", "record F", (case,), "fixed,p1"))
    assert out["status"] == "ok", out
    assert out["samples"] == 2001
    value, stderr = out["parameters"]["p1.mass"][:2]
    assert abs(value - 1.30) < 2 * stderr, (value, stderr)


def test_only_a_record_whose_motion_band_is_known_is_decimated_by_default(tmp_path):
    """The 10,001-sample, 500 Hz sweep (its displacement's band about 2 Hz): by 5 to 100 Hz;
    a 25 s, 500 Hz six-axis record (12,501 samples; its motion is in columns whose band is
    not read): left as it is. ``[test] motion_band_hz`` keeps the motion inside the flat
    0.3 of the new rate: 20 Hz leaves 5 (0.3 x 100 Hz = 30 Hz), 40 Hz allows 3 (50 Hz;
    4 would leave 37.5 Hz)."""
    from dataclasses import replace

    import reference_motion as rm
    from motion_cases import PENDULUM, make_motion_case

    from estimate.data.decimation import slosh_band_factor

    case = _fast_record(tmp_path)
    assert slosh_band_factor(case) == 5
    motion = rm.Motion(x=rm.RampedSine(0.002, PENDULUM.frequency_hz(), ramp=1.5, start=0.5))
    six, _ = make_motion_case(tmp_path, "six", motion, duration=25.0, rate=500.0, seed=4)
    assert six.time.size == 12501 and slosh_band_factor(six) is None
    for band, factor in ((20.0, 5), (40.0, 3)):
        banded = replace(case, test=replace(case.test, motion_band_hz=band))
        assert slosh_band_factor(banded) == factor, band


def test_a_record_over_what_the_default_decimation_admits_is_refused_by_its_rows(
        tmp_path, monkeypatch):
    """32 MiB admit 2048 samples; ``slosh fit`` reads up to 10 times that for its default
    decimation: A1's 3001 samples load with that allowance, and a refusal past it names the
    factor to decimate by and what the record was read for (not a case key it lacks)."""
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "32M")
    assert load_case(_case(tmp_path, ""), allowance=10).time.size == 3001
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "2M")  # 128 samples, 1280 with the allowance
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, ""), allowance=10)
    text = str(info.value)
    assert "A1.csv: rows: 3001 samples" in text and "`[test] decimate = 24`" in text
    assert "(it was read for a fit of every 10th sample)" in text
