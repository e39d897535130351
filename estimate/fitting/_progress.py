"""IPOPT iteration callback: parameter trajectories for the fit plot, live progress."""

from __future__ import annotations

import sys
from collections.abc import Callable

import casadi as ca
import numpy as np

__all__ = ["Recorder", "progress_printer"]


class Recorder(ca.Callback):
    """IPOPT iteration callback: records parameter trajectories and prints progress; asks
    IPOPT to stop (status ``User_Requested_Stop``) when ``stop(costs, theta)`` says so
    (the costs ``|r|^2`` of the iterations so far, the current estimates)."""

    def __init__(self, nw: int, ng: int, ntheta: int, scales: np.ndarray, cost_scale: float,
                 printer: Callable[[int, float, np.ndarray], None] | None,
                 stop: Callable[[list[float], np.ndarray], bool] | None = None) -> None:
        ca.Callback.__init__(self)
        self.nw, self.ng, self.ntheta = nw, ng, ntheta
        self.scales, self.cost_scale = scales, cost_scale
        self.thetas: list[np.ndarray] = []
        self.costs: list[float] = []
        self.printer = printer
        self.stop = stop
        self.stopped = False  # whether ``stop`` ended the solve
        #: The last iterate (all decision variables) whose cost was finite.
        self.last_finite: ca.DM | None = None
        self.construct("fit_iterations", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        n = ca.nlpsol_out(i)
        if n == "f":
            return ca.Sparsity.scalar()
        if n in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nw)
        if n in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        theta = np.asarray(arg[0][: self.ntheta]).ravel() * self.scales  # slice before copying
        cost = float(arg[1]) * self.cost_scale
        self.thetas.append(theta)
        self.costs.append(cost)
        if np.isfinite(cost) and np.all(np.isfinite(theta)):
            self.last_finite = ca.DM(arg[0])  # a copy in C++: converted only when used
        if self.printer is not None:
            self.printer(len(self.costs) - 1, cost, theta)
        self.stopped = self.stop is not None and self.stop(self.costs, theta)
        return [int(self.stopped)]


def progress_printer(names):
    def show(k, cost, theta):
        vals = "  ".join(f"{n}={v:.5g}" for n, v in zip(names, theta))
        print(f"\riter {k:3d}  cost {cost:.6g}  {vals}"[:200], end="", file=sys.stderr, flush=True)
    return show
