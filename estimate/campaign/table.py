"""The campaign table: one row per group and per record, written as CSV and Parquet.

Each group's row comes first, then its records; records in no group last. Columns: what
the row is (kind, id, group, fitted records, status, error), the tank, fill and liquid,
the drive amplitude, the model, then for every shared parameter and derived quantity its
estimate, standard error and 95 % interval (units in the column names), then the RMS
residual against the force noise, the diagnosis verdict and the outlier flag with its
reasons, and with ``--diagnose`` the estimate and standard error of every quantity of each
record's diagnosed model (``diagnosed p2.mass [kg]``: what the diagnosis found). Rows and
columns depend only on the stored results, never on timings or on the order tasks ended
in, so an interrupted and resumed run writes the same bytes as an uninterrupted one.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from typing import Any

from analogs.errors import MissingDependency

from .runner import CampaignRun

__all__ = ["CampaignTable", "campaign_table"]

_META = [("kind", str), ("id", str), ("group", str), ("records", str), ("status", str),
         ("error", str), ("rig", str), ("tank_shape", str), ("tank_radius [m]", float),
         ("fill_fraction", float), ("diaphragm", bool), ("liquid_density [kg/m^3]", float),
         ("liquid_viscosity [m^2/s]", float), ("drive_amplitude [m]", float),
         ("samples", int), ("model", str), ("iterations", int)]
_TAIL = [("rms_residual [N]", float), ("noise [N]", float), ("residual/noise", float),
         ("verdict", str), ("outlier", bool), ("outlier_reasons", str), ("excluded", str)]
_STATS = (("", 0), (" stderr", 1), (" lo95", 2), (" hi95", 3))
#: Prefix of the columns of a record's diagnosed (final) model, with ``--diagnose``: its
#: estimates and standard errors, the found components' among them (``diagnosed p2.mass
#: [kg]``).
DIAGNOSED = "diagnosed"


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit and unit != "-" else ""


def quantity_column(name: str, unit: str, stat: str = "") -> str:
    """Column of a parameter or derived quantity: ``"p1.mass stderr [kg]"``."""
    return f"{name}{stat}{_unit(unit)}"


@dataclass(frozen=True)
class CampaignTable:
    """``columns`` (name, type) and ``rows`` (dicts by column name; missing values are
    None)."""

    columns: tuple[tuple[str, type], ...]
    rows: tuple[dict[str, Any], ...]
    #: Quantity name -> unit, in column order.
    quantities: dict[str, str]

    def to_csv(self) -> bytes:
        """CSV bytes: floats in their shortest exact form, missing values empty."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([c for c, _ in self.columns])
        for row in self.rows:
            w.writerow([_csv_cell(row.get(c)) for c, _ in self.columns])
        return buf.getvalue().encode()

    def to_parquet(self) -> bytes:
        """Parquet bytes (pyarrow), missing values null."""
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError as err:
            raise MissingDependency("the campaign table's Parquet file needs pyarrow: "
                                    "`python3 -m pip install '.[campaign]'` (from a checkout) or "
                                    "`python3 -m pip install 'slosh-analogs[campaign]'`") from err
        types = {str: pa.string(), float: pa.float64(), int: pa.int64(), bool: pa.bool_()}
        arrays = [pa.array([_parquet_cell(r.get(c)) for r in self.rows], type=types[t])
                  for c, t in self.columns]
        table = pa.Table.from_arrays(arrays, names=[c for c, _ in self.columns])
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        return sink.getvalue().to_pybytes()


def _csv_cell(v: Any) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def _parquet_cell(v: Any) -> Any:
    return None if isinstance(v, float) and math.isnan(v) else v


def _setup_cells(setup) -> dict[str, Any]:
    if setup is None:
        return {}
    return {"rig": setup.rig, "tank_shape": setup.shape, "tank_radius [m]": setup.radius,
            "fill_fraction": setup.fill_fraction, "diaphragm": setup.diaphragm,
            "liquid_density [kg/m^3]": setup.density,
            "liquid_viscosity [m^2/s]": setup.viscosity}


