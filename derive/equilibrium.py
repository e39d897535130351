"""Relative equilibria of a derived model: where the analog rests in the tank under a steady
rig motion (a conical pendulum on a spinning table, a rotor turning with the tank).

With every relative rate zero, ``M(q) qdd = f(q, 0, u, p, t)``: the analog rests when the
generalized forces ``f`` vanish. A coordinate that nothing restores (structurally absent
from ``f``, e.g. a rotor's angle) is held at 0 and its own equation must vanish by itself.
The equations are solved numerically (SciPy's Levenberg-Marquardt on the CasADi function
and its exact Jacobian), never guessed; the solution is checked to be an equilibrium for
the whole first sample interval (the rig motion is steady) and stable.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from analogs.errors import InputError

from .derived import DerivedModel

__all__ = ["EquilibriumEquations", "equilibrium_equations", "relative_equilibrium",
           "STEADY_DRIFT"]

#: Largest change of the equilibrium coordinates (rad or m) over the first sample interval
#: for the rig motion to count as steady at the first sample; a coning table or a changing
#: spin rate moves the balance by orders of magnitude more (a 0.06 rad cone moves a pendulum
#: by ~1e-3 rad in 10 ms).
STEADY_DRIFT = 1e-5


@dataclass(frozen=True)
class EquilibriumEquations:
    """``residual(q, u, p, t)``: the generalized forces at zero rates, except that the row of
    each cyclic coordinate (:attr:`cyclic`, indices) is the coordinate itself (held at 0);
    ``forcing(q, u, p, t)``: all generalized forces at zero rates; ``jacobian`` of the
    residual with respect to ``q``."""

    residual: ca.Function
    forcing: ca.Function
    jacobian: ca.Function
    cyclic: tuple[int, ...]


def equilibrium_equations(dm: DerivedModel) -> EquilibriumEquations:
    """The equilibrium equations of ``dm`` (built once per derived model)."""

    def build() -> EquilibriumEquations:
        nq = len(dm.coordinates)
        q = ca.SX.sym("q", nq)
        u = ca.SX.sym("u", dm.nu)
        p = ca.SX.sym("p", len(dm.parameter_names))
        t = ca.SX.sym("t")
        f = dm.forcing(ca.vertcat(q, ca.SX.zeros(nq)), u, p, t)
        dep = ca.jacobian(f, q).sparsity()
        cyclic = tuple(i for i in range(nq) if not dep.colind()[i + 1] > dep.colind()[i])
        rows = [q[i] if i in cyclic else f[i] for i in range(nq)]
        r = ca.vertcat(*rows) if rows else ca.SX(0, 1)
        names = ["q", "u", "p", "t"]
        return EquilibriumEquations(
            ca.Function("equilibrium", [q, u, p, t], [r], names, ["r"]),
            ca.Function("equilibrium_forcing", [q, u, p, t], [f], names, ["f"]),
            ca.Function("equilibrium_jacobian", [q, u, p, t], [ca.jacobian(r, q)], names, ["J"]),
            cyclic)

    return dm.memo(("equilibrium",), build)


def relative_equilibrium(dm: DerivedModel, p: np.ndarray, time: np.ndarray, inputs: np.ndarray,
                         *, guess: np.ndarray | None = None) -> np.ndarray:
    """The state (coordinates, zero rates) at which the analog rests relative to the tank
    under the rig motion at ``time[0]``.

    Parameters
    ----------
    dm : DerivedModel
        The derived model.
    p : array
        Parameter vector in ``dm.parameter_names`` order.
    time : array
        The first two sample times (s): the equilibrium is solved at both, and the rig
        motion must be steady in between (:data:`STEADY_DRIFT`).
    inputs : array, shape (nu, 2)
        The rig's input signals at those times.
    guess : array, optional
        Starting coordinates (default: all zero, then each coordinate swung by +/-0.5).

    Raises
    ------
    InputError
        When no equilibrium is found, the one found is unstable, or the rig motion is not
        steady at the first sample (a coning table, a spin rate that is changing).

    Examples
    --------
    >>> import numpy as np
    >>> from analogs import SphericalPendulum
    >>> from analogs.spinning import SpinningRig
    >>> from derive import derive
    >>> dm = derive(SpinningRig() + SphericalPendulum("p1"))
    >>> p = dm.parameter_vector({"rig.spin_rate": 6.0, "rig.radius": 0.4, "rig.dry_mass": 0.0,
    ...                          "p1.mass": 1.0, "p1.length": 0.1, "p1.hinge_height": 0.0})
    >>> x0 = relative_equilibrium(dm, p, np.array([0.0, 0.01]), np.zeros((0, 2)))
    >>> round(float(np.degrees(x0[0])), 1)   # the pendulum swung out on its cone
    60.8
    """
    nq = len(dm.coordinates)
    if nq == 0:
        return np.zeros(0)
    eq = equilibrium_equations(dm)
    p = np.nan_to_num(np.asarray(p, float))
    t = np.asarray(time, float).ravel()
    u = np.asarray(inputs, float).reshape(dm.nu, t.size)
    starts = [np.zeros(nq) if guess is None else np.asarray(guess, float)]
    starts += [starts[0] + s * np.eye(nq)[i] for i in range(nq) if i not in eq.cyclic
               for s in (0.5, -0.5)]
    failures = []
    for start in starts:
        q, why = _solve(eq, start, u[:, 0], p, t[0])
        if why is None:
            why = _unstable(dm, q, u[:, 0], p, t[0])
        if why is None:
            q1, why1 = _solve(eq, q, u[:, -1], p, t[-1])
            drift = float(np.max(np.abs(q1 - q))) if why1 is None else np.inf
            if drift > STEADY_DRIFT:
                raise InputError(
                    f"initial_state = \"steady\": the rig motion is not steady at the first "
                    f"sample (t = {t[0]:g} s): the relative equilibrium moves by {drift:.3g} "
                    f"(rad or m) by the next sample; the table is coning or its spin rate is "
                    "changing. Start the record before the coning ramps in, or use "
                    "initial_state = \"free\"")
            return np.concatenate([q, np.zeros(nq)])
        failures.append(why)
    raise InputError("initial_state = \"steady\": no stable relative equilibrium of the analog "
                     f"under the rig motion at t = {t[0]:g} s ({'; '.join(dict.fromkeys(failures))}); "
                     "use initial_state = \"free\" or \"rest\"")


def _solve(eq: EquilibriumEquations, start: np.ndarray, u: np.ndarray, p: np.ndarray,
           t: float) -> tuple[np.ndarray, str | None]:
    from scipy.optimize import least_squares

    def fun(q):
        return np.asarray(eq.residual(q, u, p, t)).ravel()

    def jac(q):
        return np.asarray(eq.jacobian(q, u, p, t))

    sol = least_squares(fun, start, jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        max_nfev=2000)
    q = sol.x
    f = np.asarray(eq.forcing(q, u, p, t)).ravel()
    scale = max(float(np.max(np.abs(np.asarray(eq.jacobian(q, u, p, t))))), 1e-300)
    # every generalized force zero, to round-off of the stiffness times 1 rad (or m)
    if not np.all(np.abs(f) <= 1e-9 * scale):
        worst = int(np.argmax(np.abs(f)))
        return q, (f"the generalized force on coordinate {worst} stays {f[worst]:.3g} "
                   f"from a start at {np.round(start, 3).tolist()}")
    return q, None


def _unstable(dm: DerivedModel, q: np.ndarray, u: np.ndarray, p: np.ndarray,
              t: float) -> str | None:
    """Why the equilibrium ``q`` is unstable (an eigenvalue of the linearised motion with a
    positive real part), or ``None``."""
    nq = q.size
    x = ca.SX.sym("x", 2 * nq)
    xdot = dm.rhs(x, ca.DM(u), ca.DM(p), t)
    A = np.asarray(ca.Function("A", [x], [ca.jacobian(xdot, x)])(np.r_[q, np.zeros(nq)]))
    lam = np.linalg.eigvals(A)
    size = max(float(np.max(np.abs(lam))), 1e-300)
    if np.max(lam.real) > 1e-6 * size:
        return (f"the equilibrium at {np.round(q, 4).tolist()} is unstable (eigenvalue "
                f"{lam[np.argmax(lam.real)]:.3g} 1/s)")
    return None
