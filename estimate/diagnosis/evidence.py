"""What a fit gets wrong, as numbers: residual spectrum peaks (with their coherence with the
excitation), drive harmonics, whiteness, timing skew, amplitude dependence of damping,
frequency against the tank prediction, estimates pinned at bounds, and the noise floor."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import signal
from scipy.stats import chi2

from ..data.signals import drive_frequency, find_spectral_peaks
from ..fitting.result import FitResult
from .scoring import ResidualOverNoise, noise_figure

__all__ = ["Evidence", "ResidualPeak", "SegmentDamping", "Trend", "amplitude_trend",
           "collect_evidence", "SIGNIFICANT_T"]

#: Residual peaks weaker than this fraction of the force amplitude are ignored.
PEAK_FLOOR = 0.003
#: Relative tolerance for calling a frequency a harmonic of the drive.
HARMONIC_TOL = 0.03
#: A :class:`Trend` whose slope is fewer standard errors than this from zero is no trend:
#: its text says so, and the families' evidence leaves it out.
SIGNIFICANT_T = 2.0


@dataclass(frozen=True)
class ResidualPeak:
    """A residual spectral peak: frequency (Hz), amplitude (N), coherence with the carriage
    acceleration (0..1) and the drive harmonic it sits on (0 when none)."""

    frequency: float
    amplitude: float
    coherence: float
    harmonic: int


@dataclass(frozen=True)
class SegmentDamping:
    """Damping ratio and frequency of ``p1`` refitted on one time segment, with their
    standard errors, the RMS swing angle (rad) and the RMS force (N) of that segment."""

    start: float
    stop: float
    rms_angle: float
    rms_force: float
    damping_ratio: float
    frequency_hz: float
    damping_se: float = math.nan
    frequency_se: float = math.nan


@dataclass(frozen=True)
class Trend:
    """How a segment quantity changes with the swing amplitude: the weighted straight line
    through ``(amplitude, value)`` (amplitude in rad), its value at the smallest and largest
    segment amplitude, and the slope in standard errors (``t``; |t| > 3 is a trend)."""

    quantity: str
    amplitudes: tuple[float, float]
    values: tuple[float, float]
    slope: float
    slope_se: float

    @property
    def t(self) -> float:
        return self.slope / self.slope_se if self.slope_se > 0 else 0.0

    @property
    def ratio(self) -> float:
        """Value at the largest amplitude over the value at the smallest."""
        return self.values[1] / self.values[0] if self.values[0] else math.nan

    def text(self) -> str:
        """``"damping ratio falls x0.50 from 0.1 rad to 0.35 rad swing (slope 6.2 standard
        errors)"``, ``"frequency falls 1.2 % from ..."``. A slope within
        :data:`SIGNIFICANT_T` standard errors of zero is no trend: ``"frequency: no significant
        change (-0.0082 %) from ..."``, never a "falls -0.0 %" or a "falls x1.00"."""
        span = (f"from {self.amplitudes[0]:.2g} rad to {self.amplitudes[1]:.2g} rad swing "
                f"(slope {abs(self.t):.1f} standard errors)")
        pct = 100 * (self.ratio - 1)
        factor = self.quantity != "frequency" and abs(pct) >= 5  # damping: x0.50, x2.0
        if abs(self.t) < SIGNIFICANT_T:
            size = (f"x{self.ratio:.2f}" if factor else f"{pct:+.2g} %") if math.isfinite(pct) else ""
            return f"{self.quantity}: no significant change{f' ({size})' if size else ''} {span}"
        moves = "rises" if self.slope > 0 else "falls"
        size = ((f"x{self.ratio:.2f} " if factor else f"{abs(pct):.2g} % ")
                if math.isfinite(pct) else "")
        return f"{self.quantity} {moves} {size}{span}"


def amplitude_trend(segments: tuple[SegmentDamping, ...], quantity: str) -> Trend | None:
    """The trend of ``"damping ratio"`` or ``"frequency"`` with the swing amplitude over
    ``segments`` (at least three with finite values and standard errors), or ``None``."""
    if quantity == "frequency":
        rows = [(s.rms_angle, s.frequency_hz, s.frequency_se) for s in segments]
    else:
        rows = [(s.rms_angle, s.damping_ratio, s.damping_se) for s in segments]
    rows = [(math.sqrt(2) * a, v, e) for a, v, e in rows
            if all(map(math.isfinite, (a, v, e))) and e > 0 and v > 0]
    if len(rows) < 3:
        return None
    a, v, e = (np.array(x) for x in zip(*rows))
    if np.ptp(a) <= 0.1 * np.max(a):
        return None  # the swing hardly changes: no amplitude dependence to read
    A = np.column_stack([np.ones_like(a), a]) / e[:, None]
    coef, *_ = np.linalg.lstsq(A, v / e, rcond=None)
    cov = np.linalg.inv(A.T @ A)
    # the straight line's own scatter: a poor line widens the slope's error
    chi2_red = float(np.sum((A @ coef - v / e) ** 2)) / max(len(rows) - 2, 1)
    se = math.sqrt(cov[1, 1] * max(chi2_red, 1.0))
    lo, hi = float(a.min()), float(a.max())
    return Trend(quantity, (lo, hi), (float(coef[0] + coef[1] * lo), float(coef[0] + coef[1] * hi)),
                 float(coef[1]), se)


