"""Fit plots: measured vs simulated with zooms, residual, residual spectrum, parameter
trajectories."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import _plotting as style

if TYPE_CHECKING:  # pragma: no cover
    from .result import FitResult

__all__ = ["plot_fit", "mode_frequencies", "drive_frequency_of", "noise_density", "spectrum_top",
           "trajectory_change"]


def mode_frequencies(result: "FitResult") -> dict[str, float]:
    """Fitted small-amplitude mode frequencies [Hz] by component (``p1``: 2.03)."""
    return {k.removesuffix(".frequency_hz"): v for k, (v, _) in result.derived.items()
            if k.endswith(".frequency_hz") and np.isfinite(v)}


def drive_frequency_of(result: "FitResult", case: int = 0) -> float | None:
    """The drive frequency of ``case`` [Hz]: the crank's, or the dominant frequency of the
    carriage acceleration; None for a sweep or a record without a drive."""
    from ..data.signals import drive_frequency

    exp = result.problem.experiments[case]
    if exp.case.crank is not None:
        return float(exp.case.crank.frequency)
    acc = result.drive_acceleration(case)
    if acc is None:
        return None
    f, sweep = drive_frequency(exp.case.time, acc)
    return None if sweep else f


def noise_density(result: "FitResult", channel: str, case: int = 0) -> float | None:
    """Amplitude density of the ``channel``'s noise figure
    (:meth:`~estimate.fitting.result.FitResult.noise_figure`) spread evenly to Nyquist
    [N/sqrt(Hz) or N m/sqrt(Hz)]: the level of a white noise of the figure's standard
    deviation."""
    fig = result.noise_figure(case, channel) if result.noise_figures else None
    if fig is None or not fig.std > 0:
        return None
    t = np.asarray(result.problem.experiments[case].case.time, float)
    fs = 1.0 / float(np.median(np.diff(t)))
    return float(fig.std * np.sqrt(2.0 / fs))


def spectrum_top(fs: float, cutoff_hz: float | None, marked: list[float]) -> float:
    """Upper frequency of a spectrum plot [Hz]: just past the force filter, or (unfiltered
    data) four times the highest marked frequency, at least 15 Hz; at most Nyquist."""
    top = 1.2 * cutoff_hz if cutoff_hz else max(15.0, 4.0 * max(marked, default=0.0))
    return min(top, 0.5 * fs)


def _zoom_windows(t: np.ndarray, end: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """A transient window (the start-up, where the response builds) and a steady one (the
    record's end), each about 6 % of the record, at least 1 s and the start-up."""
    span = max(1.0, 0.06 * (t[-1] - t[0]), end - t[0])
    transient = (t[0], t[0] + span)
    steady = (t[-1] - span, t[-1])
    return transient, steady


def _time_panel(ax, t, meas, sim, unit: str, name: str, *, zooms: bool,
                filtered: bool = True) -> None:
    # with an estimated carriage motion the force is fitted raw (motor tones removed)
    ax.plot(t, meas, **style.MEASURED, label="measured (filtered)" if filtered else "measured")
    ax.plot(t, sim, **style.SIMULATED, label="simulated")
    top = max(float(np.max(np.abs(meas))), float(np.max(np.abs(sim)))) or 1.0
    ax.set(ylabel=f"{name} [{unit}]", xlim=(t[0], t[-1]))
    if not zooms:
        ax.set_ylim(-1.1 * top, 1.1 * top)
        ax.legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncols=2, fontsize="small", frameon=False)
        return
    # room above the trace for two zooms: the transient after the start-up and the steady end
    ax.set_ylim(-1.1 * top, style.ZOOM_TOP * top)
    ax.set_yticks([tk for tk in ax.get_yticks() if abs(tk) <= 1.1 * top])
    end = style.startup_end(t)
    for (lo, hi), bounds, title in zip(_zoom_windows(t, end), style.ZOOM_BOXES,
                                       ("start-up", "steady")):
        inset = ax.inset_axes(bounds)
        keep = (t >= lo) & (t <= hi)
        inset.plot(t[keep], meas[keep], **style.MEASURED)
        inset.plot(t[keep], sim[keep], **style.SIMULATED)
        inset.set_xlim(lo, hi)
        style.label_inset(inset, f"{title}: {lo:.1f}-{hi:.1f} s")
        ax.indicate_inset_zoom(inset, edgecolor="0.4")
    ax.legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncols=2, fontsize="small", frameon=False)


