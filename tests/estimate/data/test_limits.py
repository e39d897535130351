"""Resource limits (issue 13, bad finding 3): records too large for the memory budget are
refused before anything is allocated for them; filter padding is bounded in samples."""

from __future__ import annotations

import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from analogs.errors import InputError
from estimate.data import CaseError, load_case
from estimate.data.budget import FIT_BYTES_PER_SAMPLE, check_fit, fit_bytes, max_samples, memory_budget
from estimate.data.signals import lowpass

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def _case(folder: Path, csv: bytes) -> Path:
    (folder / "big.csv").write_bytes(csv)
    toml = (EXAMPLES / "A1.toml").read_text().replace('"A1.csv"', '"big.csv"')
    (folder / "big.toml").write_text(toml)
    return folder / "big.toml"


def test_the_budget_comes_from_the_environment(monkeypatch):
    monkeypatch.delenv("SLOSH_MEMORY_BUDGET", raising=False)
    assert memory_budget() == 4 * 2**30 and max_samples() == 4 * 2**30 // FIT_BYTES_PER_SAMPLE
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "512M")
    assert memory_budget() == 512 * 2**20
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "1.5GiB")
    assert memory_budget() == int(1.5 * 2**30)
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "lots")
    with pytest.raises(InputError, match=r"SLOSH_MEMORY_BUDGET='lots': expected a memory size"):
        memory_budget()


def test_ten_million_rows_are_refused_in_seconds_without_reading_them(tmp_path, monkeypatch):
    """The review's 10-million-row CSV took 48 s and 5.2 GB to load and the fit reached
    19.4 GB; now the rows are counted in 1 MiB chunks and the record is refused with the
    samples it holds and by how much to decimate it."""
    monkeypatch.delenv("SLOSH_MEMORY_BUDGET", raising=False)
    path = _case(tmp_path, b"time,displacement,force\n" + b"0.0001,0.00001,-2.5\n" * 10_000_000)
    tracemalloc.start()
    start = time.perf_counter()
    with pytest.raises(CaseError) as info:
        load_case(path)
    seconds = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    msg = str(info.value)
    assert "big.csv: rows: 10000000 samples" in msg and "memory budget of 4 GiB" in msg
    assert "decimate by 39" in msg and "SLOSH_MEMORY_BUDGET" in msg
    assert peak < 16 * 2**20, peak  # a few chunks, never the rows
    assert seconds < 20.0, seconds


def test_a_fit_is_checked_with_its_channels(monkeypatch):
    """The measured peaks (``estimate.data.budget``): 8-13 KiB per sample for lateral
    fits of one channel, 40 KiB for the spinning rig's six; the check counts 16 KiB and 46
    KiB, so a six-channel record that reads within the budget is refused at its fit,
    naming the case, its channels and how much to decimate."""
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "1G")
    assert fit_bytes(1000, 1) == 16 * 2**10 * 1000
    assert fit_bytes(1000, 6) == 46 * 2**10 * 1000
    check_fit([("lateral.csv", 60_000, 1)])  # 0.92 GiB
    with pytest.raises(InputError) as info:
        check_fit([("spin.csv", 60_000, 6)])
    msg = str(info.value)
    assert "spin.csv: 60000 samples x 6 channels" in msg and "memory budget of 1 GiB" in msg
    assert "decimate by 3" in msg


def test_a_record_within_a_larger_budget_is_read(tmp_path, monkeypatch):
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "32M")  # 2048 samples
    lines = (EXAMPLES / "A1.csv").read_bytes().splitlines(keepends=True)
    with pytest.raises(CaseError, match="3001 samples.*decimate by 2"):
        load_case(_case(tmp_path, b"".join(lines)))
    assert load_case(_case(tmp_path, b"".join(lines[:2001]))).time.size == 2000


def test_padding_is_bounded_in_samples_whatever_the_sampling_rate():
    """A 1 ns step asked for a second of padding, 1e9 samples (8 GB); at most two records
    of padding are used now, and the filter still passes a slow sine unchanged."""
    t = np.arange(3001) * 1e-9
    y = np.sin(2 * np.pi * 2e5 * t)
    tracemalloc.start()
    out = lowpass(t, y, cutoff_hz=2e7)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 50 * 2**20
    assert np.max(np.abs(out - y)[300:-300]) < 1e-3
