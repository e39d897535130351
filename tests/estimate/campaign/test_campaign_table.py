"""The campaign table (rows, exact CSV, Parquet), its optional dependency, the progress line
and the executors' completion-order interface."""

from __future__ import annotations

import io
import math
import sys
import threading
import time

import pytest
from campaign_helpers import case_toml

from analogs.errors import MissingDependency
from estimate.campaign import CampaignRun, Outlier, campaign_table, discover
from estimate.campaign.progress import Progress
from estimate.executor import Executor, LocalExecutor


def fit_outcome(mass, ids, status="ok"):
    return {"status": status, "error": None if status == "ok" else "IPOPT: x", "cases": ids,
            "model": "fixed,p1", "iterations": 7, "samples": 100 * len(ids),
            "rms_residual": 0.02, "noise": 0.01,
            "parameters": {"p1.mass": [mass, 0.01, mass - 0.02, mass + 0.02, "kg"]},
            "derived": {"p1.damping_ratio": [0.1 + mass, 0.001, math.nan, 0.2, "-"]},
            "records": {i: {"amplitude_m": 0.001 * (k + 1), "samples": 100}
                        for k, i in enumerate(ids)}}


@pytest.fixture
def run(tmp_path):
    for name, fill in (("a", 0.4), ("b", 0.4), ("c", 0.6)):
        case_toml(tmp_path, name, fill=fill)
    (tmp_path / "campaign.toml").write_text('[groups.low]\nrecords = ["a", "b"]\n')
    c = discover(str(tmp_path))
    records = {"a": fit_outcome(1.0 + 0.1, ["a"]), "b": fit_outcome(1.0, ["b"]),
               "c": {"status": "failed", "error": "c.csv: column `force`: bad", "stage": "load"}}
    group = fit_outcome(1.05, ["a", "b"]) | {"members": ["a", "b"], "excluded": {}}
    return CampaignRun(c, records, {"low": group}, {"a": {"status": "ok", "verdict": "no finding"}},
                       [Outlier("a", "low", ("p1.mass = 1.1 against 1",))], 3.0, 2, 1, 1, 0.5)


def test_rows_columns_and_exact_csv(run):
    table = campaign_table(run)
    assert [(r["kind"], r["id"]) for r in table.rows] == [
        ("group", "low"), ("record", "a"), ("record", "b"), ("record", "c")]
    assert table.quantities == {"p1.mass": "kg", "p1.damping_ratio": "-"}
    names = [c for c, _ in table.columns]
    for col in ("p1.mass [kg]", "p1.mass stderr [kg]", "p1.mass lo95 [kg]", "p1.mass hi95 [kg]",
                "p1.damping_ratio", "residual/noise", "verdict", "outlier", "excluded"):
        assert col in names
    lines = table.to_csv().decode().splitlines()
    assert lines[0].split(",")[:3] == ["kind", "id", "group"]
    import csv

    rows = list(csv.DictReader(io.StringIO(table.to_csv().decode())))
    a, c = rows[1], rows[3]
    assert float(a["p1.mass [kg]"]) == 1.0 + 0.1        # shortest exact form, not rounded
    assert a["p1.damping_ratio lo95"] == "" and a["outlier"] == "true"
    assert a["verdict"] == "no finding" and a["drive_amplitude [m]"] == "0.001"
    assert a["residual/noise"] == "2.0" and rows[0]["records"] == "a;b"
    assert c["status"] == "failed" and "column `force`" in c["error"] and c["p1.mass [kg]"] == ""
    assert c["fill_fraction"] == "0.6" and c["outlier"] == "false"


def test_parquet_holds_the_same_table(run):
    pq = pytest.importorskip("pyarrow.parquet")
    import pyarrow as pa

    table = campaign_table(run)
    back = pq.read_table(pa.BufferReader(table.to_parquet()))
    assert back.column_names == [c for c, _ in table.columns]
    assert back.column("p1.mass [kg]").to_pylist()[:3] == [1.05, 1.1, 1.0]
    assert back.column("p1.damping_ratio lo95").to_pylist()[1] is None   # NaN -> null
    assert back.column("outlier").to_pylist() == [None, True, False, False]
    assert back.column("samples").type == pa.int64()
    assert table.to_parquet() == campaign_table(run).to_parquet()          # deterministic


