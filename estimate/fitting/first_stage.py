"""The fit's first stage: a linear identification of the record that needs no good start.

Linearised, the lateral force of a rigid mass ``M`` and one slosh mode (mass ``m``, natural
frequency ``omega``, damping ratio ``zeta``) driven by the carriage acceleration ``a`` is

    F(t) = M a(t - tau) + m b(t - tau),
    B(s) / A(s) = (2 zeta omega s + omega^2) / (s^2 + 2 zeta omega s + omega^2)

(``b`` is the acceleration of the mode's bob; ``tau`` the lag of the force stream behind the
motion stream). For given ``(omega, zeta, tau)`` the force is linear in ``(M, m)`` and an
offset, so those follow by linear least squares (variable projection) and only the three
nonlinear parameters are searched, by SciPy's ``least_squares`` from a few starts: the
predicted frequency and the force spectrum's peaks around it, each with the lag where the
objective's profile over a grid is lowest. The best start is kept; starts that end in other
minima are reported with their spread. The acceleration is the least-squares spline through
the measured displacement (the estimated input's start, :mod:`estimate.fitting.carriage`) or
the filtered input; the mode's response is the exact discretisation of ``B/A`` for a
piecewise-linear acceleration (``scipy.signal.cont2discrete``, first-order hold) filtered
over the record (``scipy.signal.lfilter``), from rest.

The result starts the NLP (masses, length, hinge damping, the rigid mass of an unweighed
container, the stream lag) and decides whether the lag is identifiable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["FirstStage", "StartOutcome", "identify", "record_stage", "starting_values",
           "forget_stages", "LAG_RANGE", "LAG_IDENTIFIED"]

#: Lags searched [s]: the force stream up to 50 ms ahead of or 150 ms behind the motion.
LAG_RANGE = (-0.05, 0.15)
#: Step of the lag profile that starts each search [s].
LAG_GRID_STEP = 0.005
#: The lag is identifiable (estimated in the NLP) when the first stage determines it to this
#: standard error [s] or better: a 5 ms uncertainty moves a 3 Hz mode's phase by 5 degrees.
LAG_IDENTIFIED = 0.005
#: The first stage starts a fit only when its linear model explains this share of the
#: (low-passed) force: a record whose acceleration is mostly noise (a 0.2 mm sweep) does not.
MIN_EXPLAINED = 0.5
#: A first-stage slosh mass beyond this share of the liquid mass starts the NLP there.
BUDGET_SHARE = 0.9
#: Damping ratios searched.
ZETA_RANGE = (1e-4, 0.5)
#: Starting frequencies: the prediction and at most this many force-spectrum peaks within
#: FREQUENCY_BAND of it.
SPECTRAL_STARTS = 3
FREQUENCY_BAND = (0.3, 2.0)
#: Two starts disagree when their frequencies differ by more than this (relative) and the
#: worse one's objective is within SPREAD_CHI2 of the best (in units of the residual
#: variance): the data then do not prefer one clearly.
SPREAD_RELATIVE = 0.01
SPREAD_CHI2 = 25.0


@dataclass(frozen=True)
class StartOutcome:
    """Where one start of the search ended: frequency [Hz], damping ratio, lags [s] per
    record, rigid and slosh mass [kg], and the objective (sum of squared residuals over
    the residual variance of the best start)."""

    start_hz: float
    frequency_hz: float
    damping_ratio: float
    lags: tuple[float, ...]
    rigid_mass: float
    slosh_mass: float
    objective: float


@dataclass(frozen=True)
class FirstStage:
    """The linear identification of one or more records (shared mode and masses, a lag per
    record).

    Attributes
    ----------
    frequency_hz, damping_ratio : float
        The mode's natural frequency [Hz] and damping ratio.
    rigid_mass, slosh_mass : float
        ``M`` and ``m`` [kg] (the rigid mass includes every mass moving with the tank).
    lags, lag_stderr : tuple of float
        Per record, the force stream's lag behind the motion stream [s] and its standard
        error (Gauss-Newton, at the force noise when it is given: what the data
        determine).
    stderr : dict
        Standard errors of ``frequency_hz``, ``damping_ratio``, ``rigid_mass``,
        ``slosh_mass``.
    starts : tuple of StartOutcome
        Every start's outcome, best first.
    """

    frequency_hz: float
    damping_ratio: float
    rigid_mass: float
    slosh_mass: float
    lags: tuple[float, ...]
    lag_stderr: tuple[float, ...]
    stderr: dict = field(default_factory=dict)
    starts: tuple[StartOutcome, ...] = ()
    rms_residual: float = math.nan
    #: The swing amplitude of the linear mode [rad]; its frequency was softened back to
    #: the pendulum's small-swing one by the elliptic integral (NaN: not corrected).
    swing: float = math.nan
    #: Per record, the factor by which the other parameters inflate the lag's variance.
    lag_inflation: tuple[float, ...] = ()
    #: The share of the (low-passed) force's variance the linear model explains.
    explained: float = math.nan

    @property
    def failure(self) -> str | None:
        """Why the stage cannot start a fit (``None``: it can): the linear model explains
        under :data:`MIN_EXPLAINED` of the force, a rigid mass that is not positive, or a
        lag at the edge of the searched range."""
        if not self.explained >= MIN_EXPLAINED:
            return (f"the linear model explains {100 * self.explained:.0f} % of the force "
                    f"(needs {100 * MIN_EXPLAINED:.0f} %)")
        if not self.rigid_mass > 0:
            return f"its rigid mass {self.rigid_mass:.3g} kg is not positive"
        edge = [t for t in self.lags if not LAG_RANGE[0] + LAG_GRID_STEP < t
                < LAG_RANGE[1] - LAG_GRID_STEP]
        if edge:
            return f"its lag {1e3 * edge[0]:.1f} ms is at the edge of the searched range"
        return None

    @property
    def lag_identified(self) -> bool:
        """Whether every record's lag is determined to :data:`LAG_IDENTIFIED`."""
        return all(math.isfinite(s) and s <= LAG_IDENTIFIED for s in self.lag_stderr)

    @property
    def disagreeing(self) -> tuple[StartOutcome, ...]:
        """Starts that ended at another frequency with an objective close to the best's."""
        best = self.starts[0]
        return tuple(s for s in self.starts[1:]
                     if abs(s.frequency_hz / best.frequency_hz - 1) > SPREAD_RELATIVE
                     and s.objective - best.objective < SPREAD_CHI2)

    def to_dict(self) -> dict:
        """The JSON form (SI units): estimates, the lags, and every start's outcome."""
        return {"frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio,
                "rigid_mass": self.rigid_mass, "slosh_mass": self.slosh_mass,
                "lags_s": list(self.lags), "lag_stderr_s": list(self.lag_stderr),
                "lag_identified": self.lag_identified, "swing_rad": _finite(self.swing),
                "starts": [{"start_hz": s.start_hz, "frequency_hz": s.frequency_hz,
                            "damping_ratio": s.damping_ratio, "objective_increase": s.objective}
                           for s in self.starts],
                "starts_disagree": bool(self.disagreeing)}

    def describe(self) -> str:
        """One sentence for the fit's notes."""
        lag = ", ".join(f"{1e3 * t:.1f} +/- {1e3 * s:.1f} ms" for t, s in
                        zip(self.lags, self.lag_stderr))
        text = (f"first stage (linear identification, {len(self.starts)} starts): mode "
                f"{self.frequency_hz:.4g} Hz, damping ratio {self.damping_ratio:.3g}, slosh mass "
                f"{self.slosh_mass:.4g} kg, rigid mass {self.rigid_mass:.4g} kg, force stream lag "
                f"{lag}")
        if math.isfinite(self.swing):
            text += (f" (frequency corrected to small swings from the identified swing "
                     f"{self.swing:.2f} rad)")
        other = self.disagreeing
        if other:
            text += ("; starts disagree: " + ", ".join(
                f"{s.frequency_hz:.4g} Hz (objective +{s.objective - self.starts[0].objective:.1f})"
                for s in other) + " - the best is kept")
        return text


