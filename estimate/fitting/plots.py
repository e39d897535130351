"""Fit plots: measured vs simulated, residual, residual spectrum, parameter trajectories."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .result import FitResult

__all__ = ["plot_fit"]


def _pyplot():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_fit(result: "FitResult", path: str | Path | None = None, *, case: int = 0):
    """Panels for ``case``: measured and simulated force (N) or, for multi-channel rigs,
    every fitted channel (N, N m); the residual; residual and measured amplitude spectra
    (Welch); and the estimates over IPOPT iterations (relative to their final values).
    Saves to ``path`` when given; returns the figure."""
    from ..data.signals import welch_spectrum

    plt = _pyplot()
    exp = result.problem.experiments[case]
    t = exp.case.time
    names = result.channels[case] if result.channels else ("force_x",)
    channels = [(n, *result.channel(n, case)) for n in names]  # (name, measured, residual)
    rows = len(channels) + 3
    fig, ax = plt.subplots(rows, 1, figsize=(9, 2.6 * rows + 1), constrained_layout=True)
    for a, (name, meas, res) in zip(ax, channels):
        unit = "N m" if name.startswith("torque") else "N"
        a.plot(t, meas, lw=0.8, label="measured (filtered)")
        a.plot(t, meas + res, lw=0.8, label="simulated")
        a.set(xlabel="time [s]", ylabel=f"{name} [{unit}]")
        a.legend(loc="upper right", fontsize="small")
    ax[0].set_title(f"{exp.case.test.id}: {' + '.join(result.problem.model.names)} "
                    f"(RMS residual {result.rms_residual:.3g}, R^2 {result.r_squared:.5f})")
    k = len(channels)
    for name, _, res in channels:
        ax[k].plot(t, res, lw=0.6, label=name)
    ax[k].set(xlabel="time [s]", ylabel="residual [N, N m]")
    if len(channels) > 1:
        ax[k].legend(loc="upper right", fontsize="small")
    for name, meas, res in channels[:1] if len(channels) == 1 else channels:
        if len(channels) == 1:
            sp = welch_spectrum(t, meas)
            ax[k + 1].semilogy(sp.frequency, np.sqrt(sp.psd), label="measured")
        sp = welch_spectrum(t, res)
        label = f"residual {name}" if len(channels) > 1 else "residual"
        ax[k + 1].semilogy(sp.frequency, np.sqrt(sp.psd), label=label)
    ax[k + 1].set(xlabel="frequency [Hz]", ylabel="amplitude density [/sqrt(Hz)]", xlim=(0, 15))
    ax[k + 1].legend(loc="upper right", fontsize="small")
    if result.history.size:
        final = np.where(result.values == 0, 1.0, result.values)
        for j, name in enumerate(result.names):
            ax[k + 2].plot(result.history[:, j] / final[j], label=name)
        ax[k + 2].set(xlabel="IPOPT iteration", ylabel="estimate / final value", yscale="symlog")
        ax[k + 2].legend(loc="best", fontsize="small")
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