def test_missing_pyarrow_names_the_extra(run, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    with pytest.raises(MissingDependency, match=r"pip install '\.\[campaign\]'"):
        campaign_table(run).to_parquet()


def test_progress_shows_on_a_terminal_only():
    quiet = io.StringIO()
    p = Progress(2, stream=quiet)
    p.expect(3)
    assert quiet.getvalue() == ""
    shown = io.StringIO()
    p = Progress(2, stream=shown, enabled=True)
    p.expect(5)
    p.from_store(1)
    p.submit(4)
    p.finish(True, 2.0)
    p.finish(False, 4.0)
    # 2 tasks left x 3 s mean / 2 workers
    assert p.line() == ("campaign: 3/5 tasks done (1 from the store), 1 failed, 2 running, "
                        "about 0:03 left")
    assert shown.getvalue().endswith(p.line())


def test_the_time_left_weighs_tasks_by_their_work_and_counts_planned_groups():
    p = Progress(2, enabled=False)
    p.plan(1, 300.0)                       # one group of 300 units, fitted after the records
    p.expect(3, 300.0)                     # three records of 100 units
    p.submit(3)
    p.finish(True, 5.0, 100.0)             # 0.05 s per unit
    p.finish(False, 0.0, 100.0)            # failed to load: done, but tells no speed
    # 100 + 300 units left at 0.05 s per unit on 2 workers
    assert p.line() == ("campaign: 2/4 tasks done (0 from the store), 1 failed, 1 running, "
                        "about 0:10 left")
    p.finish(True, 5.0, 100.0)
    p.plan(0)
    p.expect(1, 300.0)
    # the group alone: one worker runs it, 300 units at 0.05 s
    assert p.line().startswith("campaign: 3/4 tasks done") and p.line().endswith("0:15 left")


def _square(x, shared=None):
    if x == 3:
        raise ValueError("three")
    return x * x


@pytest.mark.parametrize("executor", [Executor(), LocalExecutor(2)])
def test_as_completed_yields_every_task_once(executor):
    got = {}
    for i, future in executor.as_completed(_square, [0, 1, 2, 3, 4]):
        try:
            got[i] = future.result()
        except ValueError as err:
            got[i] = str(err)
    assert got == {0: 0, 1: 1, 2: 4, 3: "three", 4: 16}


def test_closing_as_completed_cancels_tasks_not_started():
    started = []
    lock = threading.Lock()

    def slow(x, shared=None):
        with lock:
            started.append(x)
        time.sleep(0.05)
        return x

    it = LocalExecutor(1).as_completed(slow, list(range(20)))
    next(it)
    it.close()
    time.sleep(0.2)
    assert len(started) <= 3


def test_a_diagnosed_record_row_holds_what_the_diagnosis_found(run):
    """New-user report defect 10: the row said "slosh_mode (+p2)" without p2's numbers."""
    import dataclasses

    from estimate.campaign.report import summary

    found = {"status": "ok", "verdict": "slosh_mode (+p2)", "cases": ["b"],
             "findings": [{"cause": "slosh_mode", "added": ["p2"], "gain": 0.4,
                           "bic_change": -80.0}],
             "final_parameters": {"p1.mass": [1.02, 0.01, 1.0, 1.04, "kg"],
                                  "p2.mass": [0.066, 0.002, 0.062, 0.070, "kg"]},
             "final_derived": {"p2.frequency_hz": [4.21, 0.01, 4.19, 4.23, "Hz"]}}
    run = dataclasses.replace(run, diagnoses={**run.diagnoses, "b": found})
    table = campaign_table(run)
    row = next(r for r in table.rows if r["id"] == "b")
    assert row["diagnosed p2.mass [kg]"] == 0.066 and row["diagnosed p2.mass stderr [kg]"] == 0.002
    assert row["diagnosed p2.frequency_hz [Hz]"] == 4.21
    assert row["diagnosed p1.mass [kg]"] == 1.02 and row["p1.mass [kg]"] == 1.0  # both fits
    other = next(r for r in table.rows if r["id"] == "a")
    assert math.isnan(other["diagnosed p2.mass [kg]"])
    text = summary(run, table, figures=[])
    assert "slosh_mode (+p2): `p2.mass` 0.066 +/- 0.002 kg, `p2.frequency_hz` 4.21 +/- 0.01 Hz" \
        in text
    # without --diagnose: no such columns
    plain = campaign_table(dataclasses.replace(run, diagnoses={}))
    assert not any(c.startswith("diagnosed ") for c, _ in plain.columns)


def test_campaign_outputs_get_the_mode_of_any_other_output(run, tmp_path):
    """New-user report defect 11: campaign.csv/.parquet/.json were 0600, report/ 0700."""
    import os
    import stat

    from estimate.campaign.report import claim_folder, write_outputs

    mask = os.umask(0o022)
    try:
        out = tmp_path / "out"
        claim_folder(out, str(tmp_path))
        write_outputs(run, out)
    finally:
        os.umask(mask)
    modes = {p.relative_to(out).as_posix(): stat.S_IMODE(p.stat().st_mode)
             for p in [out / "campaign.csv", out / "campaign.parquet", out / "campaign.json",
                       out / "report", out / "report" / "report.md"]}
    assert modes == {"campaign.csv": 0o644, "campaign.parquet": 0o644, "campaign.json": 0o644,
                     "report": 0o755, "report/report.md": 0o644}


def test_plot_titles_name_the_quantity_as_text_and_match_their_axes(run, tmp_path, monkeypatch):
    """A figure draws Markdown backticks literally; the amplitude panels are in per cent of
    the group's fit, so their titles carry no unit (the fill panels' values are in it)."""
    from matplotlib.figure import Figure

    from estimate.campaign.plots import _title, plot_against_amplitude

    shown = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: shown.append(self))
    plot_against_amplitude(campaign_table(run), ["p1.mass", "p1.damping_ratio"], tmp_path / "a.png")
    panels = [ax for ax in shown[0].axes if ax.get_visible()]
    assert [ax.get_title() for ax in panels] == ["p1 pendulum mass (p1.mass)",
                                                 "p1 damping ratio (p1.damping_ratio)"]
    assert all(ax.get_ylabel() == "% from the group fit" for ax in panels)
    assert _title("fixed.mass", "kg") == "fixed mass (fixed.mass) [kg]"
    assert _title("p1.frequency_hz", "Hz") == "p1 frequency (p1.frequency_hz) [Hz]"