#: Both the acceleration and the force are low-passed (zero phase, the same filter, so the
#: linear relation holds) at this multiple of the highest starting frequency, at least
#: LOWPASS_MIN_HZ: an acceleration differentiated from a noisy displacement otherwise
#: carries noise that biases the masses low (errors in the regressor) and the lag.
LOWPASS_FACTOR = 3.0
LOWPASS_MIN_HZ = 6.0
#: Then decimated to about this many samples per period of the cutoff.
SAMPLES_PER_CUTOFF = 5.0


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class _Record:
    """One record for the first stage: decimated times [s], the (low-passed) acceleration
    as a function of time (m/s^2, callable on arrays), the low-passed force [N] at those
    times and the samples used (weights > 0)."""

    time: np.ndarray
    acceleration: object
    force: np.ndarray
    keep: np.ndarray
    #: The acceleration at the lagged times, by lag: the searches evaluate one lag for
    #: several frequencies and damping ratios (their finite differences)
    shifted: dict = field(default_factory=dict, repr=False, compare=False)

    def acceleration_at(self, lag: float) -> np.ndarray:
        """The acceleration at ``time - lag`` (held at its end values outside) [m/s^2]."""
        a = self.shifted.get(lag)
        if a is None:
            if len(self.shifted) > 128:
                self.shifted.clear()
            t = self.time
            a = np.asarray(self.acceleration(np.clip(t - lag, t[0], t[-1])), float)
            self.shifted[lag] = a
        return a


