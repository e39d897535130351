"""The diagnosis report folder: before/after plots, parameter table and a Markdown summary
a test engineer can read in a minute."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _plotting as style
from ..data.signals import welch_spectrum
from ..fitting.plots import drive_frequency_of, mode_frequencies, noise_density, spectrum_top
from ..fitting.result import FitResult
from ..outputs import json_text
from .outcome import CandidateOutcome, Diagnosis
from .scoring import HELD_OUT_BLOCKS, HOLDOUT_BLOCKS

__all__ = ["REPORT_FILES", "write_report", "summary", "before_after_figure", "residual_spectra_figure"]

#: The files :func:`write_report` writes into its folder.
REPORT_FILES = ("summary.md", "diagnosis.json", "fit_before_after.png", "residual_spectra.png",
                "parameters.md")


def _filtered(res: FitResult) -> float | None:
    """The force filter's cutoff (Hz) when the fit low-passed the measured force, else ``None``."""
    return res.problem.force_cutoff_hz if res.problem.input == "filtered" else None


def _measured_label(res: FitResult, shown: "_Shown | None" = None) -> str:
    """What the plotted measured channel is: as recorded, low-passed, or with the tones
    above the mechanics removed (the estimated input's force)."""
    shown = shown or _Shown.of(res, {})
    cut = _filtered(res)
    if cut:
        return f"measured (low-passed at {cut:g} Hz)"
    raw = res.problem.experiments[0].case.channels[shown.name]
    meas = shown.column(res.measured[0])
    same = np.shape(meas) == np.shape(raw) and np.array_equal(meas, raw)
    return "measured" if same else "measured (tones above the mechanics removed)"


@dataclass(frozen=True)
class _Shown:
    """The channel the report's figures show: the lateral force, or on a record of several
    channels the one holding the largest share of the baseline's scaled residual; its
    column in the fit's residual arrays (None: one channel) and unit."""

    name: str
    index: int | None
    unit: str

    @classmethod
    def of(cls, res: FitResult, share: dict[str, float]) -> "_Shown":
        chans = res.channels[0] if res.channels else ("force_x",)
        if len(chans) == 1:
            return cls(chans[0], None, "N")
        name = max(chans, key=lambda c: share.get(c, 0.0))
        return cls(name, chans.index(name), "N m" if name.startswith("torque") else "N")

    def column(self, values) -> np.ndarray:
        a = np.asarray(values, float)
        return a if self.index is None else a.reshape(a.shape[0], -1)[:, self.index]


def _parameter_rows(res: FitResult) -> list[str]:
    rows = ["| parameter | estimate | std. error | 95 % interval | unit |", "|---|---|---|---|---|"]
    for i, (name, v, se, e) in enumerate(zip(res.names, res.values, res.stderr,
                                             res.problem.estimated)):
        lo, hi = res.interval(name)
        se_text = f"{se:.2g}" if res.free[i] else res.uncertainty_text(i)
        rows.append(f"| `{name}` | {v:.5g} | {se_text} | [{lo:.5g}, {hi:.5g}] | {e.unit} |")
    for k, (v, se) in res.derived.items():
        lo, hi = res.derived_interval(k)
        band = f"[{lo:.5g}, {hi:.5g}]" if lo == lo and hi == hi else ""
        rows.append(f"| `{k}` (derived) | {v:.5g} | {f'{se:.2g}' if se == se else 'at a bound'} "
                    f"| {band} | {res.derived_units.get(k, '')} |")
    return rows


def _candidate_row(i: int, c: CandidateOutcome, accepted: bool) -> str:
    """A row of the candidates table. A candidate that was not fitted (screened out, not
    tried) has no held-out gain and no BIC change: "-" in both, its verdict says why."""
    verdict = "accepted" if accepted else (c.rejected or "smaller gain")
    gain = (f"{_unsigned_zero(100 * c.gain, 1):.1f} %"
            if c.gain is not None and math.isfinite(c.gain) else "-")
    dbic = (f"{_unsigned_zero(c.bic_change, 0):+.0f}"
            if c.bic_change is not None and math.isfinite(c.bic_change) else "-")
    return f"| {i} | {c.cause} | {', '.join(c.added)} | {gain} | {dbic} | {verdict} |"