def _residual_panel(ax, t, items, unit: str, keep: np.ndarray | None,
                    left: np.ndarray | None = None) -> None:
    """``items``: (name, residual). Symmetric axis from the residual after the start-up;
    ``left``: samples left out of the fit (clipped, spikes), not drawn."""
    if left is not None:
        items = [(n, np.where(left, np.nan, r)) for n, r in items]
    end = style.startup_end(t)
    steady = t > end
    if keep is not None:
        steady &= keep
    limit = max(style.robust_limit(r, steady) for _, r in items)
    for i, (name, r) in enumerate(items):
        kw = dict(style.RESIDUAL) if len(items) == 1 else {"lw": 0.7, "color": f"C{i}"}
        ax.plot(t, r, label=f"residual {name}" if len(items) > 1 else "residual (simulated - measured)",
                **kw)
    all_r = np.nan_to_num(np.max(np.abs(np.vstack([r for _, r in items])), axis=0))
    style.mark_startup(ax, t, all_r, end, limit, unit)
    rms = [float(np.sqrt(np.nanmean(r[steady] ** 2))) for _, r in items]
    ax.axhline(0.0, color="0.6", lw=0.5, zorder=1)
    ax.set(ylabel=f"residual [{unit}]", xlabel="time [s]", ylim=(-limit, limit), xlim=(t[0], t[-1]))
    ax.set_title(f"residual after the start-up: RMS {max(rms):.3g} {unit}", fontsize="medium", loc="left")
    ax.legend(loc="upper right", fontsize="small", ncols=min(3, len(items) + 1))


def _spectrum_panel(ax, result, case, t, items, unit: str, drive: float | None,
                    modes: dict[str, float]) -> None:
    """``items``: (name, measured, residual)."""
    from ..data.signals import welch_spectrum

    fs = 1.0 / float(np.median(np.diff(t)))
    top_f = spectrum_top(fs, result.problem.force_cutoff_hz, [drive or 0.0, *modes.values()])
    curves, floors = [], []
    for i, (name, meas, res) in enumerate(items):
        band_label = f" {name}" if len(items) > 1 else ""
        sp = welch_spectrum(t, meas)
        band = sp.frequency <= top_f
        ax.semilogy(sp.frequency[band], np.sqrt(sp.psd[band]), label=f"measured{band_label}",
                    **({**style.MEASURED, "lw": 1.8} if len(items) == 1 else {"lw": 1.6, "alpha": 0.35,
                                                                               "color": f"C{i}"}))
        curves.append(np.sqrt(sp.psd[band & (sp.frequency > 0)]))
        # samples left out of the fit (clipped, spikes) are no residual: zeroed, the density
        # scaled back by the share kept
        left = result.problem.left_out[case] if result.problem.left_out else None
        share = 1.0 if left is None else max(float(np.mean(~left)), 1e-9)
        sp = welch_spectrum(t, res if left is None else np.where(left, 0.0, res))
        ax.semilogy(sp.frequency[band], np.sqrt(sp.psd[band] / share), label=f"residual{band_label}",
                    **(style.RESIDUAL if len(items) == 1 else {"lw": 0.8, "color": f"C{i}"}))
        curves.append(np.sqrt(sp.psd[band & (sp.frequency > 0)] / share))
        floor = noise_density(result, name, case)
        if floor is not None:
            floors.append(floor)
            if len(items) == 1:  # the figure's coloured spectrum
                fig = result.noise_figure(case, name)
                f = sp.frequency[band]
                ax.semilogy(f, np.sqrt(fig.psd(f, fs)), gid="noise floor", **style.NOISE,
                            label=f"noise figure {fig.std:.3g} {unit} ({fig.source})")
    if floors:
        floor = float(np.median(floors))
        if len(items) > 1:
            ax.axhline(floor, label="noise figures (white equivalent)", gid="noise floor",
                       **style.NOISE)
    else:
        floor = None
    if drive is not None and drive < top_f:
        style.mark_frequency(ax, drive, f"drive {drive:.4g} Hz", style.DRIVE, gid="drive")
    for k, f in modes.items():
        if f < top_f:
            style.mark_frequency(ax, f, f"{k} fitted {f:.4g} Hz", style.MODE, gid=f"mode {k}")
    ax.set(xlabel="frequency [Hz]", ylabel=f"amplitude density [{unit}/sqrt(Hz)]", xlim=(0, top_f),
           ylim=style.spectrum_limits(curves, floor))
    if result.problem.force_cutoff_hz and result.problem.force_cutoff_hz < top_f:
        ax.axvspan(result.problem.force_cutoff_hz, top_f, **style.DISCOUNT,
                   label=f"above the {result.problem.force_cutoff_hz:g} Hz force filter")
    ax.legend(loc="upper right", fontsize="small", ncols=2)


