"""The drive that best tells two competing models apart (``slosh design --discriminate``).

A diagnosis (``slosh diagnose --json``) holds two models that both explain the records run
so far: the baseline analog and the final one (e.g. a shorter pendulum against a pendulum
with a hinge spring, one mode against two). For a candidate drive, each model predicts the
record with its own estimates; the wrong one shows its error as a lack of fit that
refitting its parameters cannot remove. Linearised at its estimates (sensitivities ``J``
through the simulation, :class:`~.information.Sensitivities`), the chi-square that model
``B`` is left with when the record comes from model ``A`` is

    ``lambda_B = |r|^2 - r^T J_B (J_B^T J_B)^-1 J_B^T r``,  ``r = (y_A - y_B) / sigma``

(the part of the difference no change of ``B``'s parameters absorbs, in units of the noise
``sigma``). The search maximises ``min(lambda_A, lambda_B)``: whichever model is true, the
other fails by that much (for nested models, e.g. a pendulum with and without a hinge
spring, only the smaller model's failure counts: the larger reproduces its records). The
prediction is made at the models' current estimates; a parameter the records so far leave
undetermined (a length confounded with its spring) is taken where the fit left it, so
the size of the gap is uncertain, not its sign. Under a drive that separates the models well their outputs
differ by far more than a linear change of the parameters describes, so the linearised
``lambda`` overstates the gap (by 1000x on a resonant drive); the best drive of every
family is therefore judged by refitting each model to the other's record (SciPy's
``least_squares`` with the exact sensitivities as Jacobian, from the model's estimates
within its parameter bounds), and ranked by that. The refit ignores the records already
run, which also constrain the wrong model: the gap it predicts is a lower bound.
``lambda >= 25`` rejects the wrong model at five standard deviations.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import brentq

from analogs.errors import InputError
from derive import derive

from ..data.case import Case
from ..data.models import model_for_case, model_from_spec, rig_values
from ..inputs import load_json
from .drives import LATERAL_FAMILIES, LateralDrive
from .problem import MAX_SWING, DesignProblem
from .report import drive_table, write_drive
from .search import LIMIT_MARGIN, Runner, band, family_search

__all__ = ["Rival", "Rivalry", "Discrimination", "discrimination", "rivals_from_diagnosis",
           "SEPARATION"]

#: Chi-square of the wrong model's lack of fit that rejects it at five standard deviations.
SEPARATION = 25.0

#: Parameter suffixes a model specification (``--model``) can express, per pendulum.
_SPEC_PARTS = {"mass": "", "length": "", "damping": "", "hinge_height": "",
               "stiffness": "spring", "quadratic_damping": ":quadratic",
               "diaphragm_stiffness": ":diaphragm", "diaphragm_damping": ":diaphragm"}


@dataclass(frozen=True)
class Rival:
    """One competing model: its label in the diagnosis (``baseline``/``final``), its
    specification, derived model, parameter values and estimated parameters."""

    label: str
    spec: str
    model: Any = field(repr=False)
    derived: Any = field(repr=False)
    values: dict = field(repr=False)
    names: tuple[str, ...]


def _spec(parameters: dict, where: str) -> str:
    """The model specification of a diagnosis model from its parameter names."""
    tokens: dict[str, set[str]] = {}
    fixed = False
    problems = []
    for name in parameters:
        comp, _, par = name.partition(".")
        if comp == "rig":
            continue
        if comp == "fixed":
            fixed = True
        elif comp[:1] == "p" and comp[1:].isdigit() and par in _SPEC_PARTS:
            tokens.setdefault(comp, set()).add(_SPEC_PARTS[par])
        else:
            problems.append(f"`{name}`")
    if problems:
        raise InputError(f"{where}: {', '.join(problems)} cannot be written as a `--model` "
                         "specification (fixed, pN with spring, :quadratic, :diaphragm); "
                         "discrimination supports those models")
    parts = ["fixed"] if fixed else []
    for comp in sorted(tokens, key=lambda c: int(c[1:])):
        mods = tokens[comp]
        parts.append(comp + ("" if "spring" in mods else ":nospring")
                     + "".join(sorted(m for m in mods if m.startswith(":"))))
    return ",".join(parts)


def rivals_from_diagnosis(path: str | Path, case: Case) -> tuple[Rival, Rival]:
    """The baseline and final models of a diagnosis (the JSON of ``slosh diagnose``) on
    ``case``'s rig, with their estimates."""
    data = load_json(path, "a diagnosis file (JSON)")
    out = []
    for label in ("baseline", "final"):
        entry = data.get(label) if isinstance(data, dict) else None
        params = entry.get("parameters") if isinstance(entry, dict) else None
        if not isinstance(params, dict) or not params:
            raise InputError(f"{path}: expected a diagnosis (as `slosh diagnose --json` writes) "
                             f"with `{label}.parameters`")
        spec = _spec(params, f"{path}: {label}")
        model = model_for_case(model_from_spec(spec, case), case)
        dm = derive(model)
        values = {k: float(v["value"]) for k, v in params.items()
                  if isinstance(v, dict) and isinstance(v.get("value"), (int, float))}
        values = {k: v for k, v in (values | rig_values(case)).items() if k in dm.parameter_names}
        names = tuple(k for k, v in params.items() if isinstance(v, dict) and v.get("estimated")
                      and k in dm.parameter_names)
        out.append(Rival(label, spec, model, dm, values, names))
    if out[0].spec == out[1].spec:
        raise InputError(f"{path}: the diagnosis found nothing to add (baseline and final "
                         f"model are both `{out[0].spec}`): there are no two models to tell "
                         "apart; use `--target` to pin the parameters down instead")
    return out[0], out[1]