def _unsigned_zero(x: float, digits: int) -> float:
    """``x`` rounded to ``digits`` decimals, a negative zero made positive (a null delay
    prints as "0.0 ms", not "-0.0 ms")."""
    return round(x, digits) + 0.0


def _held_out_text() -> str:
    """How the diagnosis holds data out: ``"3 of 10 interleaved blocks"``
    (:data:`~estimate.diagnosis.scoring.HELD_OUT_BLOCKS`)."""
    return f"{len(HELD_OUT_BLOCKS)} of {HOLDOUT_BLOCKS} interleaved blocks"


def _fitted_on(res: FitResult) -> str:
    """What a fit of the diagnosis was fitted on, for a heading."""
    if not res.weights or not any(res.problem.held_out(i, w).any()
                                  for i, w in enumerate(res.weights)):
        return "every sample"
    kept = HOLDOUT_BLOCKS - len(HELD_OUT_BLOCKS)
    return (f"{kept} of {HOLDOUT_BLOCKS} interleaved blocks; the other {len(HELD_OUT_BLOCKS)} "
            "held out to score the candidates")


def summary(d: Diagnosis) -> str:
    """Markdown summary: verdict, findings with evidence, the baseline's residual, the
    candidates, the final parameters and the fits (with the budgets that ended any)."""
    ev = d.baseline_evidence
    cut = _filtered(d.baseline)
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
              + f"; RMS residual {d.baseline.rms_residual:.3g} {d.final_evidence.noise.unit} -> "
              f"{d.final.rms_residual:.3g} {d.final_evidence.noise.unit}; "
              f"final {d.final_evidence.noise.text()}.", ""]
    lines += ["## The baseline's residual", "",
              f"- RMS {ev.rms_residual:.3g} {ev.noise.unit} on the fitted samples; "
              f"{ev.noise.text()}.",
              f"- Drive: {_drive_text(ev)}."]
    for p in ev.peaks:
        kind = f"drive harmonic {p.harmonic}" if p.harmonic else "not a drive harmonic"
        lines.append(f"- Residual peak at {p.frequency:.3f} Hz, amplitude {p.amplitude:.3g} N, "
                     f"coherence with the excitation {p.coherence:.2f} ({kind}).")
    for k, a in ev.harmonics.items():
        lines.append(f"- Residual at {k} x drive: {a:.3g} N.")
    white = "white" if ev.ljung_box_p >= 0.05 else "correlated from sample to sample"
    lines.append(f"- Whiteness: Ljung-Box Q = {ev.ljung_box_q:.0f} (20 lags), p = {ev.ljung_box_p:.2g} "
                 f"({white}" + (f"; the {cut:g} Hz force filter itself correlates neighbouring "
                                "samples" if cut else "") + ").")
    lines.append(f"- Timing skew: correlation of the residual with dF/dt "
                 f"{_unsigned_zero(ev.skew_correlation, 2):+.2f} "
                 f"(implied delay {_unsigned_zero(1e3 * ev.skew_delay, 1):.1f} ms).")
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
            lines += [_candidate_row(i, c, c.fitted and accepted.get(i) == c.added) for c in rnd]
    lines += ["", "## Final parameters", ""] + _parameter_rows(d.final)
    lines += ["", f"{d.candidate_fits} fits in {d.seconds:.1f} s. Held-out RMS: {_held_out_text()} "
              f"left out of every fit but the final one. {d.final.interval_note()}", ""]
    ended = d.budget_ended
    if ended:
        lines += ["Fits ended by their budget (iterations or CPU time, scaled with the record):", ""]
        lines += [f"- {f.text()}" for f in ended] + [""]
    lines += [f"Note: {n}" for n in d.notes]
    return "\n".join(lines) + "\n"


