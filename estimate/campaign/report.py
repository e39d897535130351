"""The campaign's outputs, written as one transaction: the table (``campaign.csv``,
``campaign.parquet``) and the report folder (``report/report.md`` with ``fill.png`` and,
where the campaign varies the drive amplitude, ``amplitude.png``).

Everything is built first (the report in a hidden temporary folder); then each file is
renamed into place and the report folder swapped for the old one, so an interrupted or
failed write leaves the previous outputs as they were.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

from ..diagnosis.scoring import NOISE_MARGIN
from ..inputs import load_json
from ..outputs import output_mode
from .discovery import Setup
from .outliers import FAMILY_ERROR, MIN_RECORDS
from .plots import amplitude_varies, plot_against_amplitude, plot_against_fill, plotted_quantities
from .predictions import METHODS, pendulum_count, predicted, prediction_curves
from .runner import CampaignRun
from .store import package_version, write_atomic
from .table import CampaignTable, campaign_table, quantity_column

__all__ = ["MANIFEST", "MISFIT_RATIO", "OUTPUTS", "claim_folder", "summary", "write_outputs"]

#: A fit that explains a record leaves an RMS residual of about its noise figure
#: (:mod:`estimate.fitting.noise_figures`); above the diagnosis's margin it is signal the
#: model misses, and the report lists the record.
MISFIT_RATIO = NOISE_MARGIN
#: Output files of a campaign folder besides the store.
OUTPUTS = ("campaign.csv", "campaign.parquet", "report")
#: The file naming the campaign a folder belongs to.
MANIFEST = "campaign.json"


def _num(v: float) -> str:
    return "" if v is None or not math.isfinite(v) else f"{v:.5g}"


def _setups(run: CampaignRun) -> dict[str, Setup]:
    c = run.campaign
    out = {}
    for g in c.groups:
        setup = next((c.record(i).setup for i in g.records if c.record(i).setup), None)
        if setup is not None:
            out[g.name] = setup
    return out


def _group_section(row: dict[str, Any], table: CampaignTable, setup: Setup | None,
                   quantities: list[str], pendulums: int) -> list[str]:
    lines = [f"### {row['id']}", "",
             f"Fill {100 * row['fill_fraction']:.4g} %, records {row['records'] or '(none)'}; "
             f"status {row['status']}" + (f" ({row['error']})" if row["error"] else "")
             + (f"; excluded: {row['excluded']}" if row["excluded"] else "") + ".", ""]
    if row["status"] == "failed":
        return lines
    preds = {}
    if setup is not None:
        for m in METHODS:
            try:
                preds[m] = predicted(setup, row["fill_fraction"], pendulums=pendulums, method=m)
            except (ValueError, NotImplementedError):
                preds[m] = {}
    lines += ["| quantity | group fit | 95 % interval | exact prediction | legacy prediction "
              "| fit / exact - 1 |", "|---|---|---|---|---|---|"]
    for q in quantities:
        unit = table.quantities[q]
        v = row[quantity_column(q, unit)]
        lo, hi = row[quantity_column(q, unit, " lo95")], row[quantity_column(q, unit, " hi95")]
        ex, lg = preds.get("exact", {}).get(q, math.nan), preds.get("legacy", {}).get(q, math.nan)
        rel = f"{100 * (v / ex - 1):+.2f} %" if math.isfinite(ex) and ex else ""
        lines.append(f"| `{q}` [{unit}] | {_num(v)} | [{_num(lo)}, {_num(hi)}] | {_num(ex)} | "
                     f"{_num(lg)} | {rel} |")
    return lines + [""]


def _verdict(run: CampaignRun, row: dict[str, Any]) -> str:
    """A record's diagnosis verdict with the estimates of what it found
    (``slosh_mode (+p2): p2.mass 0.0661 +/- 0.0021 kg, ...``)."""
    from .tasks import found_quantities

    found = found_quantities(run.diagnoses.get(row["id"], {}))
    parts = [f"`{k}` {_num(v[0])} +/- {_num(v[1])}{' ' + v[4] if v[4] not in ('', '-') else ''}"
             for k, v in found.items()]
    return row["verdict"] + (": " + ", ".join(parts) if parts else "")


def summary(run: CampaignRun, table: CampaignTable, *, figures: list[str]) -> str:
    """The Markdown report of a campaign run."""
    c = run.campaign
    pendulums = pendulum_count(table.quantities)
    quantities = plotted_quantities(table, pendulums)
    records = [r for r in table.rows if r["kind"] == "record"]
    failed = [r for r in table.rows if r["status"] == "failed"]
    lines = [f"# Test campaign: {c.title or c.source}", ""]
    if c.note:
        lines += [c.note, ""]
    lines += [f"{len(records)} records in {len(c.groups)} groups from `{c.source}`; model "
              f"`{c.model}`, carriage input {c.input}. This run: {run.computed} tasks computed, "
              f"{run.reused} taken from the store, {run.failed} failed; {run.seconds:.1f} s.", ""]
    for fig in figures:
        lines += [f"![{fig}]({fig})", ""]
    if "fill.png" in figures:
        lines += ["*Parameters against fill.* Grey dots: each record's estimate with its 95 % "
                  "interval, spread around its fill so that the intervals stay apart; red "
                  "crosses: outliers; black diamonds: each group's multi-record fit without its "
                  "outliers; lines: the tank module's prediction, exact (solid) and the legacy "
                  "SLOSH-code basis (dashed).", ""]
    lines += ["## Groups", ""]
    setups = _setups(run)
    for row in (r for r in table.rows if r["kind"] == "group"):
        lines += _group_section(row, table, setups.get(row["id"]), quantities, pendulums)
    lines += ["## Outliers", ""]
    if run.outliers:
        for o in run.outliers:
            lines.append(f"- **{o.record}** (group {o.group}), left out of the group fit: "
                         + "; ".join(o.reasons) + ".")
    else:
        lines.append("None.")
    lines += ["", f"A record is an outlier when an estimate differs from the combination of the "
              f"other records of its group by more than {run.threshold:.2f} combined standard "
              f"errors (Bonferroni, {100 * FAMILY_ERROR:g} % family-wise over the campaign's "
              f"comparisons); the worst is removed before looking again. Groups need "
              f"{MIN_RECORDS} converged records.", ""]
    misfit = [r for r in records if r["residual/noise"] > MISFIT_RATIO]
    if misfit:
        lines += ["## Records the model does not explain", "",
                  f"RMS residual more than {MISFIT_RATIO:g} times the force noise:", ""]
        lines += [f"- **{r['id']}**: {r['residual/noise']:.2f} x the noise "
                  f"({_num(r['rms_residual [N]'])} N against {_num(r['noise [N]'])} N)"
                  + (f"; diagnosis: {_verdict(run, r)}" if r["verdict"] else "") for r in misfit]
        lines.append("")
    if failed:
        lines += ["## Failed", ""] + [f"- {r['kind']} **{r['id']}**: {r['error']}" for r in failed]
        lines.append("")
    lines += ["## Records", "", "| record | group | amplitude [mm] | "
              + " | ".join(f"`{q}`" for q in quantities) + " | residual / noise | status | "
              "verdict |", "|---" * (len(quantities) + 6) + "|"]
    for r in records:
        cells = [_num(r[quantity_column(q, table.quantities[q])]) for q in quantities]
        amp = r["drive_amplitude [m]"]
        lines.append(f"| {r['id']}{' (outlier)' if r['outlier'] else ''} | {r['group']} | "
                     f"{_num(1e3 * amp) if amp is not None else ''} | " + " | ".join(cells)
                     + f" | {_num(r['residual/noise'])} | {r['status']} | {_verdict(run, r)} |")
    lines += ["", "Full table with standard errors and intervals: `campaign.csv`, "
              "`campaign.parquet`.", ""]
    if c.skipped:
        lines += ["Not case files (no `[test]` table), skipped: "
                  + ", ".join(f"`{s}`" for s in c.skipped) + ".", ""]
    return "\n".join(lines)


def _report_folder(run: CampaignRun, table: CampaignTable, folder: Path) -> None:
    pendulums = pendulum_count(table.quantities)
    quantities = plotted_quantities(table, pendulums)
    figures = []
    if quantities:
        setups = _setups(run)
        series: dict[tuple, list[float]] = {}
        first: dict[tuple, Setup] = {}
        for s in setups.values():
            series.setdefault(s.series, []).append(s.fill_fraction)
            first.setdefault(s.series, s)
        curves = [prediction_curves(first[k], fills, pendulums=pendulums)
                  for k, fills in series.items()]
        reference = {}
        for name, s in setups.items():
            try:
                reference[name] = predicted(s, s.fill_fraction, pendulums=pendulums,
                                            method="exact")
            except (ValueError, NotImplementedError):
                continue
        plot_against_fill(table, curves, quantities, folder / "fill.png",
                          reference=reference, title=run.campaign.title)
        figures.append("fill.png")
        if amplitude_varies(table):
            plot_against_amplitude(table, quantities, folder / "amplitude.png")
            figures.append("amplitude.png")
    (folder / "report.md").write_text(summary(run, table, figures=figures))


def write_outputs(run: CampaignRun, out: str | Path) -> CampaignTable:
    """Write the table and the report of ``run`` into ``out`` (see the module docstring)."""
    out = Path(out)
    table = campaign_table(run)
    csv_bytes, parquet_bytes = table.to_csv(), table.to_parquet()
    tmp = Path(tempfile.mkdtemp(dir=out, prefix=".report."))
    try:
        os.chmod(tmp, output_mode(folder=True))  # readable as any other output, not 0700
        _report_folder(run, table, tmp)
        write_atomic(out / "campaign.csv", csv_bytes)
        write_atomic(out / "campaign.parquet", parquet_bytes)
        final = out / "report"
        old = out / f".report.old.{os.getpid()}"
        if final.exists():
            os.replace(final, old)
        os.replace(tmp, final)
        shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return table


def claim_folder(out: str | Path, source: str, *, overwrite: bool = False) -> bool:
    """Make ``out`` the output folder of the campaign ``source``; True when it already was
    (a rerun resumes there and replaces its table and report).

    Raises
    ------
    FileExistsError
        ``out`` holds the outputs of another campaign (or of none), unless ``overwrite``.
    """
    out, ident = Path(out), os.path.abspath(source)
    manifest = out / MANIFEST
    try:  # read as any input: a pipe or a device in its place is not read
        mine = load_json(manifest, "the campaign manifest", limit=2**20).get("source") == ident
    except (OSError, ValueError, AttributeError):
        mine = False
    existing = [str(out / n) for n in (*OUTPUTS, "store", MANIFEST) if (out / n).exists()]
    if existing and not mine and not overwrite:
        raise FileExistsError(f"{', '.join(existing)} exist(s) and belong to another campaign "
                              "(or to none); pass --overwrite to replace")
    out.mkdir(parents=True, exist_ok=True)
    if not mine:
        write_atomic(manifest, json.dumps({"source": ident, "created_by": "slosh campaign",
                                           "version": package_version()}, indent=1).encode())
    return mine
