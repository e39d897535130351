"""Simulation of a derived model under a prescribed excitation, through CasADi."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from analogs.errors import InputError, UnknownNameError
from analogs.model import Model

from .derived import OUTPUT_NAMES, DerivedModel
from .excitation import Excitation, NoExcitation

__all__ = ["RK4", "Adaptive", "Simulation", "simulate", "simulate_outputs", "rk4_step",
           "interval_inputs"]


@dataclass(frozen=True)
class RK4:
    """Fixed-step classical Runge-Kutta, ``substeps`` steps per output interval.

    Code-generatable (used for C export and multiple shooting). The inputs are sampled
    at the stage times, so the result matches an exact integration to O(h^4).
    ``compiled=True`` generates C for the whole run and compiles it once (cached on disk,
    see :mod:`derive.cache`); it needs a C compiler and pays off for repeated runs.
    """

    substeps: int = 1
    compiled: bool = False

    def __post_init__(self) -> None:
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise InputError(f"RK4.substeps must be a positive integer, got {self.substeps!r}")


@dataclass(frozen=True)
class Adaptive:
    """Variable-step integrator from SUNDIALS through CasADi: ``method`` ``"cvodes"``
    (BDF/Adams, default) or ``"idas"``, with relative and absolute tolerances ``rtol``
    (default 1e-10) and ``atol`` (1e-12); ``options`` are passed on to CasADi's
    ``integrator`` (e.g. ``{"max_num_steps": 10000}``)."""

    method: str = "cvodes"
    rtol: float = 1e-10
    atol: float = 1e-12
    options: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class Simulation:
    """States and outputs on the requested time grid.

    ``states`` has shape ``(len(time), nx)`` (coordinates in rad or m, then rates);
    ``outputs`` has shape ``(len(time), 8)`` in :data:`derive.OUTPUT_NAMES` order (N, N m, J);
    ``inputs`` holds the excitation values used. ``time`` is the grid (s);
    ``state_names``, ``input_names`` and ``output_names`` name the columns.
    """

    time: np.ndarray
    states: np.ndarray
    outputs: np.ndarray
    inputs: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...] = OUTPUT_NAMES

    def output(self, name: str) -> np.ndarray:
        """The output channel ``name`` (e.g. ``"force_x"``) on the time grid."""
        if name not in self.output_names:
            raise UnknownNameError(f"no output {name!r}; outputs are {', '.join(self.output_names)}")
        return self.outputs[:, self.output_names.index(name)]

    def state(self, name: str) -> np.ndarray:
        """The state ``name`` (e.g. ``"p1.theta"`` or ``"p1.theta_dot"``) on the time grid."""
        if name not in self.state_names:
            raise UnknownNameError(f"no state {name!r}; states are {', '.join(self.state_names)}")
        return self.states[:, self.state_names.index(name)]


def rk4_step(dm: DerivedModel, substeps: int = 1) -> ca.Function:
    """``step(x, U, p, t, h) -> x_next`` of the derived model ``dm``: ``substeps`` RK4
    steps over ``[t, t + h]``.

    ``U`` (a column of ``nu * (2 substeps + 1)`` values) stacks the input vectors at the
    ``2 * substeps + 1`` equally spaced stage times of the interval, first time first.
    """

    def build() -> ca.Function:
        x0 = ca.SX.sym("x", dm.nx)
        Uv = ca.SX.sym("U", dm.nu * (2 * substeps + 1))
        U = ca.reshape(Uv, dm.nu, 2 * substeps + 1)
        p = ca.SX.sym("p", len(dm.parameter_names))
        t = ca.SX.sym("t")
        h = ca.SX.sym("h")
        hs = h / substeps
        x = x0
        for i in range(substeps):
            ua, um, ub = U[:, 2 * i], U[:, 2 * i + 1], U[:, 2 * i + 2]
            ti = t + i * hs
            k1 = dm.rhs(x, ua, p, ti)
            k2 = dm.rhs(x + hs / 2 * k1, um, p, ti + hs / 2)
            k3 = dm.rhs(x + hs / 2 * k2, um, p, ti + hs / 2)
            k4 = dm.rhs(x + hs * k3, ub, p, ti + hs)
            x = x + hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return ca.Function("rk4_step", [x0, Uv, p, t, h], [x], ["x", "U", "p", "t", "h"],
                           ["x_next"])

    return dm.memo(("rk4_step", substeps), build)


def _simulator(dm: DerivedModel, exc: Excitation, substeps: int, n: int,
               outputs: tuple[int, ...], compile_: bool) -> ca.Function:
    """One CasADi function for a whole fixed-step run.

    ``sim(x0, U, p, t, h, Ug) -> (X, Y)``: ``U`` the inputs at the RK4 stage times and ``Ug``
    at the grid (both empty when the excitation is analytic and evaluated inside), ``t``
    and ``h`` the interval start times and lengths, ``X`` the states on the grid and ``Y``
    the selected outputs.
    """
    key = ("sim", exc if exc.analytic else None, substeps, n, outputs, compile_)
    return dm.memo(key, lambda: _build_simulator(dm, exc, substeps, n, outputs, compile_))


#: Steps per call of the fixed-step simulator: its CasADi function is built once per model
#: for this many steps and called chunk after chunk (one built for a whole 30,000-step
#: record took 0.5 s, its run 0.1 s). A last, shorter chunk is padded with zero-length
#: steps, through which RK4 carries the state unchanged.
CHUNK_STEPS = 1024


def _rk4_run(dm: DerivedModel, exc: Excitation, substeps: int, outputs: tuple[int, ...],
             compile_: bool, x0: np.ndarray, U: np.ndarray, p: np.ndarray, t: np.ndarray,
             h: np.ndarray, Ug: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States ``(nx, runs, len(t))`` and outputs ``(outputs, runs, len(t))`` of fixed-step
    runs under the same inputs, one per column of ``x0`` (``nx x runs``) and ``p``
    (``parameters x runs``), :data:`CHUNK_STEPS` steps per call of :func:`_simulator`
    (mapped over the runs, the inputs shared; other arguments as it takes them)."""
    n, runs = h.size, p.shape[1]
    c = min(n, CHUNK_STEPS)
    fn = _simulator(dm, exc, substeps, c, outputs, compile_)
    if runs > 1:
        key = ("sim runs", exc if exc.analytic else None, substeps, c, outputs, compile_, runs)
        # inputs U, t, h and Ug are the same for every run: passed once, not repeated
        fn = dm.memo(key, lambda: fn.map("runs", "serial", runs, [1, 3, 4, 5], []))
    # evaluated through a buffer: arguments read from and results written to NumPy
    # arrays in place (a DM result's conversion took as long as the runs)
    buffer, evaluate = fn.buffer()
    results = [np.empty(fn.nnz_out(i)) for i in range(2)]
    for i, r in enumerate(results):
        buffer.set_res(i, memoryview(r))
    Xs, Ys, x = [], [], x0
    for k0 in range(0, n, c):
        k = min(c, n - k0)  # real steps in this chunk
        Uk, hk, tk, Ugk = U[:, k0:k0 + k], h[k0:k0 + k], t[k0:k0 + k + 1], Ug[:, k0:k0 + k + 1]
        if k < c:
            pad = c - k
            Uk = np.hstack([Uk, np.repeat(Uk[:, -1:], pad, axis=1)])
            Ugk = np.hstack([Ugk, np.repeat(Ugk[:, -1:], pad, axis=1)])
            hk, tk = np.r_[hk, np.zeros(pad)], np.r_[tk, np.full(pad, tk[-1])]
        # column-major values, kept referenced until the evaluation
        args = [np.asarray(a, float).ravel(order="F") for a in (x, Uk, p, tk, hk, Ugk)]
        for i, a in enumerate(args):
            buffer.set_arg(i, memoryview(a))
        evaluate()
        # the runs' results side by side: (rows, runs * (c + 1)), column-major
        X = results[0].reshape(runs, c + 1, -1).transpose(2, 0, 1)
        Y = results[1].reshape(runs, c + 1, -1).transpose(2, 0, 1)
        first = 0 if k0 == 0 else 1  # the previous chunk gave this chunk's first sample
        Xs.append(X[:, :, first:k + 1].copy())
        Ys.append(Y[:, :, first:k + 1].copy())
        x = X[:, :, k].copy()
    return np.concatenate(Xs, axis=2), np.concatenate(Ys, axis=2)


