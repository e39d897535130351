"""The fit's first stage: a linear identification of the record that needs no good start.

Linearised, the lateral force of a rigid mass ``M`` and one slosh mode (mass ``m``, natural
frequency ``omega``, damping ratio ``zeta``) driven by the carriage acceleration ``a`` is

    F(t) = M a(t - tau) + m b(t - tau),
    B(s) / A(s) = (2 zeta omega s + omega^2) / (s^2 + 2 zeta omega s + omega^2)

(``b`` is the acceleration of the mode's bob; ``tau`` the lag of the force stream behind the
motion stream). For given ``(omega, zeta, tau)`` the force is linear in ``(M, m)`` and an
offset, so those follow by linear least squares (variable projection) and only the three
nonlinear parameters are searched, by SciPy's ``least_squares`` (with the projected
residual's exact Jacobian) from a few starts: the predicted frequency, the force
spectrum's peaks around it and the lowest physical point of the objective's profile over
frequency and damping, each with the lag where the objective's profile over a grid is
lowest. The best start is kept; starts that end in other
minima are reported with their spread. The acceleration is the least-squares spline through
the measured displacement (the estimated input's start, :mod:`estimate.fitting.carriage`) or
the filtered input; the mode's response is ``B/A`` discretised by the bilinear transform
prewarped at the mode's frequency, filtered over the record (``scipy.signal.lfilter``),
from rest.

The result starts the NLP (masses, length, hinge damping, the rigid mass of an unweighed
container, the stream lag) and decides whether the lag is identifiable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .first_stage_model import (
    LAG_GRID_STEP,
    LAG_RANGE,
    LOWPASS_FACTOR,
    LOWPASS_MIN_HZ,
    _beta_covariance,
    _finite,
    _frequency_profile,
    _lag_profile,
    _physical,
    _prepared,
    _projected,
    _projected_jacobian,
    _Projection,
    _stacked,
    _swing,
)

__all__ = ["FirstStage", "StartOutcome", "identify", "LAG_GRID_STEP", "LAG_RANGE",
           "LAG_IDENTIFIED"]

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
#: A start within this (relative) of where an earlier search ended at a physical point is
#: not searched: two steps of the frequency profile's grid, the same minimum.
SAME_MINIMUM = 0.025


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
        # the lag's standard error is what the force noise alone allows (it decides whether
        # the fit estimates the lag); the linear mode's misfit of the record is not in it,
        # so it is not given as the lag's interval
        lag = ", ".join(f"{1e3 * t:.1f} ms (standard error {1e3 * s:.2g} ms at the force "
                        f"noise alone)" for t, s in zip(self.lags, self.lag_stderr))
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
    if not top_hz > min_hz:  # sampled too slowly for any mode searched
        return None
    profiled = _frequency_profile(recs, max(lo, min_hz), min(hi, top_hz))
    if profiled is not None and all(abs(profiled / s - 1) > SPREAD_RELATIVE for s in starts):
        starts.append(profiled)
    n = len(recs)
    lo = np.r_[math.log(2 * math.pi * min_hz), math.log(ZETA_RANGE[0]), [LAG_RANGE[0]] * n]
    hi = np.r_[math.log(2 * math.pi * top_hz), math.log(ZETA_RANGE[1]), [LAG_RANGE[1]] * n]
    x_scale = np.r_[0.05, 0.5, [0.005] * n]

    def search(x0):
        f = _Projection(recs, x0, range(2 + n))
        return least_squares(f.residual, x0, jac=f.jacobian, bounds=(lo, hi), x_scale=x_scale,
                             method="trf", xtol=1e-4, ftol=1e-6, max_nfev=60)

    def search_without_lag(x0):
        # the mode alone, the streams taken as synchronous: a steady drive trades a free
        # lag for the mode's phase, and the data then prefer neither clearly
        f = _Projection(recs, x0, range(2))
        sol = least_squares(f.residual, x0[:2], jac=f.jacobian, bounds=(lo[:2], hi[:2]),
                            x_scale=x_scale[:2], method="trf", xtol=1e-4, ftol=1e-6,
                            max_nfev=60)
        sol.x = np.r_[sol.x, x0[2:]]
        sol.jac = np.hstack([sol.jac, np.zeros((sol.jac.shape[0], n))])
        return sol

    outcomes = []  # (not physical, cost, start, solution)
    for f0 in starts:  # the linear mode from every start: cheap, and no start is needed
        if any(not o[0] and abs(math.exp(o[3].x[0]) / (2 * math.pi * f0) - 1) < SAME_MINIMUM
               for o in outcomes):
            continue  # a physical minimum was found at this start already
        x0 = np.r_[math.log(2 * math.pi * f0), math.log(0.01), np.zeros(n)]
        sols = [search_without_lag(x0)]
        x0[2:] = _lag_profile(recs, x0)
        sols.append(search(x0))
        outcomes += [(not _physical(recs, sol.x), float(2 * sol.cost), f0, sol) for sol in sols]
    # the best physical outcome (positive masses, lags inside the range) first
    outcomes.sort(key=lambda o: o[:2])
    outcomes = [o[1:] for o in outcomes]
    best_cost, _, best = outcomes[0]
    r, beta = _projected(recs, best.x)
    F_all = _stacked(recs, best.x)[1]
    n_obs = r.size
    s2 = best_cost / max(n_obs - (2 + n + 3 * n), 1)
    J = _projected_jacobian(recs, best.x)
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
