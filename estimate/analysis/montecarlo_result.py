"""What a Monte Carlo force dispersion gives (:class:`MonteCarloResult`): the outputs of
every draw, their percentile bands, the derived quantities, the plots."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["PERCENTILES", "MonteCarloResult"]

#: Percentiles of the envelopes and derived-quantity summaries.
PERCENTILES = (2.5, 5.0, 50.0, 95.0, 97.5)


@dataclass(frozen=True)
class MonteCarloResult:
    """Envelopes and summaries of a Monte Carlo run.

    ``outputs[name]`` is ``(samples, len(time))``; ``nominal[name]`` the output at the fit's
    values; ``envelopes[name][q]`` the ``q``-th percentile over draws at each time;
    ``derived[name]`` per draw (``peak_<output>`` is the largest magnitude over the run,
    ``pN.frequency_hz`` and ``pN.damping_ratio`` from
    the drawn parameters). ``time`` is the grid (s); ``draws`` the drawn values
    ``(samples, len(parameter_names))`` (``parameter_names`` the drawn parameters);
    ``seed`` the random seed; ``acceptance`` the share
    of normal draws inside the parameters' bounds; ``seconds`` the run time and
    ``executor`` where it ran; ``percentiles`` those of the envelopes.
    """

    time: np.ndarray
    parameter_names: tuple[str, ...]
    draws: np.ndarray
    outputs: Mapping[str, np.ndarray]
    derived: Mapping[str, np.ndarray]
    seed: int | None
    acceptance: float
    seconds: float
    executor: str
    percentiles: tuple[float, ...] = PERCENTILES
    #: Per output, the simulation at the fit's values (the nominal), ``(len(time),)``.
    nominal: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def samples(self) -> int:
        return self.draws.shape[0]

    @property
    def draws_per_second(self) -> float:
        return self.samples / self.seconds if self.seconds > 0 else math.inf

    @property
    def envelopes(self) -> dict[str, dict[float, np.ndarray]]:
        return {name: dict(zip(self.percentiles, np.percentile(Y, self.percentiles, axis=0)))
                for name, Y in self.outputs.items()}

    def summary(self) -> dict[str, dict[str, float]]:
        """Mean, standard deviation and percentiles of every derived quantity."""
        out = {}
        for name, v in self.derived.items():
            q = np.percentile(v, self.percentiles)
            out[name] = {"mean": float(np.mean(v)), "std": float(np.std(v, ddof=1)) if v.size > 1 else 0.0,
                         **{f"p{p:g}": float(x) for p, x in zip(self.percentiles, q)}}
        return out

    def to_json(self) -> dict:
        """The envelopes and summaries as JSON-ready data (draws not included)."""
        return {
            "samples": self.samples, "seed": self.seed, "acceptance": self.acceptance,
            "seconds": self.seconds, "draws_per_second": self.draws_per_second,
            "executor": self.executor, "percentiles": list(self.percentiles),
            "parameters": list(self.parameter_names),
            "parameter_summary": {
                n: {"mean": float(np.mean(self.draws[:, i])), "std": float(np.std(self.draws[:, i], ddof=1))
                    if self.samples > 1 else 0.0} for i, n in enumerate(self.parameter_names)},
            "time": self.time.tolist(),
            "envelopes": {name: {f"p{q:g}": env[q].tolist() for q in self.percentiles}
                          for name, env in self.envelopes.items()},
            "derived": self.summary(),
        }

    def report(self) -> str:
        """A short text report."""
        lines = [f"Monte Carlo: {self.samples} draws (seed {self.seed}), {self.seconds:.2f} s, "
                 f"{self.draws_per_second:.0f} draws/s on {self.executor}; "
                 f"{100 * self.acceptance:.1f}% of normal draws inside the bounds"]
        head = "  ".join(f"{'p' + format(p, 'g'):>11}" for p in self.percentiles)
        lines.append(f"{'quantity':<22}{'mean':>11}  {'std':>11}  {head}")
        for name, s in self.summary().items():
            vals = "  ".join(f"{s['p' + format(p, 'g')]:>11.5g}" for p in self.percentiles)
            lines.append(f"{name:<22}{s['mean']:>11.5g}  {s['std']:>11.4g}  {vals}")
        return "\n".join(lines)

    def plot(self, path: str | Path | None = None, *, output: str | None = None,
             measured: np.ndarray | None = None):
        """What the parameter uncertainty does to ``output`` (default: the first).

        Top: the nominal simulation (fit values) over the ``measured`` trace when given, with
        a zoom on the record's end. Bottom: the percentile bands of the deviation of the
        draws from the nominal (the part the uncertainty moves, invisible on the full force
        scale) and the measured trace's deviation from the nominal on the same axis.
        Saves to ``path`` when given; returns the figure."""
        from .. import _plotting as style

        name = output or next(iter(self.outputs))
        unit = style.unit_of(name) if name.startswith(("force", "torque")) else "-"
        t = self.time
        Y = self.outputs[name]
        nominal = self.nominal.get(name)
        if nominal is None:  # a result made without the nominal run: the median stands in
            nominal = np.median(Y, axis=0)
            nominal_label = "median of the draws"
        else:
            nominal_label = "nominal (fit values)"
        dev = np.percentile(Y - nominal, self.percentiles, axis=0)
        env = dict(zip(self.percentiles, dev))
        fig = style.figure(path, figsize=(10, 7))
        ax = fig.subplots(2, 1, sharex=True, height_ratios=[1.2, 1])
        if measured is not None:
            ax[0].plot(t, measured, **style.MEASURED, label="measured (filtered)")
        ax[0].plot(t, nominal, **style.SIMULATED, label=nominal_label)
        ax[0].set(ylabel=f"{name} [{unit}]", xlim=(t[0], t[-1]))
        ax[0].legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncols=2, fontsize="small", frameon=False)
        qs = sorted(self.percentiles)
        for lo, hi, alpha in ((qs[0], qs[-1], 0.25), (qs[1], qs[-2], 0.45)):
            ax[1].fill_between(t, env[lo], env[hi], alpha=alpha, color="#2166ac", lw=0,
                               label=f"draws, {lo:g}-{hi:g} %")
        ax[1].plot(t, env[50.0], color="#2166ac", lw=0.8, label="draws, median")
        # the bands are percentiles already: their largest excursion sets the axis
        limit = 1.15 * float(np.max(np.abs([env[qs[0]], env[qs[-1]]]))) or 1.0
        if measured is not None:
            mdev = np.asarray(measured, float) - nominal
            ax[1].plot(t, mdev, color="0.2", lw=0.6, label="measured - nominal", zorder=3)
            limit = max(limit, style.robust_limit(mdev, t > style.startup_end(t), margin=1.1))
        ax[1].set(ylabel=f"{name} - nominal [{unit}]", xlabel="time [s]", ylim=(-limit, limit))
        ax[1].legend(loc="upper right", fontsize="small", ncols=2)
        fig.suptitle(f"Monte Carlo over the fit's uncertainty: {self.samples} draws (seed {self.seed})")
        style.save(fig, path, dpi=120)
        return fig