def trajectory_change(history: np.ndarray, final: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each estimate's change from its final value over the iterations, in per cent of that
    value (``history`` iterations x estimates); an estimate whose final value is 0 (a hinge
    spring at its bound) in per cent of its largest magnitude instead, which ends at 0 as the
    others do. Also returns which estimates ended at 0.

    Examples
    --------
    >>> change, zero = trajectory_change(np.array([[2.0, 0.5], [1.0, 0.0]]), np.array([1.0, 0.0]))
    >>> change.tolist(), zero.tolist()
    ([[100.0, 100.0], [0.0, 0.0]], [False, True])
    """
    history = np.asarray(history, float)
    final = np.asarray(final, float)
    zero = final == 0
    peak = np.max(np.abs(history), axis=0) if history.size else np.ones_like(final)
    scale = np.where(zero, np.where(peak > 0, peak, 1.0), final)
    return 100.0 * (history - final) / scale, zero


def _trajectory_panel(ax, result) -> None:
    from matplotlib.ticker import MaxNLocator, PercentFormatter

    change, zero = trajectory_change(result.history, result.values)
    it = np.arange(change.shape[0])
    for j, name in enumerate(result.names):
        label = f"{name} (final 0: % of its largest value)" if zero[j] else name
        ax.plot(it, change[:, j], marker="o", ms=3, lw=1.0, color=f"C{j % 10}",
                ls=("-", "--", ":", "-.")[j // 10 % 4], label=label)
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_formatter(PercentFormatter())
    ax.set(xlabel="IPOPT iteration [-]", ylabel="change from the final estimate [%]",
           xlim=(0, max(1, it[-1])))
    ax.legend(loc="upper right", fontsize="small", ncols=min(4, len(result.names)))


def plot_fit(result: "FitResult", path: str | Path | None = None, *, case: int = 0):
    """The fit ``result`` of ``case`` as a test engineer reads it.

    Panels: measured (thick, light) and simulated (thin, dark, dashed) force or, for
    multi-channel rigs, every fitted channel (N, N m), with zooms on the transient after the
    start-up and on the steady end (lateral rig); the residual in N (and N m) on its own
    symmetric axis, scaled by the residual after the start-up (the start-up is shaded and its
    off-scale peak named); amplitude spectra of measured and residual in N/sqrt(Hz) up to
    just past the force filter, with the raw data's noise floor, the drive frequency and the
    fitted mode frequencies; and each estimate's change from its final value (%) over the
    IPOPT iterations. Saves to ``path`` (PNG) when given; returns the figure (shown inline
    in a notebook when ``path`` is None).

    Examples
    --------
    >>> from estimate import FitProblem, fit, load_case, model_from_spec   # doctest: +SKIP
    >>> case = load_case("A1.toml")                                        # doctest: +SKIP
    >>> res = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)))  # doctest: +SKIP
    >>> plot_fit(res, "A1_fit.png")                                        # doctest: +SKIP
    """
    exp = result.problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    names = result.channels[case] if result.channels else ("force_x",)
    channels = [(n, *result.channel(n, case)) for n in names]  # (name, measured, residual)
    groups: dict[str, list] = {}
    for c in channels:
        groups.setdefault(style.unit_of(c[0]), []).append(c)
    single = len(channels) == 1
    heights = [2.6 if single else 1.2] * len(channels) + [1.3] * len(groups) + [1.6] * len(groups) + [1.5]
    fig = style.figure(path, figsize=(10, 1.9 * sum(heights) + 0.6))
    ax = fig.subplots(len(heights), 1, height_ratios=heights)
    keep = result.weights[case] > 0 if result.weights else None
    estimated = bool(result.problem.carriage) and result.problem.carriage[case] is not None
    for a, (name, meas, res) in zip(ax, channels):
        _time_panel(a, t, meas, meas + res, style.unit_of(name), name, zooms=single,
                    filtered=not estimated)
    ax[len(channels) - 1].set_xlabel("time [s]")
    k = len(channels)
    for a, (unit, items) in zip(ax[k:], groups.items()):
        _residual_panel(a, t, [(n, r) for n, _, r in items], unit, keep,
                        result.problem.left_out[case] if result.problem.left_out else None)
    k += len(groups)
    drive = drive_frequency_of(result, case)
    modes = mode_frequencies(result)
    for a, (unit, items) in zip(ax[k:], groups.items()):
        _spectrum_panel(a, result, case, t, items, unit, drive, modes)
    if result.history.size:
        _trajectory_panel(ax[-1], result)
    else:
        ax[-1].set_axis_off()
    model = result.problem.model
    # the model as fitted ("fixed,p1:nospring"), not only its components' names
    fig.suptitle(f"{exp.case.test.id}: {model.spec() or ' + '.join(model.names)} - RMS residual "
                 f"{result.rms_residual:.3g} {'N' if single else '(scaled)'}, R^2 {result.r_squared:.5f}")
    style.save(fig, path, dpi=110)
    return fig
