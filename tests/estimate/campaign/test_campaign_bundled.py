"""The bundled SYNTHETIC campaign (``examples/campaign``, 12 records made by the independent
reference simulator; truth: the exact tank prediction per fill) run with the README's command:
each fill's group fit reproduces the generator's parameters within the fit tolerances, the
record with the hidden second mode is the one outlier, and a 2-worker Dask cluster writes
the same table as the local run; `--diagnose` names the hidden mode. Slow: about a minute
of fits, twice, and two diagnoses."""

from __future__ import annotations

import shlex

import pytest
from campaign_helpers import BUNDLED, MODEL, ROOT, TOLERANCES, TRUTH, copy_records, read_csv

from estimate.cli import main

pytestmark = pytest.mark.slow
HIDDEN = "F60_sweep_0.6mm"


def readme_command() -> list[str]:
    """The README's one command that runs the bundled campaign, as arguments of `slosh`."""
    text = (ROOT / "README.md").read_text()
    line = next(ln for ln in text.splitlines() if "slosh campaign examples/campaign" in ln)
    return shlex.split(line.split("&& slosh ", 1)[1])


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    out = tmp_path_factory.mktemp("bundled") / "local"
    args = readme_command()
    assert args[:2] == ["campaign", "examples/campaign"] and args[2] == "--out", args
    args[1], args[3] = str(ROOT / args[1]), str(out)
    assert main(args) == 0
    return out


def test_each_fill_reproduces_the_generator_within_the_fit_tolerances(local):
    rows = {r["id"]: r for r in read_csv(local / "campaign.csv")}
    groups = [r for r in rows.values() if r["kind"] == "group"]
    assert sorted(float(g["fill_fraction"]) for g in groups) == [0.4, 0.6, 0.8]
    for g in groups:
        truth = TRUTH["fills"][f"{float(g['fill_fraction']):g}"]
        for q, tol in TOLERANCES.items():
            unit = {"fixed.mass": " [kg]", "p1.mass": " [kg]", "p1.frequency_hz": " [Hz]"}.get(q, "")
            assert abs(float(g[q + unit]) / truth[q] - 1) < tol, (g["id"], q)
    assert len([r for r in rows.values() if r["kind"] == "record"]) == 12


def test_the_hidden_second_mode_is_the_one_outlier_and_stays_out_of_its_group(local):
    rows = read_csv(local / "campaign.csv")
    assert [r["id"] for r in rows if r["outlier"] == "true"] == [HIDDEN]
    g60 = next(r for r in rows if r["kind"] == "group" and r["fill_fraction"] == "0.6")
    assert g60["excluded"] == f"{HIDDEN} (outlier)" and HIDDEN not in g60["records"]
    report = (local / "report" / "report.md").read_text()
    assert f"**{HIDDEN}** (group {g60['id']}), left out of the group fit" in report
    assert (local / "report" / "amplitude.png").is_file()


def test_a_two_worker_dask_cluster_writes_the_same_table(local, tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "dask"
    assert main(["campaign", str(BUNDLED), "--out", str(out), "--cluster", "2"]) == 0
    for name in ("campaign.csv", "campaign.parquet"):
        assert (out / name).read_bytes() == (local / name).read_bytes()


def test_diagnose_names_the_hidden_mode_in_the_verdict_column(tmp_path):
    """`--diagnose` on the hidden-mode record and a clean one of the same fill (slow: two
    diagnoses, about 100 s on 2 busy cores)."""
    folder = copy_records(tmp_path / "cases", [HIDDEN, "F60_sweep_0.3mm"],
                          campaign_toml=f'[campaign]\nmodel = "{MODEL}"\n')
    out = tmp_path / "out"
    assert main(["campaign", str(folder), "--out", str(out), "--diagnose"]) == 0
    verdicts = {r["id"]: r["verdict"] for r in read_csv(out / "campaign.csv")
                if r["kind"] == "record"}
    assert verdicts["F60_sweep_0.3mm"] == "no finding"
    assert "(+p2" in verdicts[HIDDEN], verdicts       # a second pendulum is what it lacks
    report = (out / "report" / "report.md").read_text()
    assert f"**{HIDDEN}**" in report and f"diagnosis: {verdicts[HIDDEN]}" in report
    # what it found, with its numbers (the row and the report)
    row = next(r for r in read_csv(out / "campaign.csv") if r["id"] == HIDDEN)
    assert float(row["diagnosed p2.mass [kg]"]) > 0 and float(row["diagnosed p2.mass stderr [kg]"]) > 0
    assert "`p2.mass`" in report