def _prepared(t, a, F, w, cutoff: float) -> _Record:
    """A record low-passed at ``cutoff`` (Hz) and decimated (see :data:`LOWPASS_FACTOR`)."""
    from scipy.interpolate import CubicSpline

    from ..data.signals import lowpass

    t = np.asarray(t, float)
    fs = 1.0 / float(np.median(np.diff(t)))
    acc = np.asarray(a(t), float)
    force = np.asarray(F, float)
    if cutoff < 0.4 * fs:
        acc, force = lowpass(t, acc, cutoff_hz=cutoff), lowpass(t, force, cutoff_hz=cutoff)
    step = max(int(fs / (SAMPLES_PER_CUTOFF * cutoff)), 1)
    keep = np.ones(t.size, bool) if w is None else np.asarray(w) > 0
    return _Record(t[::step], CubicSpline(t, acc), force[::step], keep[::step])


def identify(records, *, frequency_hz: float, gravity: float | None = None,
             noise=None, min_hz: float = 0.05) -> FirstStage | None:
    """Identify one slosh mode, the rigid mass and a lag per record.

    Parameters
    ----------
    records : sequence of (time, acceleration, force, weights)
        Uniform times [s]; the carriage acceleration as a callable ``a(times)`` (m/s^2)
        valid at any time of the record (it is held at its end values outside); the force
        [N]; sample weights (0 leaves a sample out) or ``None``.
    frequency_hz : float
        The predicted mode frequency [Hz]: the first start, and the centre of the band
        where the force spectrum's peaks give the others.
    gravity : float, optional
        Gravity [m/s^2]: the identified frequency is then corrected from the swing to the
        pendulum's small-swing frequency (a transport move swings it 0.5-1 rad, which
        softens it by 2-6 %: ``omega_0 = omega 2 K(sin^2(theta/2)) / pi``, ``K`` the
        complete elliptic integral); without it the mode is taken as linear.
    noise : sequence of float, optional
        Per record, the force noise [N]: the lags' standard errors (which decide whether
        the lag is identifiable) are then those the data allow at that noise, not those of
        the linear mode's misfit of large swings.
    min_hz : float
        Lowest frequency searched [Hz].

    Returns
    -------
    FirstStage or None
        ``None`` when the records hold no acceleration to identify anything from.
    """
    from scipy.optimize import least_squares
    from scipy.special import ellipk

    from ..data.signals import find_spectral_peaks

    records = list(records)
    if not records:
        return None
    t0, _, F0, _ = records[0]
    fs = 1.0 / float(np.median(np.diff(t0)))
    starts = [frequency_hz] if math.isfinite(frequency_hz) and frequency_hz > 0 else []
    lo, hi = (b * (frequency_hz if starts else 1.0) for b in FREQUENCY_BAND)
    try:
        peaks = find_spectral_peaks(t0, F0, min_frequency=max(lo, min_hz),
                                    max_frequency=min(hi, 0.25 * fs), max_peaks=SPECTRAL_STARTS,
                                    refine=False)
    except ValueError:
        peaks = ()
    starts += [p.frequency for p in peaks
               if all(abs(p.frequency / s - 1) > SPREAD_RELATIVE for s in starts)]
    if not starts:
        return None
    cutoff = max(LOWPASS_FACTOR * max(starts), LOWPASS_MIN_HZ)
    recs = [_prepared(t, a, F, w, cutoff) for t, a, F, w in records]
    if all(not np.any(np.abs(r.acceleration(r.time)) > 0) for r in recs):
        return None
    top_hz = min(0.25 * fs, 0.5 * cutoff)
    n = len(recs)
    lo = np.r_[math.log(2 * math.pi * min_hz), math.log(ZETA_RANGE[0]), [LAG_RANGE[0]] * n]
    hi = np.r_[math.log(2 * math.pi * top_hz), math.log(ZETA_RANGE[1]), [LAG_RANGE[1]] * n]
    x_scale = np.r_[0.05, 0.5, [0.005] * n]

    def search(x0):
        return least_squares(lambda x: _projected(recs, x)[0], x0, bounds=(lo, hi),
                             x_scale=x_scale, method="trf", xtol=1e-4, ftol=1e-6,
                             max_nfev=60)

    def search_without_lag(x0):
        # the mode alone, the streams taken as synchronous: a steady drive trades a free
        # lag for the mode's phase, and the data then prefer neither clearly
        sol = least_squares(lambda y: _projected(recs, np.r_[y, x0[2:]])[0], x0[:2],
                            bounds=(lo[:2], hi[:2]), x_scale=x_scale[:2], method="trf",
                            xtol=1e-4, ftol=1e-6, max_nfev=60)
        sol.x = np.r_[sol.x, x0[2:]]
        sol.jac = np.hstack([sol.jac, np.zeros((sol.jac.shape[0], n))])
        return sol

    outcomes = []
    for f0 in starts:  # the linear mode from every start: cheap, and no start is needed
        x0 = np.r_[math.log(2 * math.pi * f0), math.log(0.01), np.zeros(n)]
        for sol in (search_without_lag(x0), None):
            if sol is None:
                x0[2:] = _lag_profile(recs, x0)
                sol = search(x0)
            outcomes.append((float(2 * sol.cost), f0, sol))
    # the best physical outcome (positive masses, lags inside the range) first
    outcomes.sort(key=lambda o: (not _physical(recs, o[2].x), o[0]))
    best_cost, _, best = outcomes[0]
    r, beta = _projected(recs, best.x)
    F_all = _stacked(recs, best.x)[1]
    n_obs = r.size
    s2 = best_cost / max(n_obs - (2 + n + 3 * n), 1)
    J = best.jac
    if not np.any(J[:, 2:]):  # the lag was held: its sensitivity there, all free
        J = least_squares(lambda x: _projected(recs, x)[0], best.x, bounds=(lo, hi),
                          x_scale=x_scale, max_nfev=1).jac
    cov_x = s2 * np.linalg.pinv(J.T @ J)
    se_x = np.sqrt(np.clip(np.diag(cov_x), 0, None))
    info = J.T @ J
    # how much the other parameters inflate each lag's variance (1: none; a steady sine
    # trades its lag for the mode's phase)
    vif = np.diag(np.linalg.pinv(info))[2:] * np.diag(info)[2:]
    if noise is not None:
        # what the data determine, not how well a linear mode fits large swings: the
        # lags' standard errors at the force noise (low-passed as the records were)
        s2_noise = float(np.mean(np.square(noise))) * min(1.0, 2 * cutoff / fs)
        se_x[2:] = np.sqrt(np.clip(np.diag(s2_noise * np.linalg.pinv(J.T @ J))[2:], 0, None))
    omega, zeta = math.exp(best.x[0]), math.exp(best.x[1])
    swing = math.nan
    if gravity is not None:  # the linear mode is the pendulum at its swing: soften back
        swing = _swing(recs, best.x, gravity)
        if math.isfinite(swing):
            omega *= 2 * ellipk(math.sin(min(swing, 2.5) / 2) ** 2) / math.pi
    cov_beta = _beta_covariance(recs, best.x, s2)
    out = []
    for cost, f0, sol in outcomes:
        _, bb = _projected(recs, sol.x)
        out.append(StartOutcome(f0, math.exp(sol.x[0]) / (2 * math.pi), math.exp(sol.x[1]),
                                tuple(float(v) for v in sol.x[2:]), float(bb[0]), float(bb[1]),
                                (cost - best_cost) / s2))
    return FirstStage(
        frequency_hz=omega / (2 * math.pi), damping_ratio=zeta, rigid_mass=float(beta[0]),
        slosh_mass=float(beta[1]), lags=tuple(float(v) for v in best.x[2:]),
        lag_stderr=tuple(float(v) for v in se_x[2:]),
        stderr={"frequency_hz": omega / (2 * math.pi) * se_x[0], "damping_ratio": zeta * se_x[1],
                "rigid_mass": math.sqrt(max(cov_beta[0, 0], 0.0)),
                "slosh_mass": math.sqrt(max(cov_beta[1, 1], 0.0))},
        starts=tuple(out), rms_residual=math.sqrt(best_cost / n_obs), swing=swing,
        lag_inflation=tuple(float(v) for v in vif),
        explained=1 - best_cost / max(float(np.sum((F_all - F_all.mean()) ** 2)), 1e-300))


