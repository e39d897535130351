"""What a design starts from: the fit so far (its estimates, covariance and noise), the rig
(its case file and ``[rig.limits]``), the parameters to pin down and how."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from analogs import Model
from analogs.errors import InputError, UnknownNameError
from derive import DerivedModel, derive

from ..data.case import Case, Limits
from ..data.models import model_for_case, model_from_spec, rig_values
from ..fitting.record import read_fit
from .information import prior_information

__all__ = ["DesignProblem", "CRITERIA", "GOAL", "LINEAR_SWING", "MAX_DESIGN_RATE", "MAX_SWING",
           "required_limits", "with_spin"]

#: Optimality criteria on the targets' covariance: D (volume) and A (sum of variances).
CRITERIA = ("D", "A")
#: Swing (rad) up to which a pendulum analog is linear to 0.25 % in frequency (theta^2/16).
LINEAR_SWING = 0.2
#: Default largest predicted swing (rad) of a recommended drive: pendulum analogs of real
#: tanks reach 0.2-0.4 rad near resonance; beyond, the liquid surface breaks.
MAX_SWING = 0.35
#: Highest rate of the predicted records [Hz]: a faster rig's record is predicted on a grid
#: decimated to it, each sample standing for the k it replaces (noise / sqrt(k)). Slosh
#: dynamics live below ~10 Hz; the information of white-noise samples adds up.
MAX_DESIGN_RATE = 200.0
#: Default goal: a 95 % interval within +/-5 % of the value.
GOAL = 0.05
#: Correlation above which two estimates count as confounded (the default targets).
CONFOUNDED = 0.9

_LIMIT_KEYS = {"lateral": ("stroke", "velocity", "acceleration", "duration"),
               "spinning": ("spin_rate", "nutation_frequency", "cone_angle", "duration")}


def required_limits(case: Case) -> Limits:
    """The ``[rig.limits]`` of ``case`` with every key a design on its rig needs, or an error
    naming the file, the table and the keys missing."""
    keys = _LIMIT_KEYS[case.test.rig]
    limits = case.rig.limits
    missing = [k for k in keys if limits is None or getattr(limits, k) is None]
    if missing:
        example = {"stroke": "0.1` (m, total carriage travel)", "velocity": "0.5` (m/s)",
                   "acceleration": "5.0` (m/s^2)", "duration": "60.0` (s, longest record)",
                   "spin_rate": "10.0` (rad/s)", "nutation_frequency": "1.0` (Hz)",
                   "cone_angle": "0.1` (rad, cone half-angle)"}
        what = "has no `[rig.limits]` table" if limits is None else \
            "`[rig.limits]` lacks " + ", ".join(f"`{k}`" for k in missing)
        raise InputError(f"{case.path}: {what}; a design keeps every drive within what the "
                         f"{case.test.rig} rig can run: give "
                         + ", ".join(f"`{k} = {example[k]}" for k in missing)
                         + " in `[rig.limits]`")
    return limits


@dataclass(frozen=True)
class DesignProblem:
    """The known state and the question of a design.

    ``values`` are every parameter value of the design case's model (estimates of the fit
    over the rig values of the case), ``names`` the estimated (shared) parameters, ``prior``
    their information from the records already run (per unit of each) and ``scales`` their
    current standard errors; ``noise`` the white noise per measured channel of the fitted
    record and ``rms`` that record's RMS per channel (the noise of a new record grows with
    its RMS, never below ``noise``); ``displacement_noise`` (m) that of the carriage
    displacement (lateral rig).

    ``case``, ``model`` and its ``derived`` form are those of the next record;
    ``limits`` the rig's (``[rig.limits]``); ``targets`` the parameters the design is for,
    scored by ``criterion`` (``"D"`` or ``"A"``); ``channels`` the measured channels;
    ``duration`` (s) and ``rate`` (Hz) the record's; ``max_swing`` the largest predicted
    swing (rad); ``frequencies`` the fitted modes' (Hz, by component); ``goal`` the relative
    interval half-width asked for; ``fit_path`` the fit read; ``notes`` what building said.
    """

    case: Case
    model: Model
    derived: DerivedModel = field(repr=False)
    limits: Limits
    names: tuple[str, ...]
    values: Mapping[str, float] = field(repr=False)
    prior: np.ndarray = field(repr=False)
    scales: np.ndarray = field(repr=False)
    targets: tuple[str, ...]
    criterion: str
    channels: tuple[str, ...]
    noise: np.ndarray
    rms: np.ndarray
    displacement_noise: float | None
    duration: float
    rate: float
    max_swing: float
    frequencies: Mapping[str, float]
    goal: float = 0.05
    #: SI unit of each estimated parameter (from the fit).
    units: Mapping[str, str] = field(default_factory=dict)
    fit_path: Path | None = None
    notes: tuple[str, ...] = ()

    @classmethod
    def build(cls, fit_path: str | Path, case: Case, *, targets: Sequence[str] | None = None,
              criterion: str = "D", duration: float | None = None,
              max_swing: float = MAX_SWING, goal: float = GOAL) -> "DesignProblem":
        """Read the fit (the JSON of ``slosh fit``) and set up the design of the next record
        on ``case``'s rig.

        Parameters
        ----------
        fit_path : path
            The fit of the records run so far (``slosh fit --json``).
        case : Case
            The rig's case file with ``[rig.limits]`` (and a record: its sampling rate and
            force level are those of the next record).
        targets : sequence of str, optional
            Estimated parameters to pin down; default: those the fit leaves confounded
            (|correlation| >= 0.9 with another), else all.
        criterion : {"D", "A"}
            D-optimal (smallest joint confidence region of the targets) or A-optimal
            (smallest sum of their relative variances).
        duration : float, optional
            Rig time of the next record (s); default and largest: ``[rig.limits] duration``.
        max_swing : float
            Largest predicted swing of any pendulum (rad): drives are scaled down to it.
        goal : float
            The 95 % half-width (over the value) a target must reach to count as pinned
            down; the report says why a target misses it.
        """
        if criterion not in CRITERIA:
            raise InputError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")
        if not (0 < goal):
            raise InputError(f"goal must be a positive fraction, got {goal!r}")
        if not (0 < max_swing < math.pi / 2):
            raise InputError(f"max swing must be in (0, pi/2) rad, got {max_swing!r}")
        if case.test.rig == "lateral" and case.test.excitation != "measured":
            raise InputError(f"{case.path}: `[test] excitation = \"{case.test.excitation}\"`: the "
                             "design plans carriage motions for a servo-driven rig (excitation "
                             "= \"measured\"); a crank rig runs one near-sine per crank setting")
        limits = required_limits(case)
        if duration is None:
            duration = limits.duration
        if not (0 < duration <= limits.duration):
            raise InputError(f"--budget {duration:g} s: the rig runs records of at most "
                             f"{limits.duration:g} s (`[rig.limits] duration` of {case.path})")
        fit = read_fit(fit_path)
        raw = fit.data
        model = model_for_case(model_from_spec(fit.model_spec, case), case)
        dm = derive(model)
        names = tuple(n for n in fit.estimated if ":" not in n and n in dm.parameter_names)
        if not names:
            raise InputError(f"{fit_path}: no estimated parameter of the model "
                             f"{fit.model_spec!r} to design for")
        values = {k: v for k, v in fit.values.items() if ":" not in k}
        values |= rig_values(case)
        values = {k: v for k, v in values.items() if k in dm.parameter_names}
        prior, se = prior_information(list(names), fit.covariance_names, fit.covariance)
        theta = np.array([values[n] for n in names])
        scales = np.where(np.isfinite(se), se, np.where(theta != 0, np.abs(theta), 1.0))
        targets = _targets(targets, names, fit, fit_path)
        channels = tuple(c for c in dm.measured if c in case.channels)
        # the rig's rate from the record's median step, to 9 digits (100.00000000000213 is
        # 100 Hz), before any [test] decimate
        rate = limits.sample_rate or float(f"{case.recorded_rate:.9g}")
        noise, rms, sx, notes = _noise(raw, fit_path, case, channels, model, values, rate)
        freqs = {k.split(".")[0]: float(v) for k, v in (raw.get("derived") or {}).items()
                 if k.endswith(".frequency_hz") and isinstance(v, (int, float))}
        return cls(case, model, dm, limits, names, values, prior, scales, targets, criterion,
                   channels, noise, rms, sx, float(duration), float(rate), float(max_swing),
                   freqs, float(goal), {n: fit.units.get(n, "") for n in names},
                   Path(fit_path), tuple(notes))

    @property
    def decimation(self) -> int:
        """Rig samples per sample of the predicted record (1 up to :data:`MAX_DESIGN_RATE`)."""
        return max(1, math.ceil(self.rate / MAX_DESIGN_RATE - 1e-9))

    @property
    def time(self) -> np.ndarray:
        """Sample times of the predicted record (s): the rig's rate, decimated to at most
        :data:`MAX_DESIGN_RATE`."""
        rate = self.rate / self.decimation
        n = int(math.floor(self.duration * rate + 1e-9))
        return np.arange(n + 1) / rate

    @property
    def rig_time(self) -> np.ndarray:
        """Sample times of the drive file (s), at the rig's rate."""
        n = int(math.floor(self.duration * self.rate + 1e-9))
        return np.arange(n + 1) / self.rate

    @property
    def record_displacement_noise(self) -> float | None:
        """Displacement noise of a sample of the predicted record (m)."""
        if self.displacement_noise is None:
            return None
        return self.displacement_noise / math.sqrt(self.decimation)

    @property
    def theta(self) -> np.ndarray:
        return np.array([self.values[n] for n in self.names])

    def new_noise(self, rms: np.ndarray) -> np.ndarray:
        """White noise per channel of a sample of the predicted record whose outputs have RMS
        ``rms``: the fitted record's level, growing in proportion with the RMS above that
        record's (a transducer's noise has a floor, and rig vibration grows with the
        drive), over the square root of :attr:`decimation`."""
        return (self.noise * np.maximum(1.0, np.asarray(rms) / self.rms)
                / math.sqrt(self.decimation))