@dataclass(frozen=True)
class Evidence:
    """Numbers describing a fit's residual (see the module docstring): ``rms_residual`` on
    the fitted samples (N, or channel scales) and ``noise``, the residual over the
    measurement noise (:func:`~estimate.diagnosis.scoring.noise_figure`)."""

    rms_residual: float
    noise: ResidualOverNoise
    drive_frequency: float | None
    sweep: bool
    peaks: tuple[ResidualPeak, ...]
    harmonics: dict[int, float]
    ljung_box_q: float
    ljung_box_p: float
    skew_correlation: float
    skew_delay: float
    frequency_ratio: float | None
    pinned: tuple[str, ...]
    segments: tuple[SegmentDamping, ...] = field(default=())
    #: Multi-channel cases: each channel's share of the scaled residual power (sums to 1).
    channel_share: dict[str, float] = field(default_factory=dict)
    #: Where the residual concentrates: frequencies (Hz) of its strongest spectral peaks.
    residual_frequencies: tuple[float, ...] = ()

    @property
    def noise_rms(self) -> float:
        """The measurement noise the residual is compared with (:attr:`noise`)."""
        return self.noise.noise

    @property
    def noise_ratio(self) -> float:
        """The residual over the measurement noise (:attr:`noise`)."""
        return self.noise.ratio

    @property
    def within_noise(self) -> bool:
        """The residual is within the noise (:attr:`noise`)."""
        return self.noise.within

    def against(self, other: ResidualOverNoise) -> "Evidence":
        """This evidence measured against the noise of ``other`` (another fit of the same
        record, in the same unit): a diagnosis states every fit of a record against one
        figure, its final model's (a wrong baseline's residual holds its error, and a figure
        read from it would be too high)."""
        if other.unit != self.noise.unit or not math.isfinite(other.noise) or other.noise <= 0:
            return self
        return replace(self, noise=replace(self.noise, noise=other.noise, how=other.how))

    @property
    def damping_trend(self) -> Trend | None:
        """Damping ratio against the swing amplitude (see :func:`amplitude_trend`)."""
        return amplitude_trend(self.segments, "damping ratio")

    @property
    def frequency_trend(self) -> Trend | None:
        """Frequency against the swing amplitude (see :func:`amplitude_trend`)."""
        return amplitude_trend(self.segments, "frequency")

    @property
    def damping_spread(self) -> float:
        """Ratio of the largest to the smallest segment damping ratio (1 when flat)."""
        z = [s.damping_ratio for s in self.segments if s.damping_ratio > 0]
        return max(z) / min(z) if len(z) >= 2 else 1.0

    @property
    def damping_amplitude_correlation(self) -> float:
        """Correlation between segment swing amplitude and segment damping ratio."""
        if len(self.segments) < 3:
            return 0.0
        a = np.array([s.rms_angle for s in self.segments])
        z = np.array([s.damping_ratio for s in self.segments])
        if np.std(a) == 0 or np.std(z) == 0:
            return 0.0
        return float(np.corrcoef(a, z)[0, 1])

    def unexplained_peaks(self) -> tuple[ResidualPeak, ...]:
        """Peaks that are not drive harmonics, strongest first."""
        return tuple(p for p in self.peaks if p.harmonic == 0)


def _ljung_box(r: np.ndarray, lags: int = 20) -> tuple[float, float]:
    r = r - r.mean()
    n = r.size
    denom = float(r @ r)
    if denom == 0:
        return 0.0, 1.0
    rho = np.array([float(r[:-k] @ r[k:]) / denom for k in range(1, lags + 1)])
    q = n * (n + 2) * float(np.sum(rho**2 / (n - np.arange(1, lags + 1))))
    return q, float(chi2.sf(q, lags))