def _build_simulator(dm: DerivedModel, exc: Excitation, substeps: int, n: int,
                     outputs: tuple[int, ...], compile_: bool) -> ca.Function:
    """The function :func:`_simulator` keeps with ``dm``."""
    m = 2 * substeps + 1
    x = ca.SX.sym("x", dm.nx)
    p = ca.SX.sym("p", len(dm.parameter_names))
    t = ca.SX.sym("t")
    h = ca.SX.sym("h")
    if exc.analytic:
        Uk = ca.SX(0, 1)
        U = ca.horzcat(*[exc.symbolic(t + h * j / (m - 1)) for j in range(m)])
        ug = ca.SX(0, 1)
        u_grid = exc.symbolic(t)
    else:
        Uk = ca.SX.sym("U", dm.nu * m)
        U = ca.reshape(Uk, dm.nu, m)
        ug = ca.SX.sym("ug", dm.nu)
        u_grid = ug
    step = ca.Function("step", [x, Uk, p, t, h], [rk4_step(dm, substeps)(x, ca.vec(U), p, t, h)])
    y = dm.outputs(x, u_grid, p, t)
    out = ca.Function("out", [x, ug, p, t], [ca.vertcat(*[y[i] for i in outputs])])
    horizon = step.mapaccum("horizon", n)
    out_map = out.map(n + 1)
    X0 = ca.MX.sym("x0", dm.nx)
    UU = ca.MX.sym("U", Uk.numel(), n)
    P = ca.MX.sym("p", p.numel())
    T = ca.MX.sym("t", 1, n + 1)
    H = ca.MX.sym("h", 1, n)
    UG = ca.MX.sym("Ug", ug.numel(), n + 1)
    X = ca.horzcat(X0, horizon(X0, UU, P, T[:, :n], H))
    Y = out_map(X, UG, P, T)
    fn = ca.Function("simulate_rk4", [X0, UU, P, T, H, UG], [X, Y],
                     ["x0", "U", "p", "t", "h", "Ug"], ["X", "Y"])
    if compile_:
        from ._compile import compiled

        fn = compiled(fn)
    return fn