def _swing(recs, x, gravity: float) -> float:
    """The linear mode's swing amplitude [rad] after the strongest acceleration: the bob's
    displacement over the pendulum length is ``-b / g`` (``b`` the bob acceleration, the
    damping term aside); the amplitude is sqrt(2) times its RMS."""
    omega, zeta = math.exp(x[0]), math.exp(x[1])
    thetas = []
    for i, rec in enumerate(recs):
        X = _design(rec, omega, zeta, float(x[2 + i]))
        after = int(np.argmax(np.abs(X[:, 0])))
        thetas.append(X[after:, 1][rec.keep[after:]] / gravity)
    theta = np.concatenate(thetas)
    return math.sqrt(2 * float(np.mean(theta**2))) if theta.size else math.nan


def _bob_acceleration(a: np.ndarray, dt: float, omega: float, zeta: float) -> np.ndarray:
    """The linear mode's bob acceleration for the acceleration samples ``a`` (m/s^2), from
    rest: ``B/A = (2 zeta omega s + omega^2) / (s^2 + 2 zeta omega s + omega^2)``,
    discretised by the bilinear transform ``s = K (1 - 1/z) / (1 + 1/z)`` prewarped at
    ``omega`` (``K = omega / tan(omega dt / 2)``: the resonance lands exactly), filtered
    over the record by ``scipy.signal.lfilter``."""
    from scipy.signal import lfilter

    K = omega / math.tan(min(omega * dt / 2, 1.5))
    c, w2 = 2 * zeta * omega, omega**2
    num = [c * K + w2, 2 * w2, w2 - c * K]
    den = [K * K + c * K + w2, 2 * (w2 - K * K), K * K - c * K + w2]
    return lfilter(num, den, a - a[0]) + a[0]


