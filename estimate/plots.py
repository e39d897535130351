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
    """Four panels for ``case``: measured and simulated force (N), residual (N), residual
    and measured amplitude spectra (Welch), and the estimates over IPOPT iterations
    (relative to their final values). Saves to ``path`` when given; returns the figure."""
    from .signals import welch_spectrum

    plt = _pyplot()
    exp = result.problem.experiments[case]
    t = exp.case.time
    meas, sim, res = result.measured[case], result.simulated(case), result.residuals[case]
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), constrained_layout=True)
    ax[0].plot(t, meas, lw=0.8, label="measured (filtered)")
    ax[0].plot(t, sim, lw=0.8, label="simulated")
    ax[0].set(xlabel="time [s]", ylabel="force [N]",
              title=f"{exp.case.test.id}: {' + '.join(result.problem.model.names)} "
                    f"(RMS residual {result.rms_residual:.3g} N, R^2 {result.r_squared:.5f})")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, res, lw=0.6, color="C3")
    ax[1].set(xlabel="time [s]", ylabel="residual [N]")
    for sig, label in ((meas, "measured"), (res, "residual")):
        sp = welch_spectrum(t, sig)
        ax[2].semilogy(sp.frequency, np.sqrt(sp.psd), label=label)
    ax[2].set(xlabel="frequency [Hz]", ylabel="amplitude density [N/sqrt(Hz)]", xlim=(0, 15))
    ax[2].legend(loc="upper right")
    if result.history.size:
        final = np.where(result.values == 0, 1.0, result.values)
        for j, name in enumerate(result.names):
            ax[3].plot(result.history[:, j] / final[j], label=name)
        ax[3].set(xlabel="IPOPT iteration", ylabel="estimate / final value", yscale="symlog")
        ax[3].legend(loc="best", fontsize="small")
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