def collect_evidence(result: FitResult, *, case: int = 0, segments: tuple[SegmentDamping, ...] = ()
                     ) -> Evidence:
    """Residual evidence of ``result`` for one case (segments computed separately).

    For a multi-channel case (spinning rig) the residual and noise are in channel-scale
    units and the evidence that reads the carriage input (peak coherence, drive harmonics,
    timing skew) is left empty; ``channel_share`` says where the residual is."""
    if result.channels and len(result.channels[case]) > 1:
        return _multichannel_evidence(result, case)
    problem = result.problem
    exp = problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    res = result.residuals[case]
    meas = result.measured[case]
    w = result.weights[case] if result.weights else np.ones_like(res)
    keep = w > 0
    acc = result.drive_acceleration(case)
    drive, sweep = drive_frequency(t, acc) if acc is not None else (None, False)
    amp = float(np.sqrt(2) * np.std(meas))
    peaks = []
    rr = np.where(keep, res, 0.0)
    for pk in find_spectral_peaks(t, rr, min_frequency=0.3, max_frequency=problem.force_cutoff_hz or 20.0,
                                  min_relative_height=1e-3, max_peaks=6):
        if pk.amplitude < PEAK_FLOOR * amp:
            continue
        harmonic = 0
        if drive and not sweep:
            k = round(pk.frequency / drive)
            if k >= 1 and abs(pk.frequency - k * drive) <= HARMONIC_TOL * k * drive:
                harmonic = k
        coh = 0.0
        if acc is not None:
            f, c = signal.coherence(acc, rr, fs=1 / float(np.median(np.diff(t))),
                                    nperseg=min(512, t.size // 4))
            coh = float(np.interp(pk.frequency, f, c))
        peaks.append(ResidualPeak(pk.frequency, pk.amplitude, coh, harmonic))
    harmonics: dict[int, float] = {}
    if drive and not sweep:
        for k in (2, 3):
            fk = k * drive
            if fk < (problem.force_cutoff_hz or 1e9):
                design = np.column_stack([np.cos(2 * np.pi * fk * t), np.sin(2 * np.pi * fk * t)])[keep]
                coef, *_ = np.linalg.lstsq(design, res[keep], rcond=None)
                harmonics[k] = float(np.hypot(*coef))
    q, pval = _ljung_box(res[keep])
    dF = np.gradient(meas, t)
    dk = dF[keep]
    corr = float(np.corrcoef(res[keep], dk)[0, 1]) if np.std(dk) > 0 and np.std(res[keep]) > 0 else 0.0
    delay = float(res[keep] @ dk / (dk @ dk)) if dk @ dk > 0 else 0.0
    ratio = None
    fhat = result.derived.get("p1.frequency_hz")
    pred = exp.case.prediction
    if fhat is not None and pred is not None:
        f_pred = math.sqrt(exp.case.rig.gravity / pred.pendulum_length) / (2 * math.pi)
        ratio = fhat[0] / f_pred
    pinned = tuple(wn.split("`")[1] for wn in result.warnings if "at its bound" in wn)
    rms = float(np.sqrt(np.mean(res[keep] ** 2)))
    return Evidence(
        rms_residual=rms, noise=noise_figure(result, case),
        drive_frequency=drive, sweep=sweep, peaks=tuple(peaks), harmonics=harmonics,
        ljung_box_q=q, ljung_box_p=pval, skew_correlation=corr, skew_delay=delay,
        frequency_ratio=ratio, pinned=pinned, segments=segments,
        residual_frequencies=tuple(p.frequency for p in peaks[:3]))


def _multichannel_evidence(result: FitResult, case: int) -> Evidence:
    problem = result.problem
    exp = problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    chans = result.channels[case]
    w = result.weights[case] if result.weights else np.ones(t.size)
    keep = w > 0
    scaled = result.scaled_residuals(case).reshape(t.size, -1)
    r = scaled[keep]
    power = np.sum(r**2, axis=0)
    total = float(power.sum()) or 1.0
    q, pval = _ljung_box(r[:, int(np.argmax(power))])
    pinned = tuple(wn.split("`")[1] for wn in result.warnings if "at its bound" in wn)
    return Evidence(
        rms_residual=float(np.sqrt(np.mean(r**2))), noise=noise_figure(result, case),
        drive_frequency=None, sweep=False, peaks=(), harmonics={}, ljung_box_q=q,
        ljung_box_p=pval, skew_correlation=0.0, skew_delay=0.0, frequency_ratio=None,
        pinned=pinned, channel_share={c: float(p / total) for c, p in zip(chans, power)},
        residual_frequencies=_channel_lines(t, np.where(keep[:, None], scaled, 0.0)))


#: A spectral line of one channel's scaled residual counts where the residual concentrates
#: when its amplitude is at least this fraction of that channel's RMS residual.
LINE_SHARE = 0.3


def _channel_lines(t: np.ndarray, r: np.ndarray) -> tuple[float, ...]:
    """The frequencies (Hz) of the strongest spectral lines of a multi-channel scaled
    residual ``r`` (samples x channels), at most three, strongest (summed over the channels
    it is on, within 2 %) first."""
    fs = 1.0 / float(np.median(np.diff(t)))
    lines: list[list[float]] = []  # [frequency, summed squared amplitude]
    for k in range(r.shape[1]):
        rms = float(np.sqrt(np.mean(r[:, k] ** 2)))
        if rms == 0.0:
            continue
        for pk in find_spectral_peaks(t, r[:, k], min_frequency=0.3, max_frequency=0.45 * fs,
                                      min_relative_height=1e-2, max_peaks=4):
            if pk.amplitude < LINE_SHARE * rms:
                continue
            same = next((ln for ln in lines if abs(ln[0] - pk.frequency) <= 0.02 * ln[0]), None)
            if same is None:
                lines.append([pk.frequency, pk.amplitude**2])
            else:
                same[1] += pk.amplitude**2
    lines.sort(key=lambda ln: -ln[1])
    return tuple(float(f) for f, _ in lines[:3])


#: IPOPT iterations of a segment refit: two parameters and the segment's initial state
#: converge in 7-12; with a second mode held in the model two of four segments of a
#: 30 s record ran IPOPT's default 300 (6 s) without converging.
SEGMENT_ITERATIONS = 60


def segment_damping(result: FitResult, *, case: int = 0, n_segments: int = 4,
                    skip: float = 2.0) -> tuple[SegmentDamping, ...]:
    """Refit ``p1``'s damping and length on each of ``n_segments`` time segments (other
    parameters held at the estimates, the segment's initial state free) and report the
    damping ratio and frequency, with their standard errors, against the segment's swing
    amplitude (the RMS of the fitted angle). A segment whose refit does not converge in
    :data:`SEGMENT_ITERATIONS` is left out.

    The segments share the record after its first ``skip`` seconds (at most a tenth of it):
    a start-up ramp is not a steady swing. They are fitted with the filtered input (fast;
    the start-up, where filtering errs, is left out)."""
    from ..fitting.nlp import fit
    from ..fitting.problem import FitProblem

    problem = result.problem
    exp = problem.experiments[case]
    names = set(result.names)
    if exp.case.test.rig != "lateral" or exp.case.force is None \
            or not {"p1.damping", "p1.length"} <= names:
        return ()  # the spinning rig's and six-axis records: their families read no trend
    values = problem.case_values(case, result.values)
    coords = exp.derived.coordinates
    theta = (result.states[case][coords.index("p1.theta")]
             if result.states and "p1.theta" in coords else None)
    c = exp.case
    start = int(np.searchsorted(c.time, c.time[0] + min(skip, 0.1 * (c.time[-1] - c.time[0]))))
    edges = np.linspace(start, c.time.size - 1, n_segments + 1).astype(int)
    out = []
    hold = {k: v for k, v in values.items() if k not in ("p1.damping", "p1.length")
            and k in result.problem.experiments[case].derived.needed_parameters()}
    for a, b in zip(edges[:-1], edges[1:]):
        seg = replace(c, time=c.time[a:b + 1] - c.time[a], force=c.force[a:b + 1],
                      displacement=None if c.displacement is None else c.displacement[a:b + 1])
        try:
            sub = FitProblem.build(seg, problem.model, estimate=["p1.damping", "p1.length"],
                                   hold=hold, initial={"p1.damping": values["p1.damping"],
                                                       "p1.length": values["p1.length"]},
                                   bounds={"p1.length": (0.5 * values["p1.length"],
                                                         2.0 * values["p1.length"])},
                                   input="filtered", first_stage=False)  # starts given
            r = fit(sub, initial_state="free", progress=False, robust_start=False,
                    solver_options={"ipopt.max_iter": SEGMENT_ITERATIONS})
        except (ValueError, RuntimeError):
            continue
        if not r.converged:
            continue  # its damping and frequency are wherever the budget stopped it
        zeta, zeta_se = r.derived.get("p1.damping_ratio", (math.nan, math.nan))
        fz, fz_se = r.derived.get("p1.frequency_hz", (math.nan, math.nan))
        swing = float(np.sqrt(np.mean(theta[a:b + 1] ** 2))) if theta is not None else math.nan
        out.append(SegmentDamping(float(c.time[a]), float(c.time[b]), swing,
                                  float(np.sqrt(np.mean(c.force[a:b + 1] ** 2))), float(zeta),
                                  float(fz), float(zeta_se), float(fz_se)))
    return tuple(out)
