"""The fit report people read: as text (``slosh fit --report``, :meth:`FitResult.report`) and
as a Markdown file (``slosh fit --report FILE.md``) with the record's provenance."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .writer import information_criteria

if TYPE_CHECKING:  # pragma: no cover
    from ..result import FitResult

__all__ = ["report_markdown", "report_text"]

#: Correlations listed in the report: |C| above this.
REPORTED_CORRELATION = 0.1


def _is_single(result: "FitResult") -> bool:
    return not result.channels or all(len(c) == 1 for c in result.channels)


def _statistics(result: "FitResult") -> list[tuple[str, str]]:
    single = _is_single(result)
    ic = information_criteria(result)
    return [
        ("model", " + ".join(result.problem.model.names)),
        ("cases", ", ".join(e.case.test.id for e in result.problem.experiments)),
        ("transcription", result.transcription),
        ("solver status", result.verdict),
        ("iterations", str(result.iterations)),
        ("wall time", f"{result.seconds:.3f} s"),
        ("data points", str(result.n_samples)),
        ("variables", str(len(result.names))),
        ("cost (sum r^2)", f"{result.cost:.6g} {'N^2' if single else '(scaled)'}"),
        ("RMS residual", f"{result.rms_residual:.6g} {'N' if single else '(scaled)'}"),
        ("R^2", f"{result.r_squared:.6f}"),
        ("AIC", f"{ic['aic']:.6g}"),
        ("BIC", f"{ic['bic']:.6g}"),
    ]


def _noise(result: "FitResult") -> list[tuple[str, str]]:
    """The noise figure of every fitted channel and the residual over it."""
    out = []
    many = len(result.noise_figures) > 1
    for i, figs in enumerate(result.noise_figures):
        cid = f"{result.problem.experiments[i].case.test.id}: " if many else ""
        for c, fig in figs.items():
            unit = "N m" if c.startswith("torque") else "N"
            label = c if len(figs) > 1 else "force"
            out.append(("noise figure", f"{cid}{label} {fig.describe(unit)}"))
        ratio = result.residual_over_noise(i)
        if math.isfinite(ratio):
            out.append(("residual / noise", f"{cid}{ratio:.3f} (RMS residual on the fitted "
                        "samples over the noise figure)"))
    return out


def _variables(result: "FitResult") -> list[dict[str, str]]:
    """One row per estimate: value, standard error, relative error, unit, interval, the
    Gauss-Newton standard error beside the robust one, the start."""
    rows = []
    robust = result.covariance_kind == "robust"
    for i, (name, v, se, e) in enumerate(zip(result.names, result.values, result.stderr,
                                             result.problem.estimated)):
        row = {"name": name, "value": f"{v:.6g}", "unit": e.unit, "init": f"{e.initial:.4g}",
               "stderr": "", "relative": "", "interval": "", "gn": ""}
        if not result.free[i]:
            row["interval"] = result.uncertainty_text(i)
        else:
            lo, hi = result.interval(name)
            row |= {"stderr": f"+/- {se:.3g}", "relative": f"({abs(se / v) * 100:.2f}%)" if v else "",
                    "interval": f"[{lo:.6g}, {hi:.6g}]",
                    "gn": f"{result.gauss_newton_stderr[i]:.3g}" if robust else ""}
        rows.append(row)
    return rows


def _aligned(rows: Sequence[Sequence[str]], indent: str = "    ", *,
             measured: Sequence[bool] | None = None) -> list[str]:
    """Rows of cells as lines whose columns line up: a cell is as wide as its column's widest
    among the ``measured`` rows (default all); a row that is not measured keeps the widths
    as far as its cells fit and then runs on."""
    keep = [r for r, m in zip(rows, measured or [True] * len(rows)) if m] or list(rows)
    keep = [r for r in keep if len(r) == len(rows[0])] or list(rows)
    widths = [max(len(r[j]) for r in keep) for j in range(len(rows[0]))] if rows else []
    if rows:  # the names line up in every row
        widths[0] = max(len(r[0]) for r in rows)
    out = []
    for r in rows:
        cells, over = [], False
        for c, w in zip(r, widths):
            over = over or len(c) > w
            cells.append(c if over else c.ljust(w))
        out.append((indent + "  ".join(cells)).rstrip())
    return out


def _correlations(result: "FitResult") -> list[tuple[str, str, float]]:
    corr = result.correlation
    n = len(result.names)
    pairs = [(abs(corr[i, j]), result.names[i], result.names[j], corr[i, j])
             for i in range(n) for j in range(i + 1, n)]
    # NaN (an estimate at a bound) fails the comparison
    return [(a, b, c) for _, a, b, c in sorted((p for p in pairs if p[0] > REPORTED_CORRELATION),
                                               reverse=True)]


def _identifiability(result: "FitResult") -> list[str]:
    conf = result.confounded()
    bound = [n for n, f in zip(result.names, result.free) if not f]
    inside = " inside its bounds" if bound else ""
    lines = conf or [f"every estimated parameter{inside} is determined by the data"]
    if bound:
        lines.append(f"left out (at a bound): {', '.join(f'`{n}`' for n in bound)}")
    return lines


def _channels(result: "FitResult") -> list[str]:
    lines = []
    for i, names in enumerate(result.channels):
        r = result.scaled_residuals(i)
        keep = result.weights[i] > 0 if result.weights else slice(None)
        for j, c in enumerate(names):
            rms = float(np.sqrt(np.mean(r[keep, j] ** 2)))
            lines.append(f"{c:12s} scale {result.channel_scales[i][c]:.4g}  RMS residual {rms:.4g}")
    return lines


def _derived(result: "FitResult") -> list[tuple[str, str, str, str]]:
    """``(name, value, +/- stderr or why none, unit)``."""
    out = []
    for k, (v, se) in result.derived.items():
        unit = result.derived_units.get(k, "")
        text = f"+/- {se:.3g}" if math.isfinite(se) else \
            "(no standard error: it depends on an estimate at a bound)"
        why = result.derived_reach_text(k)
        if why:
            lo, hi = result.derived_interval(k)
            text += f"; 95 % [{lo:.6g}, {hi:.6g}] {why}"
        out.append((k, f"{v:.6g}", text, unit))
    return out


def report_text(result: "FitResult") -> str:
    """The text report of the fit ``result``: statistics (with AIC and BIC), estimates with
    intervals in aligned columns, derived quantities, correlations, identifiability, notes,
    warnings."""
    robust = result.covariance_kind == "robust"
    lines = ["[[Fit statistics]]"]
    stats = _statistics(result) + _noise(result)
    lines += [f"    {k:18s} = {v}" for k, v in stats]
    lines.append(f"[[Variables]] (95 % intervals from the "
                 f"{'robust' if robust else 'Gauss-Newton'} covariance"
                 f"{'; GN: the Gauss-Newton standard error' if robust else ''})")
    cells, free = [], []
    for r in _variables(result):
        gn = f"GN +/- {r['gn']}" if r["gn"] else ""
        if r["stderr"]:
            cells.append([r["name"], "=", r["value"], r["stderr"], r["relative"], r["unit"],
                          f"95%: {r['interval']}", gn, f"(init {r['init']})"])
        else:  # at a bound: what stands for the interval, then the start
            cells.append([r["name"], "=", r["value"], "", "", r["unit"],
                          f"{r['interval']}  (init {r['init']})"])
        free.append(bool(r["stderr"]))
    lines += _aligned(cells, measured=free)
    for name, (v, se, text) in result.tied().items():
        lines.append(f"    {name:28s} = {v:.6g} +/- {se:.3g} (follows: {text})")
    if result.derived:
        lines.append("[[Derived]]")
        lines += _aligned([[k, "=", v, se, unit] if se.startswith("+/-") else [k, "=", v, "", unit, se]
                           for k, v, se, unit in _derived(result)])
    pairs = _correlations(result)
    if pairs:
        lines.append(f"[[Correlations]] (|C| > {REPORTED_CORRELATION:g})")
        lines += [f"    C({a}, {b}) = {c:+.4f}" for a, b, c in pairs]
    lines.append("[[Identifiability]]")
    lines.append("    condition number of the scaled sensitivity = "
                 f"{result.identifiability.condition_number:.3g}")
    lines += [f"    {line}" for line in _identifiability(result)]
    if not _is_single(result):
        lines.append("[[Channels]] (residual scale, RMS residual / scale)")
        lines += [f"    {line}" for line in _channels(result)]
    lines.append("[[Notes]]")
    lines.append("    " + result.covariance_note())
    lines.append("    AIC and BIC are -2 log(likelihood) + 2 k and + k log(n) up to a constant: "
                 "compare them only between fits of the same records")
    lines += [f"    {n}" for n in result.problem.notes]
    if result.warnings:
        lines.append("[[Warnings]]")
        lines += [f"    {w}" for w in result.warnings]
    return "\n".join(lines)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|",
            *("| " + " | ".join(_cell(c) for c in r) + " |" for r in rows)]


def report_markdown(result: "FitResult", record: Mapping[str, Any]) -> str:
    """The report of the fit ``result`` as Markdown, with the provenance of ``record`` (the
    fit's JSON record,
    :func:`~estimate.fitting.record.fit_record`): what was fitted, from which files (with
    their SHA-256) and with which versions, then the text report's sections as tables.

    Examples
    --------
    >>> from estimate.fitting.record import fit_record, report_markdown
    >>> text = report_markdown(result, fit_record(result))      # doctest: +SKIP
    """
    prov = record.get("provenance") or {}
    robust = result.covariance_kind == "robust"
    title = ", ".join(e.case.test.id for e in result.problem.experiments)
    lines = [f"# Fit of {title}: {record.get('model_spec', '')}", "",
             f"**{result.verdict}**; {result.iterations} iterations, {result.seconds:.2f} s.", ""]
    lines += ["## Statistics", "", *_table(("quantity", "value"),
                                            _statistics(result) + _noise(result)), ""]
    rows = [[r["name"], r["value"], r["stderr"].removeprefix("+/- "), r["relative"].strip("()"),
             r["unit"], r["interval"], r["gn"], r["init"]] for r in _variables(result)]
    rows += [[name, f"{v:.6g}", f"{se:.3g}", "", "", f"follows: {text}", "", ""]
             for name, (v, se, text) in result.tied().items()]
    lines += ["## Estimates", "",
              f"95 % intervals from the {'robust' if robust else 'Gauss-Newton'} covariance.", "",
              *_table(("parameter", "value", "std. error", "relative", "unit", "95 % interval",
                       "GN std. error", "start"), rows), ""]
    if result.derived:
        lines += ["## Derived quantities", "",
                  *_table(("quantity", "value", "std. error", "unit"),
                          [(k, v, se.removeprefix("+/- "), u) for k, v, se, u in _derived(result)]),
                  ""]
    pairs = _correlations(result)
    if pairs:
        lines += [f"## Correlations (|C| > {REPORTED_CORRELATION:g})", "",
                  *_table(("parameters", "C"), [(f"{a}, {b}", f"{c:+.4f}") for a, b, c in pairs]),
                  ""]
    lines += ["## Identifiability", "", "Condition number of the scaled sensitivity: "
              f"{result.identifiability.condition_number:.3g}.", "",
              *(f"- {line}" for line in _identifiability(result)), ""]
    if not _is_single(result):
        lines += ["## Channels", "", *(f"- {line}" for line in _channels(result)), ""]
    lines += ["## Notes", "", f"- {result.covariance_note()}",
              "- AIC and BIC are -2 log(likelihood) + 2 k and + k log(n) up to a constant: "
              "compare them only between fits of the same records.",
              *(f"- {n}" for n in result.problem.notes), ""]
    warnings = record.get("warnings") or list(result.warnings)
    if warnings:
        lines += ["## Warnings", "", *(f"- {w}" for w in warnings), ""]
    lines += _provenance_lines(prov)
    return "\n".join(lines).rstrip() + "\n"


def _provenance_lines(prov: Mapping[str, Any]) -> list[str]:
    if not prov:
        return []
    versions = prov.get("versions") or {}
    lines = ["## Provenance", "",
             f"Written {prov.get('created_utc', '?')} by "
             f"{prov.get('command') or 'the Python API'}; model as given: "
             f"`{prov.get('model_spec_given') or '(default)'}`.", "",
             *_table(("file", "SHA-256"), [(f"`{f.get(k)}`", f"`{f.get(k.replace('file', 'sha256'))}`")
                                          for f in prov.get("files") or ()
                                          for k in ("case_file", "data_file")]), "",
             "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items() if v) + ".", ""]
    options = prov.get("options") or {}
    if options:
        lines += ["Options: " + ", ".join(f"`{k}` = `{json.dumps(v)}`" for k, v in options.items())
                  + ".", ""]
    return lines