def write_report(d: Diagnosis, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write the report of the diagnosis ``d``: ``summary.md``, ``diagnosis.json``,
    ``fit_before_after.png``, ``residual_spectra.png`` and ``parameters.md`` into ``folder``;
    files already there are replaced only with ``overwrite`` (else FileExistsError)."""
    folder = Path(folder)
    existing = [n for n in REPORT_FILES if (folder / n).exists()]
    if existing and not overwrite:
        raise FileExistsError(f"{folder} already holds {', '.join(existing)}; pass overwrite")
    folder.mkdir(parents=True, exist_ok=True)
    style.save(before_after_figure(d, folder / "fit_before_after.png"), folder / "fit_before_after.png",
               dpi=100)
    style.save(residual_spectra_figure(d, folder / "residual_spectra.png"),
               folder / "residual_spectra.png", dpi=100)
    (folder / "parameters.md").write_text("\n".join(
        [f"# Baseline (fitted on {_fitted_on(d.baseline)})", ""] + _parameter_rows(d.baseline)
        + ["", f"# Final (fitted on {_fitted_on(d.final)})", ""] + _parameter_rows(d.final)) + "\n")
    (folder / "summary.md").write_text(summary(d))
    (folder / "diagnosis.json").write_text(json_text(d.to_dict()))
    return folder / "summary.md"


def _drive_text(ev) -> str:
    if ev.sweep:
        return "a frequency sweep"
    return f"{ev.drive_frequency:.4g} Hz" if ev.drive_frequency else "crank"


def _model_text(res: FitResult) -> str:
    delay = _delay(res)
    late = f", force read {1e3 * delay:.3g} ms late" if delay else ""
    return " + ".join(res.problem.model.names) + late


def _delay(res: FitResult) -> float:
    """The sensor delay (s) of ``res``'s measurement models (0 without one)."""
    from ..fitting.measurement import SensorDelay

    return sum(m.delay for m in res.problem.measurement if isinstance(m, SensorDelay))


def _as_recorded(res: FitResult, t: np.ndarray, simulated: np.ndarray) -> np.ndarray:
    """``res``'s simulated force on the record's time axis: a sensor delay's fit compares
    the model with the recorded force advanced by the delay
    (:class:`~estimate.fitting.measurement.SensorDelay`), so its simulation is drawn that
    much later, as the transducer records it (NaN before the delay); else unchanged. Drawn
    at the samples' own times it ran a delay ahead of the measured curve (23.7 ms on a 2 Hz
    swing) while its residual was at the noise."""
    delay = _delay(res)
    if not delay:
        return simulated
    return np.interp(t, t + delay, simulated, left=np.nan)


def before_after_figure(d: Diagnosis, path: str | Path | None = None):
    """The diagnosis ``d``'s measured force with the baseline's and the final model's simulation (zooms on the
    start-up and the steady end), and the two residuals on their own, shared axis in N
    scaled by the baseline residual after the start-up (the start-up shaded), with the
    measurement noise as a band. ``path`` only decides how the figure is made (saved:
    without pyplot); returns the figure."""
    t = np.asarray(d.baseline.problem.experiments[0].case.time, float)
    shown = _Shown.of(d.baseline, d.baseline_evidence.channel_share)
    unit = shown.unit
    meas = shown.column(d.baseline.measured[0])
    base, final = (_as_recorded(r, t, shown.column(r.simulated(0)))
                   for r in (d.baseline, d.final))
    # the baseline's simulation in its held-out blocks follows a carriage motion read off
    # the displacement alone: shaded and left blank, as in its residual panel
    held_base = d.baseline.problem.held_out(0, d.baseline.weights[0] if d.baseline.weights
                                            else None)
    base = np.where(held_base, np.nan, base)
    fig = style.figure(path, figsize=(10, 8.5))
    ax = fig.subplots(3, 1, sharex=True, height_ratios=[2.2, 1, 1])
    for lo, hi in _runs(t, held_base):
        ax[0].axvspan(lo, hi, color="#fee08b", alpha=0.5, lw=0, zorder=0)
    ax[0].plot(t, meas, **style.MEASURED, label=_measured_label(d.baseline, shown))
    base_style = {**style.SIMULATED, "color": "#e08214", "ls": (0, (2, 1.5))}
    final_style = {**style.SIMULATED, "ls": "-"}
    ax[0].plot(t, base, **base_style, label=f"baseline ({_model_text(d.baseline)})")
    ax[0].plot(t, final, **final_style, label=f"final ({_model_text(d.final)})")
    top = float(np.max(np.abs(meas))) or 1.0
    ax[0].set(ylabel=f"{shown.name} [{unit}]", ylim=(-1.1 * top, style.ZOOM_TOP * top),
              xlim=(t[0], t[-1]))
    ax[0].set_yticks([tk for tk in ax[0].get_yticks() if abs(tk) <= 1.1 * top])
    end = style.startup_end(t)
    span = max(1.0, 0.06 * (t[-1] - t[0]), end - t[0])
    for (lo, hi), bounds, name in zip(((t[0], t[0] + span), (t[-1] - span, t[-1])),
                                      style.ZOOM_BOXES, ("start-up", "steady")):
        inset = ax[0].inset_axes(bounds)
        keep = (t >= lo) & (t <= hi)
        inset.plot(t[keep], meas[keep], **style.MEASURED)
        inset.plot(t[keep], base[keep], **base_style)
        inset.plot(t[keep], final[keep], **final_style)
        inset.set_xlim(lo, hi)
        style.label_inset(inset, f"{name}: {lo:.1f}-{hi:.1f} s")
        ax[0].indicate_inset_zoom(inset, edgecolor="0.4")
    ax[0].legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncols=3, fontsize="small", frameon=False)
    steady = t > end

    def fitted(res: FitResult) -> np.ndarray:  # after the start-up, not held out
        return steady & (res.weights[0] > 0) if res.weights else steady

    limit = max(style.robust_limit(shown.column(d.baseline.residuals[0]), fitted(d.baseline)),
                style.robust_limit(shown.column(d.final.residuals[0]), fitted(d.final)))
    figure = d.baseline.noise_figure(0, shown.name) if shown.index is not None else None
    noise = figure.std if figure is not None else d.baseline_evidence.noise_rms
    for a, res, name in ((ax[1], d.baseline, "baseline"), (ax[2], d.final, "final")):
        # the held-out blocks are no residual of the fitted model: the carriage motion there
        # rests on the displacement alone, so they are shaded and left blank
        held = res.problem.held_out(0, res.weights[0] if res.weights else None)
        resid = shown.column(res.residuals[0])
        left = res.problem.left_out[0] if res.problem.left_out else None
        # clipped samples and spikes are no residual either: left blank, unshaded
        r = np.where(held if left is None else held | left, np.nan, resid)
        a.axhspan(-noise, noise, color="#4393c3", alpha=0.2, lw=0,
                  label=f"noise RMS +/-{noise:.3g} {unit}")
        a.plot(t, r, **style.RESIDUAL, label=f"{name} residual")
        for i, (lo, hi) in enumerate(_runs(t, held)):
            a.axvspan(lo, hi, color="#fee08b", alpha=0.5, lw=0, zorder=0,
                      label="held out of this fit (not shown)" if i == 0 else None)
            if hi - lo > 0.03 * (t[-1] - t[0]):  # a sensor delay's unmatched tail: shaded
                a.text(0.5 * (lo + hi), 0.0, "held out", ha="center", va="center",
                       fontsize="small", color="0.35")
        style.mark_startup(a, t, np.abs(np.nan_to_num(r)), end, limit, unit)
        rms = float(np.sqrt(np.mean(resid[fitted(res)] ** 2)))
        a.set(ylabel=f"residual [{unit}]", ylim=(-limit, limit))
        a.set_title(f"{name} ({_model_text(res)}): RMS residual {rms:.3g} {unit} on the fitted "
                    "samples after the start-up", fontsize="medium", loc="left")
        a.legend(loc="lower right", fontsize="small", ncols=4)
    ax[2].set_xlabel("time [s]")
    across = "" if shown.index is None else f" ({shown.name}: the channel with most residual)"
    fig.suptitle(f"Diagnosis of {d.baseline.problem.experiments[0].case.test.id}: before and "
                 f"after{across}")
    return fig


