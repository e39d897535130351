"""What a record would tell: the Fisher information of the estimated parameters from a drive,
predicted at the current estimates.

Two ways, one for the search and one for the verdict:

* :class:`Sensitivities`: the measured outputs and their exact derivatives with respect to
  the estimated parameters along a simulated record (forward sensitivities: one RK4 step of
  the derived model, :func:`derive.rk4_step`, differentiated by CasADi and carried through
  the record by ``mapaccum``; compiled once per model when a C compiler is available). The
  drive is taken as exact and each channel's noise as white at the level the fitted record
  showed: cheap (milliseconds), for ranking hundreds of candidates.
* :func:`fit_information`: the information the fit itself would have, from the NLP's
  Jacobians (:func:`estimate.fitting.linearise.linearise`) of a synthetic record of the drive
  at the current estimates with noise at the predicted levels: the carriage motion is then
  estimated from the noisy displacement and marginalised, as ``slosh fit`` does. The
  recommendation's predicted intervals come from it.

Information adds over independent records (:class:`Prediction`): the records already run
enter through the covariance of the fit (its inverse), the new one through its information.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from derive import OUTPUT_NAMES, DerivedModel, rk4_step
from derive.simulate import interval_inputs

__all__ = ["Sensitivities", "Record", "Prediction", "sensitivities", "fit_information",
           "prior_information", "swing_angles", "rig_inputs", "motion_inputs", "Z95"]

#: Two-sided 95 % normal quantile: a 95 % interval is +/- Z95 standard errors.
Z95 = 1.959963984540054


@dataclass(frozen=True)
class Record:
    """A simulated record at the current estimates: time (s), states ``(nx, n)``, measured
    outputs ``(channels, n)`` and their sensitivities ``(channels, n, ntheta)`` to the
    estimated parameters (per unit of each)."""

    time: np.ndarray = field(repr=False)
    states: np.ndarray = field(repr=False)
    outputs: np.ndarray = field(repr=False)
    jacobian: np.ndarray = field(repr=False)
    channels: tuple[str, ...]

    def information(self, noise: Sequence[float]) -> np.ndarray:
        """``sum_c J_c^T J_c / sigma_c^2`` for white noise of standard deviation ``noise``
        per channel (in the channels' units)."""
        J = self.jacobian / np.asarray(noise, float)[:, None, None]
        J = J.reshape(-1, J.shape[-1])
        return J.T @ J

    def rms(self) -> np.ndarray:
        """RMS of each measured output."""
        return np.sqrt(np.mean(self.outputs**2, axis=1))


class Sensitivities:
    """Measured outputs and their parameter sensitivities along a record of ``n`` intervals
    (``n + 1`` samples) of the derived model ``dm``, for the estimated parameters ``names``
    and the output ``channels``. Use :func:`sensitivities` (kept per model and length)."""

    def __init__(self, dm: DerivedModel, names: tuple[str, ...], channels: tuple[str, ...],
                 n: int) -> None:
        self.dm, self.names, self.channels, self.n = dm, names, channels, n
        npar, nth, nx = len(dm.parameter_names), len(names), dm.nx
        S = np.zeros((npar, nth))
        for j, name in enumerate(names):
            S[dm.parameter_names.index(name), j] = 1.0
        self._select = S
        x, Sx = ca.SX.sym("x", nx), ca.SX.sym("Sx", nx, nth)
        Uk, ug = ca.SX.sym("U", dm.nu * 3), ca.SX.sym("ug", dm.nu)
        p0, th = ca.SX.sym("p0", npar), ca.SX.sym("theta", nth)
        t, h = ca.SX.sym("t"), ca.SX.sym("h")
        p = p0 + ca.mtimes(ca.DM(S), th)
        xn = rk4_step(dm)(x, Uk, p, t, h)
        Sn = ca.mtimes(ca.jacobian(xn, x), Sx) + ca.jacobian(xn, th)
        z = ca.vertcat(x, ca.vec(Sx))
        step = ca.Function("design_step", [z, Uk, p0, th, t, h], [ca.vertcat(xn, ca.vec(Sn))])
        plain = ca.Function("design_state_step", [x, Uk, p0, th, t, h], [xn])
        y = ca.vertcat(*[dm.outputs(x, ug, p, t)[OUTPUT_NAMES.index(c)] for c in channels])
        dy = ca.mtimes(ca.jacobian(y, x), Sx) + ca.jacobian(y, th)
        out = ca.Function("design_outputs", [z, ug, p0, th, t], [y, ca.vec(dy)])
        UU, UG = ca.MX.sym("U", Uk.numel(), n), ca.MX.sym("Ug", ug.numel(), n + 1)
        P0, TH = ca.MX.sym("p0", npar), ca.MX.sym("theta", nth)
        T, H = ca.MX.sym("t", 1, n + 1), ca.MX.sym("h", 1, n)
        Z0 = ca.MX.sym("z0", z.numel())
        Z = ca.horzcat(Z0, step.mapaccum(n)(Z0, UU, P0, TH, T[:, :n], H))
        Y, DY = out.map(n + 1)(Z, UG, P0, TH, T)
        self._run = ca.Function("design_record", [Z0, UU, UG, P0, TH, T, H], [Z, Y, DY])
        X0 = ca.MX.sym("x0", nx)
        X = ca.horzcat(X0, plain.mapaccum(n)(X0, UU, P0, TH, T[:, :n], H))
        self._states = ca.Function("design_states", [X0, UU, P0, TH, T, H], [X])
        from derive import c_compiler, compiled

        if c_compiler():  # the whole record in C: no per-step call overhead (cached on disk)
            self._run, self._states = compiled(self._run), compiled(self._states)

    def _arguments(self, values: Mapping[str, float], time: np.ndarray):
        t = np.asarray(time, float)
        if t.size != self.n + 1:
            raise ValueError(f"expected {self.n + 1} times, got {t.size}")
        p = self.dm.parameter_vector(values)
        theta = np.array([values[k] for k in self.names])
        p0 = np.nan_to_num(p - self._select @ theta)
        return t, p0, theta

    def __call__(self, values: Mapping[str, float], inputs: tuple[np.ndarray, np.ndarray],
                 time: np.ndarray, x0: np.ndarray | None = None) -> Record:
        """The :class:`Record` driven by ``inputs`` (:func:`rig_inputs`) on ``time`` (s) from
        ``x0`` (default: at rest) for parameter ``values``."""
        t, p0, theta = self._arguments(values, time)
        U, Ug = inputs
        z0 = np.zeros(self.dm.nx * (1 + len(self.names)))
        if x0 is not None:
            z0[:self.dm.nx] = x0
        Z, Y, DY = self._run(z0, U, Ug, p0, theta, t.reshape(1, -1), np.diff(t).reshape(1, -1))
        nch, nth = len(self.channels), len(self.names)
        # row j nch + c of DY is d(channel c)/d(theta_j): vec of the (nch x nth) block
        J = np.asarray(DY).reshape(nth, nch, self.n + 1).transpose(1, 2, 0)
        return Record(t, np.asarray(Z)[:self.dm.nx], np.asarray(Y), J, self.channels)

    def states(self, values: Mapping[str, float], inputs: tuple[np.ndarray, np.ndarray],
               time: np.ndarray, x0: np.ndarray | None = None) -> np.ndarray:
        """The states ``(nx, n + 1)`` alone (no sensitivities: a fifth of the work)."""
        t, p0, theta = self._arguments(values, time)
        x = np.zeros(self.dm.nx) if x0 is None else x0
        X = self._states(x, inputs[0], p0, theta, t.reshape(1, -1), np.diff(t).reshape(1, -1))
        return np.asarray(X)


def rig_inputs(excitation, time: np.ndarray, nu: int) -> tuple[np.ndarray, np.ndarray]:
    """The inputs of an excitation (a :class:`derive.Excitation`, or ``None`` for a rig that
    takes none) at the RK4 stage times of every interval and on the grid ``time``."""
    t = np.asarray(time, float)
    n = t.size - 1
    if not nu:
        return np.zeros((0, n)), np.zeros((0, n + 1))
    return (interval_inputs(excitation, t, np.array([0.0, 0.5, 1.0]), nu),
            np.asarray(excitation.values(t), float).reshape(nu, t.size))


def motion_inputs(motion: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inputs of a carriage motion ``(3, 2 n + 1)`` given on the half-interval grid
    (the RK4 stage times of a uniform grid): per interval the three stages, and the grid."""
    n = (motion.shape[1] - 1) // 2
    stages = np.stack([motion[:, 0:-1:2], motion[:, 1::2], motion[:, 2::2]], axis=0)
    return stages.reshape(3 * motion.shape[0], n), np.ascontiguousarray(motion[:, ::2])


def sensitivities(dm: DerivedModel, names: Sequence[str], channels: Sequence[str],
                  n: int) -> Sensitivities:
    """The :class:`Sensitivities` of ``dm`` for ``names``, ``channels`` and ``n`` intervals,
    built once per derived structure (kept with its functions,
    :meth:`derive.DerivedModel.memo`)."""
    key = ("design_sensitivities", tuple(names), tuple(channels), n)
    return dm.memo(key, lambda: Sensitivities(dm, tuple(names), tuple(channels), n))


def swing_angles(dm: DerivedModel, states: np.ndarray) -> dict[str, np.ndarray]:
    """The swing of every pendulum of ``dm`` from its rest direction (rad) along ``states``
    ``(nx, n)``: ``|theta|`` of a planar pendulum, ``sqrt(alpha^2 + beta^2)`` of a spherical
    one."""
    out = {}
    for comp in dm.model.components:
        angles = getattr(comp, "hinge_angles", ())
        rows = [dm.states.index(f"{comp.name}.{a}") for a in angles
                if f"{comp.name}.{a}" in dm.states]
        if rows:
            out[comp.name] = np.sqrt(np.sum(states[rows] ** 2, axis=0))
    return out


@dataclass(frozen=True)
class Prediction:
    """Covariance of the estimated parameters ``names`` at ``values`` after adding a record's
    information to what is known, and the intervals of the ``targets``.

    ``prior`` (the inverse of the current covariance) and ``information`` are per unit of
    each parameter. The sum is inverted in coordinates standardised by ``scales`` (the
    current standard errors: the combinations the data already fix are then well
    conditioned), its eigenvalues floored at 1e-12 of the largest (a direction no record
    determines keeps a huge finite variance)."""

    names: tuple[str, ...]
    values: np.ndarray
    covariance: np.ndarray = field(repr=False)
    targets: tuple[str, ...]

    @classmethod
    def of(cls, names: Sequence[str], values: np.ndarray, prior: np.ndarray,
           information: np.ndarray | None, targets: Sequence[str],
           scales: np.ndarray) -> "Prediction":
        s = np.asarray(scales, float)
        F = prior if information is None else prior + information
        std = F * np.outer(s, s)
        lam, V = np.linalg.eigh(0.5 * (std + std.T))
        lam = np.maximum(lam, 1e-12 * max(lam.max(), 1e-300))
        cov = (V / lam) @ V.T * np.outer(s, s)
        return cls(tuple(names), np.asarray(values, float), cov, tuple(targets))

    def stderr(self, name: str) -> float:
        i = self.names.index(name)
        return float(math.sqrt(max(self.covariance[i, i], 0.0)))

    def relative_halfwidth(self, name: str) -> float:
        """Half-width of the 95 % interval of ``name`` over its value."""
        i = self.names.index(name)
        return Z95 * self.stderr(name) / abs(self.values[i]) if self.values[i] else math.inf

    def criterion(self, kind: str) -> float:
        """``"D"``: log det of the targets' relative covariance (the volume of their joint
        confidence region); ``"A"``: the sum of their relative variances. Smaller is better."""
        idx = [self.names.index(t) for t in self.targets]
        v = self.values[idx]
        C = self.covariance[np.ix_(idx, idx)] / np.outer(v, v)
        if kind == "D":
            sign, logdet = np.linalg.slogdet(C)
            return float(logdet) if sign > 0 else -math.inf
        return float(np.trace(C))


def prior_information(names: Sequence[str], cov_names: Sequence[str],
                      covariance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The information of the records already run, per unit of each parameter of ``names``:
    the inverse of the fit's covariance (over ``cov_names``), inverted as a correlation
    matrix; parameters the covariance leaves out (at a bound) get none. Returns it with
    the standard errors (NaN where the covariance has none)."""
    n = len(names)
    F = np.zeros((n, n))
    se = np.full(n, np.nan)
    idx = [names.index(c) for c in cov_names if c in names]
    keep = [k for k, c in enumerate(cov_names) if c in names]
    if not idx:
        return F, se
    C = np.asarray(covariance, float)[np.ix_(keep, keep)]
    d = np.sqrt(np.clip(np.diag(C), 1e-300, None))
    lam, V = np.linalg.eigh(0.5 * (C + C.T) / np.outer(d, d))
    inv = (V * np.where(lam > 1e-14 * lam.max(), 1.0 / np.maximum(lam, 1e-300), 0.0)) @ V.T
    F[np.ix_(idx, idx)] = inv / np.outer(d, d)
    se[idx] = d
    return F, se


def fit_information(case, model, values: Mapping[str, float], names: Sequence[str],
                    record: Record, displacement: np.ndarray | None,
                    noise: Sequence[float], displacement_noise: float | None, *,
                    seed: int = 0) -> np.ndarray:
    """The information (per unit of each parameter ``names``) a fit of ``model`` would take
    from a record of ``case``'s rig with the outputs of ``record`` (simulated at the current
    ``values``) plus white noise ``noise`` per channel and, on the lateral rig, the carriage
    ``displacement`` (m) with ``displacement_noise`` (m): the Gauss-Newton information of the
    NLP at the current estimates (states, carriage motion and free initial states
    marginalised), over the residual variance of the noisy record."""
    from ..fitting.linearise import linearise
    from ..fitting.problem import FitProblem

    rng = np.random.default_rng(seed)
    t = record.time
    noisy = record.outputs + rng.normal(size=record.outputs.shape) * np.asarray(noise)[:, None]
    test = replace(case.test, id=f"{case.test.id}-design", starts_at_rest=True)
    if case.test.rig == "lateral":
        x = displacement + rng.normal(0.0, displacement_noise, t.size)
        synthetic = replace(case, test=test, time=t, displacement=x, force=noisy[0])
    else:
        synthetic = replace(case, test=test, time=t,
                            columns=dict(zip(record.channels, noisy)))
    params = {p.name for p in model.parameters}
    rig = {k for k in params if k.startswith("rig.")}
    hold = {k: v for k, v in values.items() if k in params and k not in names and k not in rig}
    problem = FitProblem.build(synthetic, model, estimate=list(names),
                               initial={k: values[k] for k in names}, hold=hold)
    lin = linearise(problem)
    # the residual variance the fit will scale its covariance by: the noise over the
    # channel scales it divides each residual by (1 when those are the noise levels)
    scales = problem.channel_scales(0)
    variance = float(np.mean([(sd / scales[c]) ** 2 for c, sd in zip(record.channels, noise)]))
    return lin.information / np.outer(lin.scales, lin.scales) / variance
