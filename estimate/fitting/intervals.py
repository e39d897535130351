"""What a fit's covariances say about its estimates: intervals (Wald, or one-sided from a
bound), the standard errors of either covariance, where the Gauss-Newton ones are
optimistic, and the notes that say which covariance the report uses and why
(:class:`ResultIntervals`, a base of :class:`~estimate.fitting.result.FitResult`)."""

from __future__ import annotations

import math

import numpy as np

from analogs.errors import InputError

__all__ = ["OPTIMISTIC_FACTOR", "ResultIntervals"]

_PROFILE_HINT = "`profile_interval` gives a profile-likelihood interval of a chosen parameter."
#: The fit report calls the Gauss-Newton standard error of an estimate optimistic when the
#: robust one exceeds it by more than this factor.
OPTIMISTIC_FACTOR = 1.5


class ResultIntervals:
    """The intervals and standard errors of a fit result, read from its fields
    (``values``, ``stderr``, ``covariance_kind``, ``at_bound``, ``bound_stderr``, ``dof``,
    the two covariances, ``model_error``): methods only, for
    :class:`~estimate.fitting.result.FitResult`."""

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """The ``level`` (default 0.95) interval of the estimate ``name``, within its bounds:
        the Wald interval from :attr:`stderr` (the covariance ``covariance_kind`` names; t
        distribution), reaching as far as the estimate moves when the estimates held at a
        physical bound leave it up to their one-sided limits (``bound_reach``: the union of
        the intervals conditional on any such value); for an estimate at a bound the
        one-sided interval from the bound (:meth:`one_sided_limit`), up to the other bound
        when the data do not determine it. When a fitted pendulum is far heavier than its
        tank mode (``mode_shifts``), the interval also reaches as far as the estimate moves
        when that pendulum's mass is put at the mode's prediction (:attr:`mode_reach`)."""
        i = self._index(name)
        e = self.problem.estimated[i]
        if not self.free[i]:
            limit = self.one_sided_limit(name, level)
            if self.at_bound[i] == "lower":
                return float(e.lower), (float(e.upper) if limit is None else min(limit, e.upper))
            return (float(e.lower) if limit is None else max(limit, e.lower)), float(e.upper)
        reach = (0.0, 0.0) if self.bound_reach is None else self.bound_reach[i]
        moved = (0.0, 0.0) if self.mode_reach is None else self.mode_reach[i]
        lo, hi = self._widened(self.values[i], self.stderr[i], reach, level, moved)
        return max(lo, float(e.lower)), min(hi, float(e.upper))

    def derived_interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """The ``level`` (default 0.95) interval of the derived quantity ``name``
        (``derived``; delta method conditional on the estimates held at bounds, reaching off
        them and to a conflicting mode's prediction as :meth:`interval`)."""
        if name not in self.derived:
            raise InputError(f"{name!r} is not a derived quantity of this fit; derived: "
                             f"{', '.join(self.derived) or 'none'}")
        v, se = self.derived[name]
        se, *reach = self.derived_reach.get(name, (se, 0.0, 0.0))
        return self._widened(v, se, reach, level, self.derived_mode_reach.get(name, (0.0, 0.0)))

    def _widened(self, value: float, se: float, reach, level: float,
                 moved=(0.0, 0.0)) -> tuple[float, float]:
        """``value +/- t se``, widened by the one-sided quantile times ``reach`` (down, up)
        and by ``moved`` (down, up; the union of the intervals at the value and at the
        value moved)."""
        from scipy.stats import t as student

        q = float(student.ppf(0.5 + level / 2, self.dof))
        q1 = float(student.ppf(level, self.dof))
        return (float(value - q * se - q1 * reach[0] - moved[0]),
                float(value + q * se + q1 * reach[1] + moved[1]))

    @property
    def mode_reach(self) -> np.ndarray | None:
        """``(estimates, 2)``: how far each estimate moves down and up when the pendulum
        masses far above their tank modes (``mode_shifts``) are put at the predictions,
        each alone (zero for an estimate at a bound); ``None`` when there are none."""
        if not self.mode_shifts:
            return None
        from .result import reach_sides

        sides = reach_sides(np.column_stack([m for _, m in self.mode_shifts]))
        return np.where(np.array(self.free, bool)[:, None], sides, 0.0)

    def reach_text(self, i: int) -> str:
        """What widens the 95 % interval of estimate ``i`` beyond its standard error, in
        words, or ''."""
        why = []
        if self.bound_reach is not None and np.any(self.bound_reach[i]):
            why.append("off the held bounds")
        if self.mode_reach is not None and np.any(self.mode_reach[i]):
            why.append("to " + ", ".join(label for label, m in self.mode_shifts if m[i] != 0))
        return " and ".join(why)

    def derived_reach_text(self, name: str) -> str:
        """What widens the 95 % interval of the derived quantity ``name`` beyond its
        standard error, in words, or ''."""
        why = [w for w, on in (
            ("off the held bounds", any(self.derived_reach.get(name, (0.0, 0.0, 0.0))[1:])),
            ("to the tank modes' predicted masses",
             any(self.derived_mode_reach.get(name, (0.0, 0.0))))) if on]
        return " and ".join(why)

    def one_sided_limit(self, name: str, level: float = 0.95) -> float | None:
        """For an estimate ``name`` at a bound: the one-sided ``level`` confidence limit away
        from the bound (``bound +/- t_level * bound_stderr``), ``None`` when the data do not
        determine it; raises for an estimate inside its bounds."""
        from scipy.stats import t as student

        i = self._index(name)
        side = self.at_bound[i] if self.at_bound else None
        if side is None:
            raise InputError(f"`{name}` is not at a bound; use `interval`")
        se = float(self.bound_stderr[i]) if self.bound_stderr is not None else math.nan
        if not math.isfinite(se):
            return None
        q = float(student.ppf(level, self.dof))
        e = self.problem.estimated[i]
        return float(e.lower + q * se) if side == "lower" else float(e.upper - q * se)

    def uncertainty_text(self, i: int) -> str:
        """``+/- se`` of estimate ``i`` (with its 95 % interval when an estimate held at a
        bound widens it), or what stands for it at a bound."""
        if self.free[i]:
            text = f"+/- {self.stderr[i]:.3g}"
            why = self.reach_text(i)
            if why:
                lo, hi = self.interval(self.names[i])
                text += f" (95 %: [{lo:.6g}, {hi:.6g}] {why})"
            return text
        e = self.problem.estimated[i]
        side = self.at_bound[i]
        limit = self.one_sided_limit(self.names[i])
        bound = e.lower if side == "lower" else e.upper
        if limit is None:
            return f"at its {side} bound {bound:.6g} (not determined by the data)"
        return (f"at its {side} bound {bound:.6g} (one-sided 95 %: "
                f"{'<=' if side == 'lower' else '>='} {limit:.3g})")

    @property
    def gauss_newton_stderr(self) -> np.ndarray:
        """Standard errors from the Gauss-Newton covariance (independent residuals; NaN at a
        bound)."""
        return self._stderr(self.gauss_newton_covariance)

    @property
    def robust_stderr(self) -> np.ndarray:
        """Standard errors from the covariance robust to autocorrelated residuals (NaN at a
        bound, or when it was not computed)."""
        return self._stderr(self.robust_covariance)

    def _stderr(self, cov: np.ndarray | None) -> np.ndarray:
        if cov is None:
            return np.full(len(self.names), np.nan)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
        return np.where(np.array(self.free, bool), se, np.nan)

    def optimistic(self, factor: float = OPTIMISTIC_FACTOR) -> dict[str, float]:
        """Estimates whose robust standard error exceeds the Gauss-Newton one by more than
        ``factor``, with the ratio: there the residuals are correlated (coloured noise, a
        filtered force, or an effect the model lacks) and the Gauss-Newton intervals are
        optimistic."""
        gn, rb = self.gauss_newton_stderr, self.robust_stderr
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = rb / gn
        return {n: float(r) for n, r in zip(self.names, ratio) if np.isfinite(r) and r > factor}

    @property
    def noise_stderr(self) -> np.ndarray:
        """The standard errors without the model-error widening (:attr:`model_error`): the
        spread the noise alone gives the estimates (NaN at a bound)."""
        return self.stderr / self.model_error

    def interval_note(self) -> str:
        """One sentence: which covariance the standard errors come from, and where the
        Gauss-Newton ones are optimistic."""
        if self.covariance_kind != "robust":
            return "Standard errors: Gauss-Newton covariance (independent residuals)."
        worse = self.optimistic()
        widened = (f" widened {self.model_error:.3g}x for model error (the residual over its "
                   "noise figure);" if self.model_error > 1 else "")
        return ("Standard errors: the covariance robust to correlated residuals (Newey-West, "
                "no lower than the channels' noise spectra give);"
                + widened + " "
                + ("the Gauss-Newton ones, which assume independent residuals, are optimistic: "
                   + ", ".join(f"{r:.2g}x smaller for `{n}`" for n, r in worse.items()) + "."
                   if worse else f"the Gauss-Newton ones agree within {OPTIMISTIC_FACTOR:g}x."))

    def covariance_note(self) -> str:
        """Which covariance the standard errors and intervals come from, and why."""
        p = self.problem
        text = ("Standard errors and intervals: the covariance robust to correlated residuals "
                "(a sandwich whose middle is the Newey-West long-run covariance of the "
                "parameters' scores" if self.covariance_kind == "robust" else
                "Standard errors and intervals: the Gauss-Newton covariance (independent "
                "residuals")
        text += ("; beside it the Gauss-Newton covariance of the whole NLP, states "
                 "eliminated through the dynamics" if self.covariance_kind == "robust" else "")
        if p.input == "estimated" and any(c is not None for c in p.carriage):
            text += ("; force and displacement residuals divided by their noise figures, the "
                     "carriage motion estimated and marginalised")
        text += (f"; scaled by the residual variance {self.residual_variance:.3g}, "
                 f"{self.dof} degrees of freedom). ")
        if p.force_cutoff_hz is not None:
            text += (f"The force was low-passed at {p.force_cutoff_hz:g} Hz, which correlates "
                     "neighbouring residuals, and the input was treated as exact. ")
        if self.covariance_kind == "robust":
            text += ("The robust one is used because it equals the Gauss-Newton one when the "
                     "residuals are white and widens when they are not (coloured transducer "
                     "noise, a filtered force, an effect the model lacks), where the "
                     "Gauss-Newton one is optimistic. ")
            if self.model_error > 1:
                text += (f"The residual is {self.model_error:.3g} times its noise figure: the "
                         "model misses something the noise does not explain, whose bias a "
                         "covariance of the noise does not bound, so the robust standard "
                         f"errors are widened by that factor (model error). ")
            worse = self.optimistic()
            if worse:
                text += ("Here the Gauss-Newton standard errors are optimistic: the robust ones "
                         "are " + ", ".join(f"{r:.2g}x for `{n}`" for n, r in worse.items())
                         + ". ")
        return text + self._reach_note() + self._mode_note() + _PROFILE_HINT

    def _reach_note(self) -> str:
        """What the intervals add for the estimates held at physical bounds, or ''."""
        if self.bound_reach is None or not np.any(self.bound_reach):
            return ""
        from scipy.stats import t as student

        q1 = float(student.ppf(0.95, self.dof))
        held = [n for n, side, f in zip(self.names, self.at_bound, self.free) if side and not f]
        moved = [f"`{n}` " + "/".join(t for t in (f"-{q1 * d:.3g}" if d else "",
                                                    f"+{q1 * u:.3g}" if u else "") if t)
                 for n, (d, u), f in zip(self.names, self.bound_reach, self.free)
                 if f and (d or u)]
        return ("Held at a physical bound: " + ", ".join(f"`{n}`" for n in held) + ". The "
                "truth may lie just inside it, so the 95 % intervals of the estimates that "
                "move with it reach as far as they move when it leaves the bound up to its "
                "one-sided 95 % limit (the union of the intervals conditional on any such "
                "value): " + ", ".join(moved) + ". ")

    def _mode_note(self) -> str:
        """What the intervals add for pendulums far heavier than their tank modes, or ''."""
        if not self.mode_shifts:
            return ""
        parts = []
        for label, m in self.mode_shifts:
            # the moves of at least a tenth of a standard error
            moved = [f"`{n}` {v:+.3g}" for n, v, se, f
                     in zip(self.names, m, self.stderr, self.free)
                     if f and v != 0 and not abs(v) < 0.1 * se]
            parts.append(f"{label}: " + ", ".join(moved))
        from .initial import PREDICTION_FACTOR

        return (f"A fitted pendulum is more than {PREDICTION_FACTOR:g} times its tank mode's "
                "predicted mass: it may stand for something else in the record than that "
                "mode (a second fixed mass, the noise near its frequency), and the estimates "
                "that move with it would then be elsewhere. The 95 % intervals reach as far "
                "as the estimates move (the regression in the covariance) when its mass is "
                "put at the prediction (the union of the intervals at the fit and there): "
                + "; ".join(parts) + ". ")