@dataclass(frozen=True)
class Rivalry:
    """A drive scored for discrimination: the chi-square each model is left with when the
    other is true (``lack_of_fit`` by the label of the model that fails: linearised, or
    after a refit once judged; ``linearised`` keeps the linearised one), the peak swing of
    either model (rad) and what limits the amplitude."""

    drive: LateralDrive
    swing: float
    limited_by: str
    lack_of_fit: dict[str, float]
    label: str = ""
    linearised: dict[str, float] | None = None

    #: Labels of the models whose failure counts (nested models: only the smaller one,
    #: which the larger reproduces exactly).
    counted: tuple[str, ...] = ()

    @property
    def score(self) -> float:
        return -min(v for k, v in self.lack_of_fit.items() if not self.counted or k in self.counted)


def _lack_of_fit(r: np.ndarray, J: np.ndarray) -> float:
    """``|r|^2`` less what a least-squares change of the parameters absorbs."""
    x, *_ = np.linalg.lstsq(J, r, rcond=1e-10)
    return float(r @ r - (J @ x) @ r)


def _score(problem: DesignProblem, rivals: tuple[Rival, Rival], drive: LateralDrive, *,
           label: str = "", scale: float | None = None) -> Rivalry | None:
    runs = [Runner(problem, drive, derived=r.derived, values=r.values, names=r.names)
            for r in rivals]
    limited, worst = max(runs[0].ratios().items(), key=lambda kv: kv[1])
    if not worst > 0:
        return None
    top = (1 - LIMIT_MARGIN) / worst
    if scale is not None and scale < top:
        top, limited = scale, "given"

    def swing(s: float) -> float:
        return max(run.swing(s) for run in runs)

    s, cap = top, problem.max_swing
    if swing(top) > cap:
        s = 0.99 * brentq(lambda x: swing(x) - cap, 1e-3 * top, top, xtol=0.02 * top,
                          rtol=0.02, maxiter=12)
        while swing(s) > cap:
            s *= 0.99
        limited = "swing"
    recs = [run.record(s) for run in runs]
    sigma = problem.new_noise(np.maximum(recs[0].rms(), recs[1].rms()))[:, None]
    diff = ((recs[0].outputs - recs[1].outputs) / sigma).ravel()
    lack = {}
    for k, (rival, rec) in enumerate(zip(rivals, recs)):
        J = (rec.jacobian / sigma[:, :, None]).reshape(-1, rec.jacobian.shape[-1])
        lack[rival.label] = _lack_of_fit(diff if k else -diff, J)
    return Rivalry(replace(drive, scale=s), swing(s), limited, lack, label,
                   counted=_counted(rivals))


def _counted(rivals: tuple[Rival, Rival]) -> tuple[str, ...]:
    """The models whose lack of fit counts: both, unless one's parameters are a subset of
    the other's (nested: the larger reproduces the smaller's records exactly, so only the
    smaller can fail)."""
    a, b = (set(r.derived.parameter_names) for r in rivals)
    if a < b:
        return (rivals[0].label,)
    if b < a:
        return (rivals[1].label,)
    return tuple(r.label for r in rivals)