def _design(rec: _Record, omega: float, zeta: float, lag: float) -> np.ndarray:
    """Columns ``[a(t - lag), b(t - lag), 1]`` of one record (``b`` of the linear mode)."""
    t = rec.time
    a = rec.acceleration_at(lag)
    b = _bob_acceleration(a, float(t[1] - t[0]), omega, zeta)
    return np.column_stack([a, b, np.ones_like(a)])


def _stacked(recs, x) -> tuple[np.ndarray, np.ndarray]:
    """The stacked design (shared M, m; an offset per record) and force, kept samples."""
    omega, zeta = math.exp(x[0]), math.exp(x[1])
    blocks, forces = [], []
    n = len(recs)
    for i, rec in enumerate(recs):
        X = _design(rec, omega, zeta, float(x[2 + i]))[rec.keep]
        offset = np.zeros((X.shape[0], n))
        offset[:, i] = 1.0
        blocks.append(np.hstack([X[:, :2], offset]))
        forces.append(rec.force[rec.keep])
    return np.vstack(blocks), np.concatenate(forces)


def _projected(recs, x) -> tuple[np.ndarray, np.ndarray]:
    """Residual of the linear least-squares fit at the nonlinear parameters ``x`` (log
    omega, log zeta, lags), and the linear coefficients ``(M, m, offsets...)``."""
    X, F = _stacked(recs, x)
    beta, *_ = np.linalg.lstsq(X, F, rcond=None)
    return F - X @ beta, beta


