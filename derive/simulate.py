"""Simulation of a derived model under a prescribed excitation, through CasADi."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from analogs.model import Model

from .derived import OUTPUT_NAMES, DerivedModel
from .excitation import Excitation, NoExcitation

__all__ = ["RK4", "Adaptive", "Simulation", "simulate", "rk4_step"]


@dataclass(frozen=True)
class RK4:
    """Fixed-step classical Runge-Kutta, ``substeps`` steps per output interval.

    Code-generatable (used for C export and multiple shooting). The inputs are sampled
    at the stage times, so the result matches an exact integration to O(h^4).
    """

    substeps: int = 1

    def __post_init__(self) -> None:
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise ValueError(f"RK4.substeps must be a positive integer, got {self.substeps!r}")


@dataclass(frozen=True)
class Adaptive:
    """Variable-step integrator from SUNDIALS through CasADi (``"cvodes"`` BDF/Adams or
    ``"idas"``) with relative and absolute tolerances."""

    method: str = "cvodes"
    rtol: float = 1e-10
    atol: float = 1e-12
    options: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class Simulation:
    """States and outputs on the requested time grid.

    ``states`` has shape ``(len(time), nx)`` (coordinates in rad or m, then rates);
    ``outputs`` has shape ``(len(time), 8)`` in :data:`derive.OUTPUT_NAMES` order (N, N m, J);
    ``inputs`` holds the excitation values used.
    """

    time: np.ndarray
    states: np.ndarray
    outputs: np.ndarray
    inputs: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...] = OUTPUT_NAMES

    def output(self, name: str) -> np.ndarray:
        """One output channel (e.g. ``"force_x"``) on the time grid."""
        if name not in self.output_names:
            raise KeyError(f"no output {name!r}; outputs are {', '.join(self.output_names)}")
        return self.outputs[:, self.output_names.index(name)]

    def state(self, name: str) -> np.ndarray:
        """One state (e.g. ``"p1.theta"`` or ``"p1.theta_dot"``) on the time grid."""
        if name not in self.state_names:
            raise KeyError(f"no state {name!r}; states are {', '.join(self.state_names)}")
        return self.states[:, self.state_names.index(name)]


def rk4_step(dm: DerivedModel, substeps: int = 1) -> ca.Function:
    """``step(x, U, p, t, h) -> x_next``: ``substeps`` RK4 steps over ``[t, t + h]``.

    ``U`` holds the inputs at the ``2 * substeps + 1`` equally spaced stage times of the
    interval, one column each.
    """
    key = ("rk4_step", substeps)
    if key not in dm._memo:
        x0 = ca.SX.sym("x", dm.nx)
        U = ca.SX.sym("U", dm.nu, 2 * substeps + 1)
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
        dm._memo[key] = ca.Function("rk4_step", [x0, U, p, t, h], [x],
                                    ["x", "U", "p", "t", "h"], ["x_next"])
    return dm._memo[key]


def _horizon(dm: DerivedModel, substeps: int, n: int) -> ca.Function:
    key = ("rk4_horizon", substeps, n)
    if key not in dm._memo:
        dm._memo[key] = rk4_step(dm, substeps).mapaccum("rk4_horizon", n)
    return dm._memo[key]


def _output_map(dm: DerivedModel, n: int) -> ca.Function:
    key = ("outputs", n)
    if key not in dm._memo:
        dm._memo[key] = dm.outputs.map(n)
    return dm._memo[key]


def _initial_state(dm: DerivedModel, x0) -> np.ndarray:
    if x0 is None:
        return np.zeros(dm.nx)
    if isinstance(x0, Mapping):
        unknown = sorted(set(x0) - set(dm.states))
        if unknown:
            raise KeyError(f"unknown state {unknown}; states are {', '.join(dm.states)}")
        return np.array([float(x0.get(s, 0.0)) for s in dm.states])
    arr = np.asarray(x0, float).ravel()
    if arr.size != dm.nx:
        raise ValueError(f"x0 must have {dm.nx} values ({', '.join(dm.states)}), got {arr.size}")
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
        Output channels whose parameters must be given (default: the rig's measured
        channels). All outputs are computed; others may be NaN when their parameters
        have no value.

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
    if isinstance(model, Model):
        from ._derive import derive

        model = derive(model)
    dm = model
    t = np.asarray(t, float).ravel()
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise ValueError("t must be a strictly increasing array of at least 2 times (s)")
    exc = excitation if excitation is not None else NoExcitation(size=dm.nu)
    if exc.size != dm.nu:
        raise ValueError(
            f"the excitation supplies {exc.size} input values but the model takes {dm.nu} "
            f"({', '.join(dm.inputs) or 'none'})"
        )
    p = dm.parameter_vector(params, outputs=outputs)
    x_init = _initial_state(dm, x0)
    n = t.size - 1
    if isinstance(integrator, RK4):
        s = integrator.substeps
        h = np.diff(t)
        frac = np.arange(2 * s + 1) / (2 * s)
        stage_t = (t[:-1, None] + h[:, None] * frac[None, :]).ravel()
        U = exc.values(stage_t).reshape(dm.nu, n * (2 * s + 1))
        X = _horizon(dm, s, n)(x_init, U, p, t[:-1].reshape(1, -1), h.reshape(1, -1))
        X = np.hstack([x_init.reshape(-1, 1), np.asarray(X).reshape(dm.nx, n)])
    elif isinstance(integrator, Adaptive):
        X = _adaptive(dm, integrator, exc, x_init, p, t)
    else:
        raise TypeError(f"integrator must be RK4(...) or Adaptive(...), got {integrator!r}")
    Ug = exc.values(t).reshape(dm.nu, t.size)
    Y = np.asarray(_output_map(dm, t.size)(X, Ug, p, t.reshape(1, -1)))
    return Simulation(time=t, states=X.T.copy(), outputs=Y.T.copy(), inputs=Ug.T.copy(),
                      state_names=dm.states, input_names=dm.inputs)


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