def _arguments(model: DerivedModel | Model, t, excitation: Excitation | None
               ) -> tuple[DerivedModel, np.ndarray, Excitation]:
    """The derived model (a ``Model`` derived through the cache), the time grid as a
    checked 1-D array and the excitation (``None``: none) checked against the model."""
    if isinstance(model, Model):
        from ._derive import derive

        model = derive(model)
    t = np.asarray(t, float).ravel()
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise InputError("t must be a strictly increasing array of at least 2 times (s)")
    exc = excitation if excitation is not None else NoExcitation(size=model.nu)
    if exc.size != model.nu:
        raise InputError(
            f"the excitation supplies {exc.size} input values but the model takes {model.nu} "
            f"({', '.join(model.inputs) or 'none'})"
        )
    return model, t, exc


def _sampled_inputs(dm: DerivedModel, exc: Excitation, t: np.ndarray, substeps: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The simulator's ``U`` (inputs at the RK4 stage times) and ``Ug`` (at the grid);
    empty for an analytic excitation, which the simulator evaluates inside."""
    n = t.size - 1
    if exc.analytic:
        return np.zeros((0, n)), np.zeros((0, n + 1))
    U = interval_inputs(exc, t, np.arange(2 * substeps + 1) / (2 * substeps), dm.nu)
    return U, exc.values(t).reshape(dm.nu, t.size)


def _initial_state(dm: DerivedModel, x0) -> np.ndarray:
    if x0 is None:
        return np.zeros(dm.nx)
    if isinstance(x0, Mapping):
        unknown = sorted(set(x0) - set(dm.states))
        if unknown:
            raise UnknownNameError(f"unknown state {unknown}; states are {', '.join(dm.states)}")
        return np.array([float(x0.get(s, 0.0)) for s in dm.states])
    arr = np.asarray(x0, float).ravel()
    if arr.size != dm.nx:
        raise InputError(f"x0 must have {dm.nx} values ({', '.join(dm.states)}), got {arr.size}")
    return arr


def simulate(
    model: DerivedModel | Model,
    params: Mapping[str, float] | None,
    t: np.ndarray,
    excitation: Excitation | None = None,
    *,
    integrator: RK4 | Adaptive = RK4(),
    x0: Mapping[str, float] | np.ndarray | None = None,
    outputs: tuple[str, ...] | None = None,
) -> Simulation:
    """Simulate ``model`` on the time grid ``t`` (s) under ``excitation``.

    Parameters
    ----------
    model : DerivedModel or analogs.Model
        A derived model (a ``Model`` is derived first, through the cache).
    params : mapping
        Parameter values by dotted name (over the declared defaults); see
        :meth:`DerivedModel.parameter_vector`.
    t : array
        Increasing output times (s); the simulation starts at ``t[0]`` from ``x0``.
    excitation : Excitation, optional
        Rig input signals; ``None`` means a tank at rest (or a rig needing no input).
    integrator : RK4 or Adaptive
        ``RK4(substeps)``, fixed steps on the grid; or ``Adaptive(...)`` (CVODES).
    x0 : mapping or array, optional
        Initial state (default: at rest, all zero).
    outputs : tuple of str, optional
        Output channels to compute; their parameters must have values. Default: all
        outputs, with values required only for the rig's measured channels (outputs whose
        parameters are missing come out NaN).

    Examples
    --------
    >>> import numpy as np
    >>> from analogs import LateralRig, FixedMass, Pendulum
    >>> from derive import Sine, simulate
    >>> sim = simulate(LateralRig() + FixedMass("fixed") + Pendulum("p1"),
    ...                {"rig.dry_mass": 1.2, "fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.057},
    ...                np.linspace(0, 1, 101), Sine(0.005, 2.0))
    >>> sim.output("force_x").shape
    (101,)
    """
    dm, t, exc = _arguments(model, t, excitation)
    p = dm.parameter_vector(params, outputs=outputs)
    x_init = _initial_state(dm, x0)
    names = OUTPUT_NAMES if outputs is None else tuple(outputs)
    for name in names:
        dm.output_index(name)
    idx = tuple(OUTPUT_NAMES.index(nm) for nm in names)
    if isinstance(integrator, RK4):
        s = integrator.substeps
        h = np.diff(t)
        U, Ug = _sampled_inputs(dm, exc, t, s)
        X, Y = _rk4_run(dm, exc, s, idx, integrator.compiled, x_init[:, None], U, p[:, None],
                        t, h, Ug)
        X, Y = X[:, 0], Y[:, 0]
    elif isinstance(integrator, Adaptive):
        X = _adaptive(dm, integrator, exc, x_init, p, t)
        Ug = exc.values(t).reshape(dm.nu, t.size)
        out = dm.outputs.map(t.size)(X, Ug, p, t.reshape(1, -1))
        Y = np.asarray(out)[list(idx), :]
    else:
        raise TypeError(f"integrator must be RK4(...) or Adaptive(...), got {integrator!r}")
    inputs = exc.values(t).reshape(dm.nu, t.size)
    return Simulation(time=t, states=X.T.copy(), outputs=Y.T.copy(), inputs=inputs.T.copy(),
                      state_names=dm.states, input_names=dm.inputs, output_names=names)


def simulate_outputs(model: DerivedModel | Model, params: Sequence[Mapping[str, float]],
                     t: np.ndarray, excitation: Excitation | None = None, *,
                     outputs: tuple[str, ...], substeps: int = 1,
                     compiled: bool | None = None) -> np.ndarray:
    """The outputs of one fixed-step RK4 run of ``model`` per parameter set of ``params``,
    all from rest at ``t[0]`` under the same ``excitation``: what :func:`simulate` with
    ``RK4(substeps)`` gives for each, as one array ``(len(params), len(t),
    len(outputs))`` in the outputs' units.

    The excitation is sampled at the stage times once and the runs are mapped CasADi
    calls, :data:`CHUNK_STEPS` steps at a time (the runs' states carried from chunk to
    chunk), compiled when a C compiler exists: a scan of 70 trial pendulums on 3001
    samples took 0.4 s interpreted, where 70 calls of :func:`simulate` took 1.8 s (most of
    it sampling the same excitation again).

    Parameters
    ----------
    model : DerivedModel or analogs.Model
        A derived model (a ``Model`` is derived first, through the cache).
    params : sequence of mappings
        Parameter values by dotted name (over the declared defaults), one mapping per run.
    t : array
        Increasing output times (s).
    excitation : Excitation, optional
        Rig input signals, the same for every run; ``None`` means a tank at rest.
    outputs : tuple of str
        Output channels (:data:`derive.OUTPUT_NAMES`); their parameters must have values.
    substeps : int, default 1
        RK4 steps per output interval.
    compiled : bool, optional
        Run compiled C (:data:`CHUNK_STEPS` steps per function, compiled once per model,
        outputs and substeps and cached on disk). Default: when a C compiler exists.
    """
    dm, t, exc = _arguments(model, t, excitation)
    RK4(substeps)  # checks substeps
    if not params:
        return np.zeros((0, t.size, len(outputs)))
    P = np.column_stack([dm.parameter_vector(p, outputs=outputs) for p in params])
    idx = tuple(dm.output_index(nm) for nm in outputs)
    U, Ug = _sampled_inputs(dm, exc, t, substeps)
    if compiled is None:
        from ._compile import c_compiler

        compiled = c_compiler() is not None
    _, Y = _rk4_run(dm, exc, substeps, idx, compiled, np.zeros((dm.nx, P.shape[1])), U, P, t,
                    np.diff(t), Ug)
    return np.ascontiguousarray(Y.transpose(1, 2, 0))


def interval_inputs(exc: Excitation | None, t: np.ndarray, fractions: np.ndarray,
                    nu: int) -> np.ndarray:
    """Inputs at ``t_k + f h_k`` for every interval ``k`` and fraction ``f`` of ``fractions``,
    as a ``(nu * len(fractions), n)`` array: column k stacks the input vectors of interval
    k, first fraction first (what ``reshape(U_k, nu, m)`` and :func:`rk4_step` expect)."""
    t = np.asarray(t, float)
    n, m = t.size - 1, len(fractions)
    if nu == 0:
        return np.zeros((0, n))
    times = (t[:-1, None] + np.diff(t)[:, None] * np.asarray(fractions)[None, :]).ravel()
    vals = np.asarray(exc.values(times), float).reshape(nu, n, m)  # [channel, interval, stage]
    return np.ascontiguousarray(vals.transpose(1, 2, 0).reshape(n, m * nu).T)


def _adaptive(dm: DerivedModel, opts: Adaptive, exc: Excitation, x0: np.ndarray,
              p: np.ndarray, t: np.ndarray) -> np.ndarray:
    if dm.nx == 0:
        return np.zeros((0, t.size))
    x = ca.MX.sym("x", dm.nx)
    pp = ca.MX.sym("p", p.size)
    tt = ca.MX.sym("t")
    u = exc.symbolic(tt) if dm.nu else ca.MX(0, 1)
    dae = {"x": x, "p": pp, "t": tt, "ode": dm.rhs(x, u, pp, tt)}
    solver_opts = {"abstol": opts.atol, "reltol": opts.rtol, "max_num_steps": 1_000_000,
                   **dict(opts.options)}
    F = ca.integrator("sim", opts.method, dae, float(t[0]), t[1:].tolist(), solver_opts)
    res = F(x0=x0, p=np.nan_to_num(p))
    return np.hstack([x0.reshape(-1, 1), np.asarray(res["xf"])])