def _beta_covariance(recs, x, s2: float) -> np.ndarray:
    X, _ = _stacked(recs, x)
    return s2 * np.linalg.pinv(X.T @ X)


def _physical(recs, x) -> bool:
    """Positive rigid and slosh masses and lags off the edges of :data:`LAG_RANGE`."""
    _, beta = _projected(recs, x)
    inside = all(LAG_RANGE[0] + LAG_GRID_STEP < t < LAG_RANGE[1] - LAG_GRID_STEP for t in x[2:])
    return bool(beta[0] > 0 and beta[1] > 0 and inside)


def _lag_profile(recs, x0: np.ndarray) -> np.ndarray:
    """Per record, the lag on a grid over :data:`LAG_RANGE` where the projected objective
    (the others at ``x0``) is lowest among lags with positive masses: a drive near one
    frequency also fits half a period off with the masses' signs flipped."""
    grid = np.arange(LAG_RANGE[0], LAG_RANGE[1] + 0.5 * LAG_GRID_STEP, LAG_GRID_STEP)
    x = x0.copy()
    for i in range(len(recs)):
        costs = []
        for tau in grid:
            x[2 + i] = tau
            r, beta = _projected(recs[i:i + 1], np.r_[x[:2], tau])
            costs.append(float(r @ r) if beta[0] > 0 and beta[1] > 0 else math.inf)
        if np.isfinite(costs).any():
            x[2 + i] = grid[int(np.argmin(costs))]
    return x[2:]


_RECENT: dict = {}


def forget_stages() -> None:
    """Drop the kept :func:`record_stage` results (benchmarks time a first fit of a record)."""
    _RECENT.clear()


def record_stage(problem_parts, *, frequency_hz: float, gravity: float) -> FirstStage | None:
    """The first stage of the measured lateral cases of a problem being built:
    ``problem_parts`` is ``(experiments, carriage inputs, record noises, weights)``; the
    acceleration is each estimated carriage motion's start (the least-squares spline
    through the displacement) or the filtered input's. ``None`` when a case is not a
    lateral measured one with one force channel, or one whose liquid is not at rest at the
    first sample (``[test] initial_state`` "free" or "steady": the identification filters
    the acceleration from rest, and a window of a running test or a free decay would put
    the unmodelled start in the lag and the damping). The last few results are kept (the
    diagnosis builds a problem per candidate of one record)."""
    import hashlib

    exps, carriage, noise, weights = problem_parts
    records, key, levels = [], [round(frequency_hz, 9), gravity], []
    for i, e in enumerate(exps):
        case = e.case
        if case.test.rig != "lateral" or case.test.excitation != "measured" \
                or case.force is None or e.channels != ("force_x",) \
                or (case.test.initial_state or "rest") != "rest":
            return None
        ci = carriage[i] if carriage else None
        F = noise[i].force if noise and noise[i] is not None else case.force
        levels.append(noise[i].force_noise if noise and noise[i] is not None else math.nan)
        w = weights[i] if weights else None
        acc = _acceleration(e, ci)
        if acc is None:
            return None
        records.append((case.time, acc, F, w))
        key.append(hashlib.sha256(np.ascontiguousarray(case.time).tobytes()
                                  + np.ascontiguousarray(F).tobytes()
                                  + np.ascontiguousarray(case.displacement).tobytes()
                                  + (b"" if w is None else np.asarray(w, float).tobytes())
                                  + (b"e" if ci is not None else b"f")).hexdigest())
    key = tuple(key)
    if key not in _RECENT:
        _RECENT[key] = identify(records, frequency_hz=frequency_hz, gravity=gravity,
                                noise=levels if np.all(np.isfinite(levels)) else None)
        while len(_RECENT) > 4:
            _RECENT.pop(next(iter(_RECENT)))
    return _RECENT[key]


