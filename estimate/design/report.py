"""What a design recommends, in words, JSON, a drive file the rig can take and a plot."""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .drives import LateralDrive, SpinDrive
from .information import Z95, Prediction
from .problem import LINEAR_SWING, DesignProblem
from .search import Candidate, Search, spin_case

__all__ = ["Design", "drive_table", "gain_text", "halfwidth_text", "write_drive"]

#: A correlation above which a target that misses the goal is named confounded with another.
STILL_CONFOUNDED = 0.99


def _percent(x: float) -> str:
    if not math.isfinite(x):
        return "undetermined"
    return f"+/-{100 * x:.2g} %" if x < 0.1 else f"+/-{100 * x:.0f} %"


def halfwidth_text(name: str, p: Prediction, unit: str = "") -> str:
    """The 95 % half-width of ``name``: relative (``+/-0.6 %``), or in its unit when the
    interval holds zero (a value the data cannot tell from zero has no relative width)."""
    rel = p.relative_halfwidth(name)
    if rel < 1:
        return _percent(rel)
    return f"+/-{Z95 * p.stderr(name):.2g}{' ' + unit if unit else ''}"


def gain_text(name: str, before: Prediction, after: Prediction, unit: str = "") -> str:
    """``"interval of p1.mass from +/-4 % to +/-0.6 %"`` (95 % half-widths over the value, or
    in ``unit`` when an interval holds zero)."""
    return (f"interval of {name} from {halfwidth_text(name, before, unit)} to "
            f"{halfwidth_text(name, after, unit)}")


def _correlation(p: Prediction, a: str, b: str) -> float:
    i, j = p.names.index(a), p.names.index(b)
    C = p.covariance
    return float(C[i, j] / math.sqrt(max(C[i, i] * C[j, j], 1e-300)))


