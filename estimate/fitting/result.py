"""Fit results: estimates with uncertainties, derived quantities, report and JSON."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from analogs.errors import UnknownNameError

if TYPE_CHECKING:  # pragma: no cover
    from ..data.signals.noise_figure import NoiseFigure
    from .identifiability import Identifiability
    from .problem import FitProblem

from .intervals import OPTIMISTIC_FACTOR, ResultIntervals

__all__ = ["FitResult", "OPTIMISTIC_FACTOR", "derived_jacobian", "derived_quantities",
           "derived_shifts", "reach_sides"]

def derived_jacobian(problem: "FitProblem", theta: np.ndarray):
    """``(found, values, J)``: the quantities the model derives at the estimates of case 0
    (:meth:`analogs.Model.derived_quantities`), their values and their Jacobian w.r.t. the
    estimates; ``found`` empty when it derives none."""
    th = ca.MX.sym("theta", theta.size)
    vals: dict[str, Any] = dict(problem.fixed[0])
    for j, e in enumerate(problem.estimated):
        if e.case in (None, 0):
            vals[e.parameter] = th[j]
    labels = [e.name for e in problem.estimated]
    for t in problem.ties:
        vals[t.parameter] = t.constant + sum(k * th[labels.index(n)] for n, k in t.terms)
    found = problem.model.derived_quantities(vals)
    if not found:
        return {}, np.zeros(0), np.zeros((0, theta.size))
    e = ca.vertcat(*[ca.MX(v) if not isinstance(v, ca.MX) else v for v, _ in found.values()])
    fn = ca.Function("derived", [th], [e, ca.jacobian(e, th)])
    v, J = fn(theta)
    return found, np.asarray(v).ravel(), np.asarray(J)


def derived_quantities(problem: "FitProblem", theta: np.ndarray, cov: np.ndarray,
                       held: np.ndarray | None = None, reach: np.ndarray | None = None,
                       jacobian=None) -> tuple[dict[str, tuple[float, float]], dict[str, str],
                                  dict[str, tuple[float, float, float]]]:
    """The quantities the model's components derive (:meth:`analogs.Model.derived_quantities`,
    e.g. ``pN.frequency_hz`` and ``pN.damping_ratio`` with the summed hinge and diaphragm
    terms) at the estimates of case 0, with delta-method standard errors; their units; and,
    for the intervals, ``(standard error, down, up)``: the standard error conditional on the
    estimates ``held`` at a bound (their rows of ``cov`` are zero) and the reach off those
    bounds per unit one-sided quantile along the regression ``reach`` (:func:`reach_sides`).
    A quantity that depends on a held estimate has no standard error (NaN). ``jacobian``:
    :func:`derived_jacobian` at ``theta``, when the caller has it."""
    found, v, J = jacobian or derived_jacobian(problem, theta)
    if not found:
        return {}, {}, {}
    se = np.sqrt(np.clip(np.einsum("ij,jk,ik->i", J, cov, J), 0, None))
    shown = se.copy()
    if held is not None and np.any(held):
        shown[np.any(J[:, np.asarray(held, bool)] != 0, axis=1)] = np.nan
    sides = reach_sides(J @ reach) if reach is not None else np.zeros((len(found), 2))
    return ({k: (float(a), float(b)) for k, a, b in zip(found, v, shown)},
            {k: unit for k, (_, unit) in found.items()},
            {k: (float(a), float(b), float(c)) for k, a, (b, c) in zip(found, se, sides)})


def derived_shifts(jacobian, shifts: np.ndarray) -> dict[str, tuple[float, float]]:
    """Per derived quantity, ``(down, up)``: how far it moves (to first order, its
    :func:`derived_jacobian` ``jacobian``) when the estimates move by the columns of
    ``shifts`` (:attr:`FitResult.mode_shifts`), each alone (:func:`reach_sides`)."""
    found, _, J = jacobian
    return {k: (float(a), float(b)) for k, (a, b) in zip(found, reach_sides(J @ shifts))}


def reach_sides(reach: np.ndarray) -> np.ndarray:
    """``(rows, 2)``: how far each row's quantity reaches down and up when every held
    estimate (a column of ``reach``, signed away from its bound) leaves its bound by one
    standard deviation, the held estimates moving independently (a box)."""
    return np.stack([np.maximum(-reach, 0).sum(axis=1), np.maximum(reach, 0).sum(axis=1)],
                    axis=1)


@dataclass(frozen=True)
class FitResult(ResultIntervals):
    """The outcome of :func:`estimate.fit`.

    ``values``, ``stderr`` and ``covariance`` follow ``names`` (SI units, see ``units``);
    ``cost`` is the sum of squared force residuals (N^2) over the fitted samples (for
    multi-channel cases: of residuals divided by their channel scales, dimensionless),
    ``residuals`` and ``measured`` hold, per case, the residual (simulated - measured, N,
    also on samples left out by zero weights) and the (filtered) measured force; for a
    multi-channel case (spinning rig) both are ``samples x channels`` arrays, columns
    named by ``channels`` (N and N m);
    ``history`` the estimates at every IPOPT iteration and ``cost_history`` the cost there.

    Attributes
    ----------
    problem : FitProblem
        What was fitted.
    rms_residual, r_squared : float
        RMS residual over the fitted samples (N; scaled for several channels) and the
        share of the measurement's variance the model explains.
    n_samples, iterations : int
        Fitted samples, IPOPT iterations.
    seconds : float
        Wall time of the fit, s.
    converged, status : bool, str
        Whether IPOPT converged, and its status (``"Solve_Succeeded"``).
    warnings : tuple of str
        What the fit says about itself (bounds reached, a low R^2, ...).
    identifiability : Identifiability
        The scaled sensitivity's conditioning and the confounded groups.
    derived : dict
        Derived quantities ``(value, stderr)`` of case 0 (:func:`derived_quantities`).
    cost_kind, transcription : str
        The cost (``"squared"``, ``"abs"``) and the transcription used.
    dof : int
        Degrees of freedom of the residual (also ``residual_variance``, below).
    initial_states : tuple of dict
        Per case, the state at the first sample (see ``initial_state_kinds``).
    bound_stderr : ndarray or None
        Per estimate at a bound, the spread the data allow away from it (see ``at_bound``).
    carriage_coefficients : tuple
        Per case, the estimated carriage spline's coefficients (see ``states``).
    covariance_kind : str
        ``"robust"`` or ``"gauss-newton"``: which covariance ``covariance`` is (see
        ``robust_covariance`` and ``gauss_newton_covariance``).
    """

    problem: "FitProblem" = field(repr=False)
    values: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray = field(repr=False)
    cost: float
    rms_residual: float
    r_squared: float
    n_samples: int
    iterations: int
    seconds: float
    converged: bool
    status: str
    warnings: tuple[str, ...]
    identifiability: "Identifiability" = field(repr=False)
    derived: dict[str, tuple[float, float]]
    history: np.ndarray = field(repr=False)
    cost_history: np.ndarray = field(repr=False)
    residuals: tuple[np.ndarray, ...] = field(repr=False)
    measured: tuple[np.ndarray, ...] = field(repr=False)
    cost_kind: str = "squared"
    transcription: str = ""
    #: Per-case sample weights used (0 = left out of the fit, e.g. held-out segments).
    weights: tuple[np.ndarray, ...] = field(default=(), repr=False)
    #: Sensitivity of the (weighted) residuals to the estimates (samples x parameters).
    sensitivity: np.ndarray = field(default=None, repr=False)
    #: Per case, the fitted output names (columns of ``residuals`` and ``measured`` when
    #: there are several).
    channels: tuple[tuple[str, ...], ...] = field(default=(), repr=False)
    #: Per case, the residual scale of each channel (1 for the lateral force).
    channel_scales: tuple[dict[str, float], ...] = field(default=(), repr=False)
    #: SI unit of each derived quantity (as its component declares it).
    derived_units: dict[str, str] = field(default_factory=dict)
    #: Per case, the estimated carriage motion ``(3, samples)``: displacement (m), velocity
    #: (m/s), acceleration (m/s^2); ``None`` when the input was used as given.
    carriage: tuple[np.ndarray | None, ...] = field(default=(), repr=False)
    #: Per case, estimated minus measured carriage displacement (m), or ``None``.
    displacement_residuals: tuple[np.ndarray | None, ...] = field(default=(), repr=False)
    #: Per case, the states at the samples ``(nx, samples)`` and the estimated carriage
    #: motion's coefficients (``None`` when the input was used as given): what a later fit
    #: of the same cases starts from (``fit(..., warm_start=result)``).
    states: tuple[np.ndarray, ...] = field(default=(), repr=False)
    carriage_coefficients: tuple[np.ndarray | None, ...] = field(default=(), repr=False)
    #: The weighted least-squares objective at the optimum (force and displacement residuals
    #: in units of their scales), the residual variance ``objective / dof`` that scales the
    #: covariance, and the degrees of freedom (observations minus estimated quantities,
    #: carriage coefficients and free initial states included).
    objective: float = math.nan
    residual_variance: float = math.nan
    dof: int = 1
    #: Per case, where the analog started (``"rest"``, ``"steady"`` or ``"free"``) and the
    #: state at the first sample (rad, m, rad/s, m/s by state name) at the estimates.
    initial_state_kinds: tuple[str, ...] = ()
    initial_states: tuple[dict[str, float], ...] = field(default=(), repr=False)
    #: Per estimate, ``"lower"``/``"upper"`` when it ended at that (active) bound, else
    #: ``None``. Such an estimate has no Wald standard error (``stderr`` is NaN, its
    #: covariance rows and columns are zero, its correlations NaN) and is left out of the
    #: identifiability check; ``bound_stderr`` gives the standard deviation the data allow
    #: it away from the bound (NaN when they do not determine it), for a one-sided interval.
    at_bound: tuple[str | None, ...] = ()
    bound_stderr: np.ndarray | None = field(default=None, repr=False)
    #: Per estimate and derived quantity, ``(down, up)``: how far its value reaches when the
    #: estimates held at physical bounds leave them by one ``bound_stderr`` each, the others
    #: re-estimated (the regression in the covariance without the bounds). The truth may be
    #: just inside a bound; the intervals add this reach times the one-sided quantile
    #: (:meth:`interval`). Zero when nothing is held or nothing correlates with it.
    bound_reach: np.ndarray | None = field(default=None, repr=False)
    #: Per estimate held at a physical bound that the data determine (a finite
    #: ``bound_stderr``) and per active linear bound: its label (the estimate's name, or the
    #: bound in words) and how every estimate moves (``names`` order) when it leaves the
    #: bound by one standard deviation (the held estimate by its ``bound_stderr`` away from
    #: the bound, the others along the regression): the columns ``bound_reach`` sums. A
    #: Monte Carlo of the fit draws along them (half-normal).
    bound_directions: tuple[tuple[str, np.ndarray], ...] = field(default=(), repr=False)
    #: Per derived quantity, ``(standard error, down, up)`` for its interval: the standard
    #: error conditional on the held estimates (``derived`` has none for a quantity that
    #: depends on one) and its reach as ``bound_reach``.
    derived_reach: dict[str, tuple[float, float, float]] = field(default_factory=dict,
                                                                 repr=False)
    #: Per fitted pendulum mass above ``PREDICTION_FACTOR`` times its tank mode's predicted
    #: mass (:mod:`estimate.fitting.mode_conflicts`): its label and how every estimate moves
    #: (``names`` order, SI units) when that mass is put at the prediction, the others along
    #: the regression in the covariance. Such a pendulum may stand for something else in the
    #: record than its mode; the intervals reach as far as these moves (:attr:`mode_reach`).
    mode_shifts: tuple[tuple[str, np.ndarray], ...] = field(default=(), repr=False)
    #: Per derived quantity, ``(down, up)``: how far it moves with :attr:`mode_shifts`.
    derived_mode_reach: dict[str, tuple[float, float]] = field(default_factory=dict,
                                                               repr=False)
    #: The linear bounds the estimates end on (the masses within the liquid,
    #: :mod:`estimate.fitting.budget`), in words; the covariance holds them there.
    active_bounds: tuple[str, ...] = ()
    #: Per case, the noise figure of each fitted channel
    #: (:mod:`estimate.fitting.noise_figures`): the one figure the report, the covariance,
    #: the diagnosis verdict and the campaign use.
    noise_figures: tuple[dict[str, "NoiseFigure"], ...] = field(default=(), repr=False)
    #: Both covariances of the estimates (:mod:`estimate.fitting.covariance`): Gauss-Newton
    #: (independent residuals) and robust to autocorrelated residuals (Newey-West sandwich);
    #: ``covariance`` and ``stderr`` are the one named by ``covariance_kind``, which the
    #: intervals use.
    gauss_newton_covariance: np.ndarray | None = field(default=None, repr=False)
    robust_covariance: np.ndarray | None = field(default=None, repr=False)
    covariance_kind: str = "gauss-newton"
    #: Per case, the Newey-West bandwidth of the robust covariance (samples).
    bandwidths: tuple[int, ...] = ()
    #: How much the robust standard errors were widened for model error
    #: (:func:`~estimate.fitting.noise_figures.model_error_factor`: the residual over its
    #: noise figure when above the margin), 1 when the residual is within the noise.
    model_error: float = 1.0

    @property
    def bounds_reached(self) -> tuple[str, ...]:
        """Every bound the fit ends on, in words: estimates at a bound of their own and
        active linear bounds (the liquid mass budget). Empty: the optimum is interior."""
        out = []
        for i, side in enumerate(self.at_bound):
            if side:
                e = self.problem.estimated[i]
                bound = e.lower if side == "lower" else e.upper
                out.append(f"{e.name} at its {side} bound {bound:.4g} {e.unit}".rstrip())
        return tuple(out) + tuple(self.active_bounds)

    @property
    def outside_tank(self) -> tuple[str, ...]:
        """Every estimate that puts the analog outside its tank (a height below the bottom
        or above the top, an inertia beyond the whole liquid's at the wall:
        :attr:`FitProblem.tank_ranges`), by more than 2 of its standard errors, in words.
        Empty: the analog is physically possible."""
        out = []
        ranges = getattr(self.problem, "tank_ranges", {}) or {}
        for i, e in enumerate(self.problem.estimated):
            if e.parameter not in ranges:
                continue
            lo, hi = ranges[e.parameter]
            v = float(self.values[i])
            se = float(self.stderr[i]) if i < len(self.stderr) else math.nan
            slack = 2 * se if math.isfinite(se) else 0.0
            if v < lo - slack or v > hi + slack:
                side = "below" if v < lo else "above"
                bound = lo if v < lo else hi
                out.append(f"{e.name} = {v:.4g} {e.unit} is {side} {bound:.4g} {e.unit}".rstrip())
        return tuple(out)

    @property
    def verdict(self) -> str:
        """One line: ``converged``, ``converged at a bound: ...`` (naming every bound the
        fit ends on), ``converged outside the tank: ...`` (a physically impossible analog:
        :attr:`outside_tank`) or ``NOT converged``, with IPOPT's status."""
        if not self.converged:
            return f"NOT converged ({self.status})"
        outside = self.outside_tank
        if outside:
            return (f"converged outside the tank ({self.status}), not a physical analog: "
                    + "; ".join(outside))
        reached = self.bounds_reached
        if reached:
            return f"converged at a bound ({self.status}): " + "; ".join(reached)
        return f"converged ({self.status})"

    def tied(self) -> dict[str, tuple[float, float, str]]:
        """Parameters that follow the estimates (:attr:`FitProblem.ties`: the fixed liquid
        of an unweighed tank): value, delta-method standard error and what they are."""
        out = {}
        by_label = dict(zip(self.names, self.values))
        for t in self.problem.ties:
            c = np.zeros(len(self.names))
            for n, k in t.terms:
                c[self.names.index(n)] = k
            cov = np.nan_to_num(self.covariance)
            out[t.parameter] = (t.value(by_label), float(np.sqrt(max(c @ cov @ c, 0.0))), t.text)
        return out

    def noise_figure(self, case: int = 0, channel: str | None = None) -> "NoiseFigure | None":
        """The noise figure of ``channel`` (default: the first fitted) of ``case``."""
        figures = self.noise_figures[case] if self.noise_figures else {}
        if not figures:
            return None
        return figures[channel] if channel is not None else next(iter(figures.values()))

    def residual_over_noise(self, case: int = 0) -> float:
        """The RMS residual on the fitted samples of ``case`` over its noise figure
        (:func:`estimate.fitting.noise_figures.residual_over_noise`)."""
        from .noise_figures import residual_over_noise

        return residual_over_noise(self, case)

    def scaled_residuals(self, case: int = 0) -> np.ndarray:
        """Residuals of ``case`` divided by their channel scales (what the cost sums):
        1-D for one channel, ``samples x channels`` for several."""
        r = self.residuals[case]
        if not self.channel_scales:
            return r
        s = np.array([self.channel_scales[case][c] for c in self.channels[case]])
        return r / s if r.ndim == 2 else r / s[0]

    def channel(self, name: str, case: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """``(measured, residual)`` of the fitted channel ``name`` of ``case`` (N or N m)."""
        names = self.channels[case] if self.channels else ("force_x",)
        if name not in names:
            raise UnknownNameError(f"{name!r} was not fitted; fitted channels: {', '.join(names)}")
        m, r = self.measured[case], self.residuals[case]
        if m.ndim == 1:
            return m, r
        j = names.index(name)
        return m[:, j], r[:, j]

    def drive_acceleration(self, case: int = 0) -> np.ndarray | None:
        """Carriage acceleration of ``case`` at its samples (m/s^2): the estimated carriage
        motion when it was estimated, else the excitation's ``rig.x_ddot`` input; None for a
        crank drive or a rig without a carriage input."""
        if self.carriage and self.carriage[case] is not None:
            return np.asarray(self.carriage[case])[2]
        exp = self.problem.experiments[case]
        dm = exp.derived
        if dm.nu and "rig.x_ddot" in dm.inputs:
            t = np.asarray(exp.case.time, float)
            return np.asarray(exp.excitation.values(t))[dm.inputs.index("rig.x_ddot")]
        return None

    @property
    def names(self) -> tuple[str, ...]:
        return self.problem.names

    @property
    def units(self) -> tuple[str, ...]:
        return tuple(e.unit for e in self.problem.estimated)

    def value(self, name: str) -> float:
        """Estimate of ``name`` (a label of :attr:`names`)."""
        return float(self.values[self._index(name)])

    def _index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise UnknownNameError(f"{name!r} was not estimated; estimated: "
                                   f"{', '.join(self.names)}") from None

    @property
    def free(self) -> tuple[bool, ...]:
        """Per estimate, whether it is inside its bounds (has a Wald standard error)."""
        return tuple(not self.at_bound or self.at_bound[i] is None for i in range(len(self.names)))

    @property
    def correlation(self) -> np.ndarray:
        """Correlations of the estimates (in [-1, 1]; NaN for estimates at a bound)."""
        d = np.sqrt(np.clip(np.diag(self.covariance), 0, None))
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.clip(np.nan_to_num(self.covariance / np.outer(d, d), nan=0.0, posinf=0.0,
                                      neginf=0.0), -1.0, 1.0)
        bound = ~np.array(self.free, bool)
        c[bound, :] = np.nan
        c[:, bound] = np.nan
        return c

    @property
    def case_values(self) -> list[dict[str, float]]:
        """All model parameter values of every case at the estimates."""
        return [self.problem.case_values(i, self.values) for i in range(len(self.problem.experiments))]

    def simulated(self, case: int = 0) -> np.ndarray:
        """Simulated force of ``case`` at the estimates (N)."""
        return self.measured[case] + self.residuals[case]

    def confounded(self) -> list[str]:
        """Sentences naming confounded parameter groups and the combination the data fix."""
        out = []
        for group, why in zip(self.identifiability.groups, self.identifiability.evidence):
            comps = {g.split(":")[-1].split(".")[0] for g in group}
            text = (f"{' and '.join(f'`{g}`' for g in group)} are confounded: the data fix them only "
                    f"together ({why})")
            combos = [k for k in self.derived if k.split(".")[0] in comps and k.endswith("frequency_hz")]
            for k in combos:
                v, se = self.derived[k]
                if math.isfinite(se):
                    text += f"; the identifiable combination is {k} = {v:.5g} +/- {se:.2g} Hz"
            out.append(text)
        return out

    # -- output ------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The JSON record of the fit (:func:`estimate.fitting.record.fit_record`, the form
        ``slosh fit --json`` writes, with provenance)."""
        from .record import fit_record

        return fit_record(self)

    def report(self) -> str:
        """A text fit report (:func:`estimate.fitting.record.report_text`): statistics with
        AIC and BIC, estimates with intervals, derived quantities, correlations,
        identifiability, notes, warnings."""
        from .record import report_text

        return report_text(self)