def _acceleration(exp, carriage):
    """The carriage acceleration (m/s^2) of an experiment as a function of time: its
    estimated motion's start, or the filtered input; ``None`` without one."""
    if carriage is not None:
        def acc(tt):
            return carriage.values(carriage.coefficients, tt)[2]
        return acc
    exc, dm = exp.excitation, exp.derived
    if exc is None or "rig.x_ddot" not in dm.inputs:
        return None
    j = dm.inputs.index("rig.x_ddot")

    def acc_filtered(tt):
        return np.asarray(exc.values(np.asarray(tt, float)))[j]
    return acc_filtered


def starting_values(stage: FirstStage, *, gravity: float, estimated, values, liquid_mass,
                    length_bounds: tuple[float, float] | None = None,
                    host: str = "p1") -> dict[str, float]:
    """Start values (by parameter name) of the first slosh mode ``host``, the rigid mass
    and the lags from the first stage, for the parameters ``estimated`` given the others'
    ``values``: ``host.mass``; ``host.length`` from the frequency (or, with a hinge spring
    estimated, the predicted length kept and the spring taking the rest of the stiffness);
    the hinge damper from the damping ratio; ``rig.dry_mass`` (an unweighed container: the
    rigid mass less the fixed liquid and the other modes) or ``fixed.mass`` (the rigid
    mass less the dry mass and the other modes). A slosh mass that is not positive leaves
    the masses to the prediction (the frequency and damping still start the mode); one
    beyond :data:`BUDGET_SHARE` of the liquid starts there."""
    est = set(estimated)
    m = stage.slosh_mass
    keep_mass = m > 0
    if not keep_mass:  # the frequency still holds; the mass stays the prediction's
        m = float(values.get(f"{host}.mass", math.nan))
        if not m > 0:
            return {}
    if liquid_mass is not None and m >= BUDGET_SHARE * liquid_mass:
        m = BUDGET_SHARE * liquid_mass  # inside the liquid budget, where IPOPT starts
    omega = 2 * math.pi * stage.frequency_hz
    out: dict[str, float] = {}
    L = gravity / omega**2
    if f"{host}.stiffness" in est and f"{host}.length" in values:
        L0 = float(values[f"{host}.length"])
        if omega**2 > gravity / L0:
            L = L0
            out[f"{host}.stiffness"] = m * L**2 * (omega**2 - gravity / L)
        else:
            out[f"{host}.stiffness"] = 0.0
    if keep_mass:
        out[f"{host}.mass"] = m
    out[f"{host}.length"] = L
    out[f"{host}.damping"] = 2 * stage.damping_ratio * omega * m * L**2
    others = sum(float(v) for k, v in values.items()
                 if k.endswith(".mass") and k.split(".")[0] not in ("fixed", "rig", host)
                 and k not in est)
    others += sum(float(values.get(k, 0.0)) for k in est
                  if k.endswith(".mass") and k.split(".")[0] not in ("fixed", "rig", host))
    M = stage.rigid_mass - others
    if not keep_mass:
        return {k: v for k, v in out.items() if k in est}
    if "rig.dry_mass" in est:
        fixed = (liquid_mass - m - others) if "fixed.mass" not in est and liquid_mass else \
            float(values.get("fixed.mass", 0.0))
        out["rig.dry_mass"] = max(M - fixed, 0.0)
    elif "fixed.mass" in est:
        dry = float(values.get("rig.dry_mass", 0.0))
        upper = (liquid_mass - m - others) if liquid_mass else math.inf
        out["fixed.mass"] = min(max(M - dry, 1e-3 * m), upper)
    return {k: v for k, v in out.items() if k in est}