def _targets(targets, names, fit, fit_path) -> tuple[str, ...]:
    if targets:
        unknown = [t for t in targets if t not in names]
        if unknown:
            raise UnknownNameError(f"--target: {', '.join(f'`{u}`' for u in unknown)} not "
                                   f"estimated by the fit {fit_path}; estimated: "
                                   + ", ".join(names))
        return tuple(dict.fromkeys(targets))
    cov_names = list(fit.covariance_names)
    C = fit.covariance
    d = np.sqrt(np.clip(np.diag(C), 1e-300, None))
    R = C / np.outer(d, d)
    out = [n for i, n in enumerate(cov_names) if n in names
           and any(abs(R[i, j]) >= CONFOUNDED for j in range(len(cov_names)) if j != i)]
    return tuple(out) or tuple(names)


def _noise(raw, fit_path, case: Case, channels, model, values, rate: float):
    """White noise per channel of a sample at the rig's ``rate`` (Hz), the fitted record's
    RMS per channel (from ``case``'s record) and the displacement noise, with notes saying
    where they come from. A fit record gives its noise per sample of the fitted record and
    (since it says so) that record's rate: a white noise's density is what carries over,
    so a sample at another rate has the noise times ``sqrt(rate / fitted rate)`` (a record
    fitted decimated by 5 has a fifth of the variance per sample)."""
    measured = np.array([case.channels[c] for c in channels], float)
    rms = np.sqrt(np.mean(measured**2, axis=1))
    entries = raw.get("noise") if isinstance(raw, dict) else None
    first = entries[0] if isinstance(entries, list) and entries else None
    if isinstance(first, dict) and isinstance(first.get("force_noise_N"), (int, float)):
        sx = first.get("displacement_noise_m")
        sx = float(sx) if isinstance(sx, (int, float)) else None
        fitted = first.get("sample_rate_hz")
        scale = (math.sqrt(rate / fitted) if isinstance(fitted, (int, float)) and fitted > 0
                 else 1.0)
        note = (f"noise of the fitted record: force {first['force_noise_N']:.3g} N"
                + (f", displacement {sx:.3g} m" if sx is not None else "") + f" ({fit_path})")
        if abs(scale - 1.0) > 1e-6:
            note += (f"; per sample at the rig's {rate:.6g} Hz from the fitted record's "
                     f"{fitted:.6g} Hz: times {scale:.3g} (a white noise's density kept)")
        return (np.array([float(first["force_noise_N"]) * scale]), rms,
                None if sx is None else sx * scale, [note])
    # no noise figure in the fit (spinning rig, filtered input): the residual of the fit on
    # this case's record, channel by channel
    from ..data.experiment import experiment

    exp = experiment(case, model)
    sim = exp.simulate({k: v for k, v in values.items() if k in exp.derived.parameter_names})
    resid = measured - np.array([sim.output(c) for c in channels])
    # per sample of this record; at the rig's rate as above (a decimated record)
    noise = np.sqrt(np.mean(resid**2, axis=1)) * math.sqrt(rate / case.sample_rate)
    return noise, rms, None, [
        "noise per channel: the RMS residual of the fitted model on " + str(case.path.name)
        + " (" + ", ".join(f"{c} {s:.3g}" for c, s in zip(channels, noise)) + ")"]


def with_spin(case: Case, **spin) -> Case:
    """``case`` with other ``[rig.spin]`` values (a planned spinning-rig test)."""
    return replace(case, rig=replace(case.rig, spin=replace(case.rig.spin, **spin)))
