"""Monte Carlo of a fitted analog over its parameters' uncertainty.

Parameters are drawn from the fit's covariance (a multivariate normal truncated to the
parameter bounds by rejection: draws outside the bounds are redrawn, never clipped), all in
this process from one seed. An estimate the fit holds on a physical bound (a hinge spring
at 0, the masses on the liquid budget) leaves it by a half-normal amount of its one-sided
standard deviation, the other estimates moving with it along the fit's regression
(``covariance.off_bounds``): the posterior of a flat prior on the physical side when the
data put the estimate on the bound, so the draws spread as far off the bound as the fit's
intervals reach. A pendulum far heavier than its tank mode's prediction (the fit's
``covariance.to_predicted_modes``: a mode the record may not hold, fitted to noise) moves
half the draws to the refit with that mass at the prediction, the others staying at the
fit: the two ends whose intervals the fit's intervals join. The draws are simulated in
fixed-size batches (one CasADi function mapped over the batch, compiled to C when a
compiler exists) on an executor (:mod:`estimate.executor`). Batches are deterministic, so
results are identical whichever executor runs them.
"""

from __future__ import annotations

import hashlib
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from analogs.errors import InputError
from derive import DerivedModel, Excitation, NoExcitation, rk4_step

from ..executor import Executor, LocalExecutor, chunks
from ..fitting.record import Fit, read_fit
from .montecarlo_result import PERCENTILES, MonteCarloResult

__all__ = ["Fit", "read_fit", "draw_parameters", "MonteCarlo", "MonteCarloResult",
           "monte_carlo", "derived_quantities", "PERCENTILES"]



def draw_parameters(fit: Fit, samples: int, *, seed: int | None = 0,
                    max_rounds: int = 200) -> tuple[np.ndarray, float]:
    """``samples`` draws of the fit's parameters (:attr:`Fit.draw_names`), truncated to
    their bounds: ``mean + L z + sum_k |z_k| move_k + sum_j u_j shift_j`` (``L L^T`` the
    covariance, ``move_k`` the estimates' move off the ``k``-th bound per standard
    deviation, ``shift_j`` their move with the ``j``-th conflicting mode at its prediction,
    ``u_j`` 0 or 1 with equal odds); the estimates held on a bound stay on it when a move
    pushes them through it.

    Returns
    -------
    draws : array, shape (samples, len(fit.draw_names))
    acceptance : float
        Fraction of normal draws inside the bounds.

    Raises
    ------
    ValueError
        When the covariance is not symmetric positive semi-definite, or fewer than one in
        ``max_rounds`` draws lands inside the bounds.
    """
    if samples < 1:
        raise InputError(f"samples must be at least 1, got {samples}")
    if not fit.covariance_names:
        raise InputError(f"{fit.path}: the fit has no covariance; Monte Carlo needs "
                         "`covariance.parameters` and `covariance.matrix`")
    C = fit.covariance
    # symmetric up to rounding: records written before fits symmetrised their sandwich
    # covariance hold 1e-8 relative asymmetries
    scale = np.sqrt(np.abs(np.outer(np.diag(C), np.diag(C))))
    if not np.all(np.isfinite(C)) or np.any(np.abs(C - C.T) > 1e-6 * scale):
        raise InputError(f"{fit.path}: covariance.matrix must be symmetric and finite")
    w, V = np.linalg.eigh((C + C.T) / 2)
    if w.min() < -1e-10 * max(w.max(), 0.0):
        raise InputError(f"{fit.path}: covariance.matrix is not positive semi-definite "
                         f"(smallest eigenvalue {w.min():.3g})")
    names = fit.draw_names
    L = np.zeros((len(names), len(names)))
    k = len(fit.covariance_names)
    L[:k, :k] = V * np.sqrt(np.clip(w, 0.0, None))
    M, S = (np.array([[move.get(n, 0.0) for n in names] for _, move in moves]).reshape(
        -1, len(names)) for moves in (fit.off_bounds, fit.to_modes))
    mu = np.array([fit.values[n] for n in names])
    lo = np.array([fit.lower[n] for n in names])
    hi = np.array([fit.upper[n] for n in names])
    # the estimates outside the covariance are held on a bound: the moves of another bound
    # or mode can push them on through it, where they stay (the data put them there)
    held = np.array([n not in fit.covariance_names for n in names], bool)
    rng = np.random.default_rng(seed)
    out, drawn = [], 0
    need = samples
    for _ in range(max_rounds):
        rows = max(need, 64)
        z = rng.standard_normal((rows, len(names)))
        x = mu + z @ L.T + np.abs(rng.standard_normal((rows, M.shape[0]))) @ M
        if S.shape[0]:  # a record without conflicting modes draws the same numbers as before
            x = x + rng.integers(0, 2, size=(rows, S.shape[0])) @ S
        x[:, held] = np.clip(x[:, held], lo[held], hi[held])
        drawn += x.shape[0]
        ok = np.all((x >= lo) & (x <= hi), axis=1)
        out.append(x[ok][:need])
        need -= out[-1].shape[0]
        if need == 0:
            break
    else:
        raise InputError(f"only {samples - need} of {samples} draws fell inside the parameter "
                         f"bounds after {drawn} tries; check the covariance and the bounds")
    accepted = sum(o.shape[0] for o in out)
    return np.vstack(out), accepted / drawn