def _refit(problem: DesignProblem, rivals: tuple[Rival, Rival], r: Rivalry) -> Rivalry:
    """``r`` judged by refitting each model to the other's record (noise-free, exact drive):
    SciPy ``least_squares`` on the residuals over the noise, the exact sensitivities as
    Jacobian, within the parameters' bounds."""
    from scipy.optimize import least_squares

    runs = [Runner(problem, r.drive, derived=v.derived, values=dict(v.values), names=v.names)
            for v in rivals]
    recs = [run.record(r.drive.scale) for run in runs]
    sigma = problem.new_noise(np.maximum(recs[0].rms(), recs[1].rms()))[:, None]
    lack = {}
    for k, (rival, run) in enumerate(zip(rivals, runs)):
        data = recs[1 - k].outputs
        bounds = {p.name: (p.lower, p.upper) for p in rival.derived.parameters}
        lo = np.array([bounds[n][0] for n in rival.names])
        hi = np.array([bounds[n][1] for n in rival.names])
        x0 = np.clip(np.array([rival.values[n] for n in rival.names]), lo, hi)
        cache: dict = {}

        def record(x, run=run, rival=rival, cache=cache):
            key = x.tobytes()
            if key not in cache:
                run.values = {**rival.values, **dict(zip(rival.names, map(float, x)))}
                cache.clear()
                cache[key] = run.record(r.drive.scale)
            return cache[key]

        def residual(x, data=data):
            return ((record(x).outputs - data) / sigma).ravel()

        def jacobian(x):
            J = record(x).jacobian / sigma[:, :, None]
            return J.reshape(-1, J.shape[-1])

        sol = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac",
                            max_nfev=40)
        lack[rival.label] = float(2 * sol.cost)
    return replace(r, lack_of_fit=lack, linearised=dict(r.lack_of_fit))