@dataclass(frozen=True)
class Design:
    """The recommendation of a design: the ``problem``, the ``search`` and its findings."""

    problem: DesignProblem
    search: Search

    @property
    def recommended(self) -> Candidate:
        return self.search.ranked[0]

    # -- findings ----------------------------------------------------------------------------
    def gains(self) -> list[str]:
        after = self.recommended.prediction
        return [gain_text(n, self.search.before, after, self.problem.units.get(n, ""))
                for n in self.problem.targets]

    def unseparated(self) -> list[str]:
        """Sentences for targets the recommended record leaves wider than the goal, and why."""
        after = self.recommended.prediction
        goal = self.problem.goal
        out = []
        for t in self.problem.targets:
            width = after.relative_halfwidth(t)
            if width <= goal:
                continue
            partners = [n for n in self.problem.names if n != t
                        and abs(_correlation(after, t, n)) >= STILL_CONFOUNDED]
            with_ = (f" from {', '.join(f'`{n}`' for n in partners)} (predicted correlation "
                     + ", ".join(f"{_correlation(after, t, n):+.4f}" for n in partners) + ")"
                     ) if partners else ""
            unit = self.problem.units.get(t, "")
            zero = (f" (its value {self.problem.values[t]:.3g}{' ' + unit if unit else ''} "
                    "is not told from zero)") if width >= 1 else ""
            out.append(
                f"`{t}` cannot be pinned down to {_percent(goal)}{with_} on this rig: the best "
                f"drive within its limits and a swing of {self.problem.max_swing:g} rad leaves "
                f"its interval at {halfwidth_text(t, after, unit)}{zero}. "
                + ("Within that swing the force depends on them almost only through their "
                   "combination (the pendulum's frequency); what tells them apart grows with "
                   "the swing's nonlinearity (a larger `--max-swing`, if the liquid allows "
                   "it), a longer record, or needs another measurement." if partners else
                   "The rig's limits and the noise allow no more in one record of this "
                   "length; more records, or a longer one, narrow it further."))
        return out

    def warnings(self) -> list[str]:
        out = []
        rec = self.recommended
        if rec.swing > LINEAR_SWING:
            out.append(f"the predicted peak swing {rec.swing:.2f} rad leaves the linear range "
                       f"(< {LINEAR_SWING:g} rad: frequency within 0.25 %); the analog's "
                       "nonlinearity is part of the prediction, and a real liquid surface may "
                       "break or swirl at such swings")
        after, before = rec.prediction, self.search.before
        if all(after.relative_halfwidth(t) > 0.9 * before.relative_halfwidth(t)
               for t in self.problem.targets):
            out.append("the best drive found narrows no target's interval by more than 10 %: "
                       "the next record on this rig adds little to what is known")
        return out + self.unseparated()

    # -- outputs -----------------------------------------------------------------------------
    def _candidate_dict(self, c: Candidate) -> dict[str, Any]:
        p = self.problem
        d = c.drive
        out: dict[str, Any] = {
            "label": c.label, "family": d.family, "description": d.describe(),
            "variables": d.values, "scale": d.scale, "limited_by": c.limited_by,
            "peak_swing_rad": c.swing,
            "criterion": c.best.criterion(p.criterion),
            "predicted": {n: {"stderr": c.best.stderr(n),
                              "halfwidth_95_relative": c.best.relative_halfwidth(n)}
                          for n in p.targets},
            "surrogate": {n: c.surrogate.relative_halfwidth(n) for n in p.targets},
            "noise": dict(zip(p.channels, map(float, c.noise))),
        }
        if isinstance(d, LateralDrive):
            pk = d.peaks(p.rate)
            out["peaks"] = {"displacement_m": pk.displacement, "velocity_m_s": pk.velocity,
                            "acceleration_m_s2": pk.acceleration}
            out["limit_ratios"] = pk.ratios(p.limits)
        else:
            out["spin"] = {"rate_rad_s": d.spin_rate, "nutation_frequency_hz": d.nutation_frequency,
                           "cone_angle_rad": d.cone_angle, "spin_up_s": d.spin_up,
                           "nutation_ramp_s": d.nutation_ramp,
                           "tank_frame_frequency_hz": d.tank_frame_frequency}
            out["limit_ratios"] = {
                "spin_rate": abs(d.spin_rate) / p.limits.spin_rate,
                "nutation_frequency": abs(d.nutation_frequency) / p.limits.nutation_frequency,
                "cone_angle": d.cone_angle / p.limits.cone_angle}
        return out

    def to_dict(self, drive_file: str | None = None) -> dict[str, Any]:
        """The JSON form of ``slosh design --json``; ``drive_file`` names the drive CSV
        written beside it (None: none)."""
        p, s = self.problem, self.search
        lim = p.limits
        return {
            "fit": str(p.fit_path) if p.fit_path else None,
            "case": str(p.case.path),
            "rig": p.case.test.rig,
            "targets": list(p.targets),
            "criterion": p.criterion,
            "limits": {k: v for k, v in vars(lim).items() if v is not None},
            "duration_s": p.duration,
            "sample_rate_hz": p.rate,
            "predicted_record_rate_hz": p.rate / p.decimation,
            "max_swing_rad": p.max_swing,
            "goal_halfwidth_95_relative": p.goal,
            "pinned_down": {n: self.recommended.prediction.relative_halfwidth(n) <= p.goal
                            for n in p.targets},
            "linear_swing_rad": LINEAR_SWING,
            "before": {n: {"value": float(p.values[n]), "stderr": s.before.stderr(n),
                           "halfwidth_95_relative": s.before.relative_halfwidth(n)}
                       for n in p.targets},
            "recommended": self._candidate_dict(self.recommended),
            "gain": self.gains(),
            "shrink_factor": {n: s.before.relative_halfwidth(n)
                              / self.recommended.prediction.relative_halfwidth(n)
                              for n in p.targets},
            "finalists": [self._candidate_dict(c) for c in s.ranked],
            "alternatives": [self._candidate_dict(c) for c in s.alternatives],
            "drive_file": drive_file,
            "warnings": self.warnings(),
            "notes": list(p.notes),
            "evaluations": s.evaluations,
            "seconds": s.seconds,
        }

    def summary(self) -> str:
        p, rec = self.problem, self.recommended
        lines = [f"recommended: {rec.drive.describe()} for {p.duration:g} s "
                 f"(amplitude limited by {rec.limited_by}; peak swing {rec.swing:.3f} rad)"]
        lines += [f"  {g}" for g in self.gains()]
        for c in self.search.ranked[1:] + self.search.alternatives:
            lines.append(f"  instead: {c.label}: {c.drive.describe()}: " + ", ".join(
                f"{n} {halfwidth_text(n, c.prediction, p.units.get(n, ''))}"
                for n in p.targets))
        return "\n".join(lines)

    def drive_table(self) -> tuple[list[str], np.ndarray]:
        """The recommended drive as the rig takes it (:func:`drive_table`)."""
        return drive_table(self.problem, self.recommended.drive)

    def write_drive(self, path: Path) -> None:
        """Write :meth:`drive_table` as CSV to ``path`` (:func:`write_drive`)."""
        write_drive(path, *self.drive_table())

    def plot(self, path: Path) -> None:
        """The recommended drive and its predicted record, and the families' scores, as a
        PNG at ``path``."""
        from .._plotting import figure, save

        p, rec = self.problem, self.recommended
        fig = figure(path, figsize=(9, 9))
        axes = fig.subplots(3, 1)
        t = rec.record.time
        header, rows = self.drive_table()
        ax = axes[0]
        ratios = self._candidate_dict(rec)["limit_ratios"]
        if isinstance(rec.drive, LateralDrive):
            ax.plot(rows[:, 0], 1e3 * rows[:, 1], lw=0.8, color="tab:blue")
            ax.set_ylabel("carriage displacement [mm]", color="tab:blue")
            twin = ax.twinx()
            twin.plot(t, rec.drive.motion(t)[2], lw=0.5, color="tab:gray", alpha=0.7)
            twin.axhline(p.limits.acceleration, color="tab:gray", ls=":", lw=0.8)
            twin.axhline(-p.limits.acceleration, color="tab:gray", ls=":", lw=0.8)
            twin.set_ylabel("acceleration [m/s^2] (limit dotted)", color="tab:gray")
        else:
            ax.plot(rows[:, 0], rows[:, 2], lw=0.8, label="spin rate [rad/s]")
            ax.plot(rows[:, 0], 100 * rows[:, 4], lw=0.8, label="cone angle [rad x 100]")
            ax.set_ylabel("rig motion")
            ax.legend(loc="upper right", fontsize=8)
        ax.set_title(f"recommended: {rec.drive.describe()}\npeak / limit: " + ", ".join(
            f"{k} {v:.2f}" for k, v in ratios.items()), fontsize=9)
        from .information import swing_angles

        dm = p.derived
        if isinstance(rec.drive, SpinDrive):
            from ..data.experiment import experiment
            from ..data.models import model_for_case

            case = spin_case(p, rec.drive)
            dm = experiment(case, model_for_case(p.model, case)).derived
        ax = axes[1]
        for name, sw in swing_angles(dm, rec.record.states).items():
            ax.plot(t, sw, lw=0.8, label=f"{name} swing")
        ax.axhline(LINEAR_SWING, color="tab:orange", ls="--", lw=0.8, label="linear range")
        ax.axhline(p.max_swing, color="tab:red", ls=":", lw=0.8, label="swing limit")
        ax.set_ylabel("predicted swing [rad]")
        ax.set_xlabel("time [s]")
        ax.legend(loc="upper right", fontsize=8)
        ax = axes[2]
        rows_ = [("before", self.search.before)] + [
            (c.label + (" (recommended)" if c is rec else ""), c.prediction)
            for c in (*self.search.ranked, *self.search.alternatives)]
        width = 0.8 / len(p.targets)
        x = np.arange(len(rows_))
        heights = np.array([[100 * pr.relative_halfwidth(n) for _, pr in rows_]
                            for n in p.targets])
        for k, name in enumerate(p.targets):
            ax.bar(x + k * width, heights[k], width, label=name)
        ax.set_xticks(x + width * (len(p.targets) - 1) / 2)
        ax.set_xticklabels([textwrap.fill(r, 16) for r, _ in rows_], fontsize=7)
        finite = heights[np.isfinite(heights) & (heights > 0)]
        if finite.size and finite.max() > 10 * finite.min():
            ax.set_yscale("log")
        ax.set_ylabel("predicted 95 % half-width [%]")
        ax.legend(fontsize=8)
        save(fig, path)


def drive_table(problem: DesignProblem, drive) -> tuple[list[str], np.ndarray]:
    """A drive as the rig takes it, at the rig's rate: ``time,displacement`` (s, m) on the
    lateral rig; ``time,spin_angle,spin_rate,nutation_phase,cone_angle`` (s, rad, rad/s,
    rad, rad) on the spinning rig."""
    t = problem.rig_time
    if isinstance(drive, SpinDrive):
        from ..data.spin import spin_excitation

        u = np.asarray(spin_excitation(spin_case(problem, drive)).values(t))
        return (["time", "spin_angle", "spin_rate", "nutation_phase", "cone_angle"],
                np.column_stack([t, u[0], u[1], u[3], u[6]]))
    return ["time", "displacement"], np.column_stack([t, drive.motion(t)[0]])


def write_drive(path: Path, header: list[str], rows: np.ndarray) -> None:
    """A drive table as CSV with a header line, ten significant digits."""
    np.savetxt(path, rows, delimiter=",", header=",".join(header), comments="", fmt="%.10g")