def derived_quantities(dm: DerivedModel, P: np.ndarray) -> dict[str, np.ndarray]:
    """Per draw, every quantity the model's components derive (columns of ``P`` in
    ``dm.parameter_names`` order; :meth:`analogs.Model.derived_quantities`), e.g. the
    small-amplitude frequency and damping ratio of each pendulum including hinge and
    diaphragm terms."""
    values = {n: P[:, i] for i, n in enumerate(dm.parameter_names)}
    found = dm.model.derived_quantities(values)
    return {k: np.broadcast_to(np.asarray(v, float), (P.shape[0],)).copy()
            for k, (v, _) in found.items()}


def _stage_inputs(exc: Excitation, t: np.ndarray, nu: int) -> tuple[np.ndarray, np.ndarray]:
    """Inputs at the RK4 stage times ``(3 nu, n)`` (stage by stage in each column) and on
    the grid ``(nu, n + 1)``, as :func:`derive.simulate` samples them."""
    from derive.simulate import interval_inputs

    U = interval_inputs(exc, t, np.array([0.0, 0.5, 1.0]), nu)
    return U, np.asarray(exc.values(t), float).reshape(nu, t.size)


def _batch_function(dm: DerivedModel, t: np.ndarray, exc: Excitation, x0: np.ndarray,
                    outputs: tuple[int, ...], batch: int) -> ca.Function:
    """``batch(P) -> Y``: ``P`` (np x batch) parameter columns; ``Y`` ((n+1)*len(outputs) x
    batch) the selected outputs on the grid, output by output, one column per draw (RK4 on
    the grid, inputs at the stage times as constants)."""
    n = t.size - 1
    U, Ug = _stage_inputs(exc, t, dm.nu)
    step = rk4_step(dm, 1)
    x = ca.SX.sym("x", dm.nx)
    u = ca.SX.sym("u", 3 * dm.nu)
    p = ca.SX.sym("p", len(dm.parameter_names))
    tt = ca.SX.sym("t")
    h = ca.SX.sym("h")
    one = ca.Function("one", [x, u, p, tt, h], [step(x, ca.reshape(u, step.size_in(1)), p, tt, h)])
    ug = ca.SX.sym("ug", dm.nu)
    y = dm.outputs(x, ug, p, tt)
    out = ca.Function("out", [x, ug, p, tt], [ca.vertcat(*[y[i] for i in outputs])])
    P = ca.MX.sym("p", p.numel())
    X0 = ca.DM(x0)
    X = ca.horzcat(X0, one.mapaccum("horizon", n)(X0, ca.DM(U), P, ca.DM(t[:-1]).T,
                                                   ca.DM(np.diff(t)).T))
    Y = out.map(n + 1)(X, ca.DM(Ug), P, ca.DM(t).T)
    single = ca.Function("mc_single", [P], [ca.vec(Y.T)])
    return single.map("mc_batch", "serial", batch, [], [])