def residual_spectra_figure(d: Diagnosis, path: str | Path | None = None):
    """Amplitude spectra (N/sqrt(Hz)) of the diagnosis ``d``'s measured force and of the baseline and final
    residuals (the baseline thick and light under the thin final), the raw data's noise
    floor, the drive frequency, the fitted mode frequencies of the final model and the
    residual peaks the diagnosis found. ``path`` only decides how the figure is made
    (saved: without pyplot); returns the figure."""
    t = np.asarray(d.baseline.problem.experiments[0].case.time, float)
    shown = _Shown.of(d.baseline, d.baseline_evidence.channel_share)
    fs = 1.0 / float(np.median(np.diff(t)))
    drive = drive_frequency_of(d.baseline) if shown.index is None else None
    modes = mode_frequencies(d.final)
    top_f = spectrum_top(fs, d.baseline.problem.force_cutoff_hz, [drive or 0.0, *modes.values()])
    fig = style.figure(path, figsize=(10, 5))
    ax = fig.subplots()
    curves = []
    # the baseline's residual on its fitted samples only (held-out blocks zeroed, the
    # density scaled back by the fitted share): the held-out blocks are no residual of it
    w = d.baseline.weights[0] > 0 if d.baseline.weights else np.ones(t.size, bool)
    # the final fit's left-out samples (clipped, spikes) likewise; it holds nothing out
    w_final = d.final.weights[0] > 0 if d.final.weights else np.ones(t.size, bool)
    for y, share, label, kw in (
            (shown.column(d.baseline.measured[0]), 1.0, _measured_label(d.baseline, shown),
             {"color": "0.75", "lw": 1.0}),
            (np.where(w, shown.column(d.baseline.residuals[0]), 0.0), float(np.mean(w)),
             f"baseline residual ({_model_text(d.baseline)}), fitted samples",
             {"color": "#e08214", "lw": 2.4, "alpha": 0.7}),
            (np.where(w_final, shown.column(d.final.residuals[0]), 0.0), float(np.mean(w_final)),
             f"final residual ({_model_text(d.final)})", {"color": "0.1", "lw": 0.9})):
        sp = welch_spectrum(t, y)
        band = (sp.frequency <= top_f)
        ax.semilogy(sp.frequency[band], np.sqrt(sp.psd[band] / share), label=label, **kw)
        curves.append(np.sqrt(sp.psd[band & (sp.frequency > 0)] / share))
    floor = noise_density(d.baseline, shown.name)
    if floor is not None:
        ax.axhline(floor, label="noise floor (raw data)", gid="noise floor", **style.NOISE)
    if drive is not None and drive < top_f:
        style.mark_frequency(ax, drive, f"drive {drive:.4g} Hz", style.DRIVE, gid="drive")
    for k, f in modes.items():
        if f < top_f:
            style.mark_frequency(ax, f, f"{k} fitted {f:.4g} Hz", style.MODE, gid=f"mode {k}")
    for i, p in enumerate(d.baseline_evidence.peaks):
        ax.axvline(p.frequency, color="#b2182b", ls=":", lw=1.0, gid=f"peak {i + 1}",
                   label="baseline residual peaks" if i == 0 else None)
    cut = d.baseline.problem.force_cutoff_hz
    if cut and cut < top_f:
        ax.axvspan(cut, top_f, **style.DISCOUNT, label=f"above the {cut:g} Hz force filter")
    ax.set(xlabel="frequency [Hz]", ylabel=f"amplitude density [{shown.unit}/sqrt(Hz)]",
           xlim=(0, top_f),
           ylim=style.spectrum_limits(curves, floor))
    ax.set_title(("Residual spectra: what the baseline misses and the final model explains"
                  if d.findings else "Residual spectra of the baseline (no finding)")
                 + (f" ({shown.name})" if shown.index is not None
                    else " (drive: a sweep)" if drive is None else ""))
    ax.legend(loc="upper right", fontsize="small", ncols=2)
    return fig


def _runs(t: np.ndarray, flag: np.ndarray) -> list[tuple[float, float]]:
    """Time ranges (s) where ``flag`` holds."""
    edges = np.flatnonzero(np.diff(np.r_[0, flag.astype(int), 0]))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(edges[::2], edges[1::2])]
