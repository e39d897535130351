"""The diagnosis report folder: before/after plots, parameter table and a Markdown summary
a test engineer can read in a minute."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.signals import welch_spectrum
from ..fitting.result import FitResult
from ..outputs import json_text
from .outcome import Diagnosis

__all__ = ["REPORT_FILES", "write_report", "summary"]

#: The files :func:`write_report` writes into its folder.
REPORT_FILES = ("summary.md", "diagnosis.json", "fit_before_after.png", "residual_spectra.png",
                "parameters.md")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _parameter_rows(res: FitResult) -> list[str]:
    rows = ["| parameter | estimate | std. error | 95 % interval | unit |", "|---|---|---|---|---|"]
    for i, (name, v, se, e) in enumerate(zip(res.names, res.values, res.stderr,
                                             res.problem.estimated)):
        lo, hi = res.interval(name)
        se_text = f"{se:.2g}" if res.free[i] else res.uncertainty_text(i)
        rows.append(f"| `{name}` | {v:.5g} | {se_text} | [{lo:.5g}, {hi:.5g}] | {e.unit} |")
    for k, (v, se) in res.derived.items():
        rows.append(f"| `{k}` (derived) | {v:.5g} | {se:.2g} | | |" if se == se
                    else f"| `{k}` (derived) | {v:.5g} | at a bound | | |")
    return rows


def summary(d: Diagnosis) -> str:
    """Markdown summary: verdict, findings with evidence, what the baseline got wrong."""
    ev = d.baseline_evidence
    lines = [f"# Diagnosis of {', '.join(e.case.test.id for e in d.baseline.problem.experiments)}", ""]
    if d.findings:
        lines.append(f"**{len(d.findings)} finding{'s' if len(d.findings) > 1 else ''}.** The baseline "
                     f"({' + '.join(d.baseline.problem.model.names)}) misses:")
        lines.append("")
        for i, f in enumerate(d.findings, 1):
            lines.append(f"{i}. **{f.cause}** (added {', '.join(f.added)}): {f.evidence}.")
    else:
        lines.append("**No finding.** No candidate extension improved the held-out residual "
                     "significantly.")
    if d.verdict is not None:
        lines += ["", f"**Verdict.** {d.verdict.text}"]
    lines += ["", f"Final model: {' + '.join(d.final.problem.model.names)}"
              + (f" with {', '.join(type(m).__name__ for m in d.final.problem.measurement)}"
                 if d.final.problem.measurement else "")
              + f"; RMS residual {d.baseline.rms_residual:.3g} N -> {d.final.rms_residual:.3g} N "
              f"(noise in the fitted band about {ev.noise_rms:.3g} N).", ""]
    lines += ["## What the baseline gets wrong", "",
              f"- RMS residual {ev.rms_residual:.3g} N on the fitted samples; measurement noise in the "
              f"fitted band {ev.noise_rms:.3g} N ({'within' if ev.within_noise else 'above'} the noise).",
              f"- Drive: {_drive_text(ev)}."]
    for p in ev.peaks:
        kind = f"drive harmonic {p.harmonic}" if p.harmonic else "not a drive harmonic"
        lines.append(f"- Residual peak at {p.frequency:.3f} Hz, amplitude {p.amplitude:.3g} N, "
                     f"coherence with the excitation {p.coherence:.2f} ({kind}).")
    for k, a in ev.harmonics.items():
        lines.append(f"- Residual at {k} x drive: {a:.3g} N.")
    lines.append(f"- Whiteness: Ljung-Box Q = {ev.ljung_box_q:.0f} (20 lags), p = {ev.ljung_box_p:.2g} "
                 "(the 10 Hz force filter correlates neighbouring samples).")
    lines.append(f"- Timing skew: correlation of the residual with dF/dt {ev.skew_correlation:+.2f} "
                 f"(implied delay {1e3 * ev.skew_delay:.1f} ms).")
    if ev.frequency_ratio:
        lines.append(f"- Fitted first-mode frequency / predicted: {ev.frequency_ratio:.3f}.")
    if ev.pinned:
        lines.append(f"- Estimates pinned at their bounds: {', '.join(f'`{p}`' for p in ev.pinned)}.")
    if ev.segments:
        segs = ", ".join(f"{s.damping_ratio:.3g} at {s.rms_angle:.2g} rad" for s in ev.segments)
        lines.append(f"- Damping ratio by segment (RMS swing): {segs}; spread x{ev.damping_spread:.2f}.")
    if d.rounds:
        lines += ["", "## Candidates", "", "| round | cause | added | held-out gain | BIC change | verdict |",
                  "|---|---|---|---|---|---|"]
        accepted = {i: f.added for i, f in enumerate(d.findings, 1)}  # round -> what it added
        for i, rnd in enumerate(d.rounds, 1):
            for c in rnd:
                verdict = "accepted" if accepted.get(i) == c.added else (c.rejected or "smaller gain")
                lines.append(f"| {i} | {c.cause} | {', '.join(c.added)} | {100 * c.gain:.1f} % | "
                             f"{c.bic_change:+.0f} | {verdict} |")
    lines += ["", "## Final parameters", ""] + _parameter_rows(d.final)
    lines += ["", f"{d.candidate_fits} fits in {d.seconds:.1f} s. Held-out RMS: 3 of 10 interleaved "
              "blocks left out of every fit. Standard errors assume independent residuals "
              "(optimistic for filtered data).", ""]
    lines += [f"Note: {n}" for n in d.notes]
    return "\n".join(lines) + "\n"


def write_report(d: Diagnosis, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write ``summary.md``, ``diagnosis.json``, ``fit_before_after.png``,
    ``residual_spectra.png`` and ``parameters.md`` into ``folder``."""
    folder = Path(folder)
    existing = [n for n in REPORT_FILES if (folder / n).exists()]
    if existing and not overwrite:
        raise FileExistsError(f"{folder} already holds {', '.join(existing)}; pass overwrite")
    folder.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    t = d.baseline.problem.experiments[0].case.time
    fig, ax = plt.subplots(2, 1, figsize=(10, 7), sharex=True, constrained_layout=True)
    for a, res, title in ((ax[0], d.baseline, "baseline"), (ax[1], d.final, "final")):
        a.plot(t, res.measured[0], lw=0.7, label="measured (filtered)")
        a.plot(t, res.simulated(0), lw=0.7, label=f"simulated ({' + '.join(res.problem.model.names)})")
        a.plot(t, res.residuals[0], lw=0.6, color="C3", label="residual")
        a.set(ylabel="force [N]", title=f"{title}: RMS residual {res.rms_residual:.3g} N")
        a.legend(loc="upper right", fontsize="small")
    ax[1].set(xlabel="time [s]")
    fig.savefig(folder / "fit_before_after.png", dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(9, 4.5), constrained_layout=True)
    for res, label in ((d.baseline, "baseline residual"), (d.final, "final residual")):
        sp = welch_spectrum(t, res.residuals[0])
        ax.semilogy(sp.frequency, np.sqrt(sp.psd), label=label)
    for p in d.baseline_evidence.peaks:
        ax.axvline(p.frequency, color="0.6", ls=":", lw=0.8)
    ax.set(xlabel="frequency [Hz]", ylabel="amplitude density [N/sqrt(Hz)]", xlim=(0, 15))
    ax.legend()
    fig.savefig(folder / "residual_spectra.png", dpi=100)
    plt.close(fig)
    (folder / "parameters.md").write_text("\n".join(["# Baseline", ""] + _parameter_rows(d.baseline)
                                                    + ["", "# Final", ""] + _parameter_rows(d.final)) + "\n")
    (folder / "summary.md").write_text(summary(d))
    (folder / "diagnosis.json").write_text(json_text(d.to_dict()))
    return folder / "summary.md"


def _drive_text(ev) -> str:
    if ev.sweep:
        return "a frequency sweep"
    return f"{ev.drive_frequency:.4g} Hz" if ev.drive_frequency else "crank"