_WORKER_CACHE: dict[str, ca.Function] = {}


@dataclass(frozen=True)
class _Task:
    """One batch: its parameter columns; the serialized batch function is shared."""

    key: str
    P: np.ndarray
    compile: bool


def _run_task(task: _Task, shared: str) -> np.ndarray:
    fn = _WORKER_CACHE.get(task.key)
    if fn is None:
        fn = ca.Function.deserialize(shared)
        if task.compile:
            from derive import compiled

            fn = compiled(fn)
        _WORKER_CACHE[task.key] = fn
    return np.asarray(fn(task.P)).T


@dataclass(frozen=True)
class MonteCarlo:
    """A Monte Carlo problem.

    Attributes
    ----------
    derived : DerivedModel
        The model simulated for every draw.
    time : ndarray
        The output grid (s).
    excitation : Excitation or None
        The rig's input signals (None: a rig that needs none).
    fit : Fit
        The fit record whose estimates and covariance the draws come from
        (:func:`~estimate.fitting.record.read_fit`).
    fixed : mapping
        Parameter values that are not drawn (the case's rig values), over the fit's.
    outputs : tuple of str, optional
        The outputs kept (default: the channels the rig measures).
    """

    derived: DerivedModel
    time: np.ndarray
    excitation: Excitation | None
    fit: Fit
    fixed: Mapping[str, float] = field(default_factory=dict)
    outputs: tuple[str, ...] | None = None

    def base_vector(self) -> np.ndarray:
        """Parameter vector of the fit's values over ``fixed`` (rig values of the case)."""
        dm = self.derived
        known = set(dm.parameter_names)
        values = {k: v for k, v in self.fit.values.items() if k in known}
        return dm.parameter_vector({**values, **self.fixed}, outputs=self._outputs())

    def _outputs(self) -> tuple[str, ...]:
        return tuple(self.outputs or self.derived.measured)

    def run(self, samples: int, *, seed: int | None = 0, executor: Executor | None = None,
            batch_size: int = 256, compile: bool = True,
            progress: bool | None = None) -> MonteCarloResult:
        """Draw ``samples`` parameter sets and simulate them in batches of ``batch_size``.

        Parameters
        ----------
        samples : int
            Number of draws.
        seed : int, optional
            Seed of NumPy's default generator for the draws (default 0).
        executor : Executor, optional
            Where batches run (default: :class:`~estimate.executor.LocalExecutor`).
        batch_size : int, default 256
            Draws per batch (one mapped CasADi function; the last batch is padded).
        compile : bool, default True
            Compile the batch function to C (cached on disk) when a compiler exists.
        progress : bool, optional
            Show a bar of the finished batches; default: on a terminal only.
        """
        start = _time.perf_counter()
        executor = executor or LocalExecutor()
        dm = self.derived
        names = self._outputs()
        for n in names:
            dm.output_index(n)
        _check_memory(samples, len(names), np.size(self.time))
        drawn = self.fit.draw_names
        unknown = [n for n in drawn if n not in dm.parameter_names]
        if unknown:
            raise InputError(f"covariance parameters {', '.join(unknown)} are not parameters of "
                             f"the model ({', '.join(dm.parameter_names)})")
        base = self.base_vector()
        draws, acceptance = draw_parameters(self.fit, samples, seed=seed)
        cols = [dm.parameter_names.index(n) for n in drawn]
        # the draws, then the nominal (the fit's values) as one more column
        P = np.tile(np.nan_to_num(base), (samples + 1, 1))
        P[:samples, cols] = draws
        t = np.asarray(self.time, float)
        exc = self.excitation if self.excitation is not None else NoExcitation(size=dm.nu)
        batch = max(1, min(batch_size, samples + 1))
        fn = _batch_function(dm, t, exc, np.zeros(dm.nx), tuple(dm.output_index(n) for n in names),
                             batch)
        text = fn.serialize()
        key = hashlib.sha256(text.encode()).hexdigest()[:24]
        tasks = []
        for a, b in chunks(samples + 1, batch):
            Pb = P[a:b]
            if Pb.shape[0] < batch:
                Pb = np.vstack([Pb, np.repeat(Pb[-1:], batch - Pb.shape[0], axis=0)])
            tasks.append(_Task(key, np.ascontiguousarray(Pb.T), compile))
        from .._progress import progress as bar

        with bar(total=len(tasks), desc="Monte Carlo", unit="batch", enabled=progress) as b:
            results = executor.map(_run_task, tasks, shared=text, done=b.update)
        Y = np.vstack(results)[:samples + 1]  # (samples + 1, len(names) * (n + 1)), output by output
        nt = t.size
        outputs = {name: Y[:samples, i * nt:(i + 1) * nt] for i, name in enumerate(names)}
        nominal = {name: Y[samples, i * nt:(i + 1) * nt] for i, name in enumerate(names)}
        derived = {f"peak_{name}": np.max(np.abs(v), axis=1) for name, v in outputs.items()}
        derived |= derived_quantities(dm, P[:samples])
        return MonteCarloResult(
            time=t, parameter_names=drawn, draws=draws, outputs=outputs,
            derived=derived, seed=seed, acceptance=acceptance,
            seconds=_time.perf_counter() - start, nominal=nominal,
            executor=f"{type(executor).__name__} ({executor.workers} worker"
                     f"{'s' if executor.workers > 1 else ''})")