@dataclass(frozen=True)
class Discrimination:
    """The drive that best tells the two ``rivals`` apart (of the design ``problem``), the
    best of every family ``ranked``, the ``evaluations`` of the search and its ``seconds``."""

    problem: DesignProblem
    rivals: tuple[Rival, Rival]
    ranked: tuple[Rivalry, ...]
    evaluations: int
    seconds: float

    @property
    def recommended(self) -> Rivalry:
        return self.ranked[0]

    def _text(self, r: Rivalry) -> str:
        return ", ".join(f"`{k}` model left with chi-square {v:.3g}"
                         + ("" if k in r.counted else " (it contains the other)")
                         for k, v in r.lack_of_fit.items())

    def summary(self) -> str:
        rec = self.recommended
        lines = [f"to tell `{self.rivals[0].spec}` ({self.rivals[0].label}) from "
                 f"`{self.rivals[1].spec}` ({self.rivals[1].label}): {rec.drive.describe()} "
                 f"for {self.problem.duration:g} s (amplitude limited by {rec.limited_by}; peak "
                 f"swing {rec.swing:.3f} rad)", f"  if the other is true: {self._text(rec)}"]
        lines += [f"  instead: {r.label}: {r.drive.describe()}: {self._text(r)}"
                  for r in self.ranked[1:]]
        return "\n".join(lines)

    def warnings(self) -> list[str]:
        worst = -self.recommended.score
        if worst >= SEPARATION:
            return []
        return [f"even the best drive leaves the wrong model a chi-square of only {worst:.3g} "
                f"(< {SEPARATION:g}, five standard deviations): one record of "
                f"{self.problem.duration:g} s on this rig cannot tell the two models apart "
                "reliably; their outputs differ by less than the noise under every drive "
                "within the limits and the swing limit"]

    def to_dict(self, drive_file: str | None = None) -> dict[str, Any]:
        """The JSON form of ``slosh design --discriminate --json``; ``drive_file`` names the
        drive CSV written beside it (None: none)."""

        def entry(r: Rivalry) -> dict[str, Any]:
            pk = r.drive.peaks(self.problem.rate)
            return {"label": r.label, "family": r.drive.family, "description": r.drive.describe(),
                    "variables": r.drive.values, "scale": r.drive.scale,
                    "limited_by": r.limited_by, "peak_swing_rad": r.swing,
                    "lack_of_fit_chi2": dict(r.lack_of_fit),
                    "linearised_lack_of_fit_chi2": r.linearised,
                    "counted": list(r.counted),
                    "limit_ratios": pk.ratios(self.problem.limits)}

        return {"case": str(self.problem.case.path), "rig": self.problem.case.test.rig,
                "models": {r.label: r.spec for r in self.rivals},
                "separation_chi2": SEPARATION, "duration_s": self.problem.duration,
                "sample_rate_hz": self.problem.rate, "max_swing_rad": self.problem.max_swing,
                "recommended": entry(self.recommended),
                "finalists": [entry(r) for r in self.ranked], "drive_file": drive_file,
                "warnings": self.warnings(), "notes": list(self.problem.notes),
                "evaluations": self.evaluations, "seconds": self.seconds}

    def write_drive(self, path: Path) -> None:
        """Write the recommended drive's table as CSV to ``path``."""
        write_drive(path, *drive_table(self.problem, self.recommended.drive))

    def plot(self, path: Path) -> None:
        """Both models' predicted records at the recommended drive, as a PNG at ``path``."""
        from .._plotting import figure, save

        p, rec = self.problem, self.recommended
        runs = [Runner(p, rec.drive, derived=r.derived, values=r.values, names=r.names)
                for r in self.rivals]
        recs = [run.record(rec.drive.scale) for run in runs]
        fig = figure(path, figsize=(9, 6))
        ax1, ax2 = fig.subplots(2, 1, sharex=True)
        t = p.time
        ax1.plot(t, 1e3 * rec.drive.motion(t)[0], lw=0.8)
        ax1.set_ylabel("carriage displacement [mm]")
        ax1.set_title(f"to tell them apart: {rec.drive.describe()}", fontsize=9)
        for c, name in enumerate(p.channels):
            ax2.plot(t, (recs[1].outputs[c] - recs[0].outputs[c]), lw=0.7,
                     label=f"{name}: {self.rivals[1].label} - {self.rivals[0].label}")
        for sd in (p.noise[0], -p.noise[0]):
            ax2.axhline(sd, color="0.5", ls=":", lw=0.8)
        ax2.set_ylabel("predicted difference [N]\n(noise level dotted)")
        ax2.set_xlabel("time [s]")
        ax2.legend(fontsize=8)
        save(fig, path)


def discrimination(diagnosis: str | Path, case: Case, *, fit: str | Path,
                   duration: float | None = None, max_swing: float = MAX_SWING,
                   families: tuple[str, ...] | None = None) -> Discrimination:
    """Search the lateral drives for the one that best tells the baseline and final models
    of ``diagnosis`` apart on ``case``'s rig; the noise levels come from the fit ``fit``
    (the JSON of ``slosh fit``) of the records run so far. ``duration`` (s, default the
    rig's longest record), ``max_swing`` (rad) and ``families`` (default every lateral
    one) are those of :meth:`DesignProblem.build` and the search."""
    if case.test.rig != "lateral":
        raise InputError(f"{case.path}: discrimination is implemented for the lateral rig; "
                         "on the spinning rig use `--target`")
    t0 = time.perf_counter()
    problem = DesignProblem.build(fit, case, duration=duration, max_swing=max_swing)
    rivals = rivals_from_diagnosis(diagnosis, case)
    lo, hi = band(problem)
    counter = [0]
    found = []
    for name in families or tuple(LATERAL_FAMILIES):
        if name not in LATERAL_FAMILIES:
            raise InputError(f"--families: unknown {name!r}; known: " + ", ".join(LATERAL_FAMILIES))
        fam = LATERAL_FAMILIES[name]

        def score(problem, drive, *, label=""):
            return _score(problem, rivals, drive, label=label)

        c = family_search(problem, fam, [(lo, hi)] * len(fam.variables), counter, score=score)
        if c is not None:
            found.append(c)
    if not found:
        raise InputError("no drive keeps both models' swing below the swing limit "
                         f"{max_swing:g} rad on this rig")
    judged = sorted((_refit(problem, rivals, r) for r in found), key=lambda r: r.score)
    return Discrimination(problem, rivals, tuple(judged), counter[0], time.perf_counter() - t0)