def _error_cell(outcome: dict[str, Any]) -> str:
    """The error of a failed outcome with whether it is retried (:data:`FAILURE_CAUSES`)."""
    from .tasks import FAILURE_CAUSES

    error = outcome.get("error") or ""
    cause = FAILURE_CAUSES.get(outcome.get("failure")) if outcome.get("status") == "failed" \
        else None
    return f"{error} [{cause}]" if error and cause else error


def _fit_cells(outcome: dict[str, Any], units: dict[str, str]) -> dict[str, Any]:
    out: dict[str, Any] = {"status": outcome.get("status"), "error": _error_cell(outcome),
                           "model": outcome.get("model") or "",
                           "iterations": outcome.get("iterations"),
                           "samples": outcome.get("samples")}
    for table in ("parameters", "derived"):
        for name, values in outcome.get(table, {}).items():
            units.setdefault(name, values[4])
            for stat, i in _STATS:
                out[quantity_column(name, values[4], stat)] = values[i]
    if "rms_residual" in outcome:
        rms, noise = outcome["rms_residual"], outcome["noise"]
        out |= {"rms_residual [N]": rms, "noise [N]": noise,
                "residual/noise": rms / noise if noise and math.isfinite(noise) else math.nan}
    return out


def _group_verdict(run: CampaignRun, members: tuple[str, ...]) -> str:
    verdicts = {i: run.diagnoses[i].get("verdict") or f"failed: {run.diagnoses[i].get('error')}"
                for i in members if i in run.diagnoses}
    found = {i: v for i, v in verdicts.items() if v != "no finding"}
    if not verdicts:
        return ""
    return "; ".join(f"{i}: {v}" for i, v in found.items()) or "no finding"


def campaign_table(run: CampaignRun) -> CampaignTable:
    """The table of the campaign ``run`` (see the module docstring for its layout)."""
    c = run.campaign
    flagged = {o.record: o for o in run.outliers}
    units: dict[str, str] = {}
    final_units: dict[str, str] = {}  # the diagnoses' final models (--diagnose)
    rows = []

    def record_row(rid: str, group: str) -> dict[str, Any]:
        rec, outcome = c.record(rid), run.records[rid]
        row = {"kind": "record", "id": rid, "group": group, "records": rec.relpath,
               **_setup_cells(rec.setup), **_fit_cells(outcome, units),
               "model": c.model_of(rid), "outlier": rid in flagged,
               "outlier_reasons": "; ".join(flagged[rid].reasons) if rid in flagged else ""}
        row["drive_amplitude [m]"] = outcome.get("records", {}).get(rid, {}).get("amplitude_m")
        if rid in run.diagnoses:
            d = run.diagnoses[rid]
            row["verdict"] = d.get("verdict") or f"failed: {d.get('error')}"
            for table in ("final_parameters", "final_derived"):
                for name, values in (d.get(table) or {}).items():
                    final_units.setdefault(name, values[4])
                    for stat, i in _STATS[:2]:
                        row[quantity_column(f"{DIAGNOSED} {name}", values[4], stat)] = values[i]
        return row

    for g in c.groups:
        outcome = run.groups[g.name]
        first = next((c.record(i).setup for i in g.records if c.record(i).setup), None)
        rows.append({"kind": "group", "id": g.name, "group": g.name,
                     "records": ";".join(outcome["members"]), **_setup_cells(first),
                     **_fit_cells(outcome, units), "model": g.model,
                     "verdict": _group_verdict(run, g.records),
                     "excluded": "; ".join(f"{i} ({why})"
                                           for i, why in outcome["excluded"].items())})
        rows += [record_row(i, g.name) for i in g.records]
    grouped = {i for g in c.groups for i in g.records}
    rows += [record_row(r.id, "") for r in c.records if r.id not in grouped]
    quantity_cols = [(quantity_column(n, u, stat), float) for n, u in units.items()
                     for stat, _ in _STATS]
    final_cols = [(quantity_column(f"{DIAGNOSED} {n}", u, stat), float)
                  for n, u in final_units.items() for stat, _ in _STATS[:2]]
    columns = tuple(_META + quantity_cols + _TAIL + final_cols)
    clean = tuple({k: _typed(row.get(k), t) for k, t in columns} for row in rows)
    return CampaignTable(columns, clean, dict(units))


def _typed(v: Any, t: type) -> Any:
    if v is None:
        return {str: "", float: math.nan}.get(t)
    return t(v)