#: Copies of the simulated outputs held at once (results, their stack, percentile sorting).
_OUTPUT_COPIES = 3


def _check_memory(samples: int, outputs: int, n_time: int) -> None:
    """Refuse a run whose simulated outputs would not fit the memory budget."""
    from ..data.budget import BUDGET_VARIABLE, memory_budget, size_text

    need = _OUTPUT_COPIES * 8 * samples * outputs * n_time
    budget = memory_budget()
    if need > budget:
        most = budget // (_OUTPUT_COPIES * 8 * outputs * n_time)
        raise InputError(f"{samples} draws of {outputs} output(s) over {n_time} time samples "
                         f"need about {size_text(need)}, over the memory budget of "
                         f"{size_text(budget)} (set {BUDGET_VARIABLE} to change it): use at "
                         f"most {most} draws, or a shorter or decimated case")


def monte_carlo(derived: DerivedModel, time: np.ndarray, excitation: Excitation | None,
                fit: Fit, samples: int, *, fixed: Mapping[str, float] | None = None,
                outputs: Sequence[str] | None = None, seed: int | None = 0,
                executor: Executor | None = None, batch_size: int = 256,
                compile: bool = True, progress: bool | None = None) -> MonteCarloResult:
    """Run :class:`MonteCarlo` (``derived``, ``time``, ``excitation``, ``fit``, ``fixed``,
    ``outputs``: its attributes) in one call; see :meth:`MonteCarlo.run`.

    Examples
    --------
    >>> from estimate.data import load_case                       # doctest: +SKIP
    >>> from estimate.data.experiment import experiment                 # doctest: +SKIP
    >>> from estimate.data.models import model_from_spec                # doctest: +SKIP
    >>> fit = read_fit("A1_fit.json")                               # doctest: +SKIP
    >>> case = load_case("A1.toml")                                 # doctest: +SKIP
    >>> exp = experiment(case, model_from_spec(fit.model_spec, case))  # doctest: +SKIP
    >>> res = monte_carlo(exp.derived, case.time, exp.excitation, fit, 1000,
    ...                   fixed=exp.fixed)                           # doctest: +SKIP
    """
    problem = MonteCarlo(derived, np.asarray(time, float), excitation, fit, dict(fixed or {}),
                         tuple(outputs) if outputs else None)
    return problem.run(samples, seed=seed, executor=executor, batch_size=batch_size,
                       compile=compile, progress=progress)
