"""Nutation time constant (NTC) of a spin-stabilised spacecraft carrying slosh analogs.

Two independent ways to the same number:

- **simulated**: integrate the nonlinear equations from steady spin with a small
  transverse rate, and fit ``exp(sigma t)`` to the envelope (the peaks) of a transverse
  body rate;
- **linearized**: the eigenvalues of the equations linearised about steady spin (CasADi
  Jacobian); the nutation mode is the one that carries most of the transverse body rate
  excited by the same initial kick.

The NTC is ``tau = 1 / sigma`` (s): positive when the nutation grows, negative when it
decays (energy dissipation grows the nutation of a prolate spinner and damps an oblate one).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from analogs.errors import InputError
from analogs.model import Model
from analogs.spacecraft import FreeSpacecraft, body_angular_velocity
from derive import Adaptive, DerivedModel, derive, simulate

__all__ = ["NutationTimeConstant", "nutation_time_constant", "steady_spin",
           "linearize", "envelope_growth_rate"]


@dataclass(frozen=True)
class NutationTimeConstant:
    """Result of :func:`nutation_time_constant`.

    Attributes
    ----------
    simulated, linearized : float
        NTC ``1 / sigma`` (s) from the envelope fit and from the eigenvalue; positive for
        growing nutation.
    growth_rate_simulated, growth_rate_linearized : float
        ``sigma`` (1/s).
    nutation_frequency : float
        Imaginary part of the nutation eigenvalue (rad/s): the nutation frequency seen in
        the spinning reference frame (close to the body-frame one).
    eigenvalues : ndarray
        All eigenvalues of the linearisation (1/s).
    equilibrium : dict
        Steady-spin coordinates (rad, m).
    time, transverse_rate : ndarray
        The simulation grid (s) and ``sqrt(omega_x^2 + omega_y^2)`` (rad/s) on it.
    peaks : tuple of ndarray
        Times (s) and values (rad/s) of the ``omega_x`` peaks used in the fit.
    """

    simulated: float
    linearized: float
    growth_rate_simulated: float
    growth_rate_linearized: float
    nutation_frequency: float
    eigenvalues: np.ndarray = field(repr=False)
    equilibrium: Mapping[str, float] = field(repr=False)
    time: np.ndarray = field(repr=False)
    transverse_rate: np.ndarray = field(repr=False)
    peaks: tuple[np.ndarray, np.ndarray] = field(repr=False)

    @property
    def relative_difference(self) -> float:
        """``|tau_sim - tau_lin| / |tau_lin|``."""
        return abs(self.simulated - self.linearized) / abs(self.linearized)

    @property
    def grows(self) -> bool:
        """True when the nutation grows (by the linearisation)."""
        return self.growth_rate_linearized > 0

    def report(self) -> str:
        """A short text report with units."""
        word = "grows" if self.grows else "decays"
        return "\n".join([
            f"Nutation {word}: nutation frequency {self.nutation_frequency:.6g} rad/s "
            f"({self.nutation_frequency / (2 * np.pi):.6g} Hz) in the spinning frame",
            f"  NTC, nonlinear simulation (envelope fit, {self.peaks[0].size} peaks): "
            f"{self.simulated:.6g} s  (sigma = {self.growth_rate_simulated:.6g} 1/s)",
            f"  NTC, linearised about steady spin (eigenvalue):        "
            f"{self.linearized:.6g} s  (sigma = {self.growth_rate_linearized:.6g} 1/s)",
            f"  relative difference: {_percent(self.relative_difference)}",
            "  (NTC = 1/sigma: positive grows, negative decays)",
        ])


def _percent(x: float) -> str:
    # below 0.01 % the envelope fit's rounding decides the digits (they differ between machines)
    return "< 0.01 %" if x < 1e-4 else f"{100 * x:.3g} %"


def _spacecraft(dm: DerivedModel) -> FreeSpacecraft:
    rig = dm.model.rig
    if not isinstance(rig, FreeSpacecraft):
        raise TypeError(
            f"the NTC needs a model on a `FreeSpacecraft` rig, got {rig.label}; build it as "
            "`FreeSpacecraft(...) + Rotor(...) + ...`")
    return rig


def _functions(dm: DerivedModel, p: np.ndarray):
    x = ca.MX.sym("x", dm.nx)
    xdot = dm.rhs(x, ca.MX(0, 1), p, 0.0)
    return x, xdot


def steady_spin(model: DerivedModel | Model, params: Mapping[str, float] | None = None
                ) -> dict[str, float]:
    """Coordinates of steady spin of ``model`` (a :class:`~analogs.spacecraft.FreeSpacecraft`
    model, derived or not) with the parameter values ``params`` (over its defaults) at the
    nominal rate (all rates zero, all accelerations zero), found by SciPy least squares
    from the all-zero state.

    Off-axis masses shift the centre of mass (``bus.x``...) and tilt the spin axis; cyclic
    coordinates (rotor angles, ``bus.psi``) stay at zero.

    Raises
    ------
    RuntimeError
        When no steady spin is found (residual acceleration above 1e-9 of ``Omega^2``).
    """
    from scipy.optimize import least_squares

    dm = derive(model) if isinstance(model, Model) else model
    rig = _spacecraft(dm)
    p = dm.parameter_vector(params)
    spin = p[dm.parameter_names.index(f"{rig.name}.spin_rate")]
    n = len(dm.coordinates)
    x, xdot = _functions(dm, p)
    acc = ca.Function("acc", [x], [xdot[n:]])
    jac = ca.Function("acc_jacobian", [x], [ca.jacobian(xdot[n:], x)[:, :n]])

    def res(q):
        return np.asarray(acc(np.r_[q, np.zeros(n)])).ravel()

    def jres(q):
        return np.asarray(jac(np.r_[q, np.zeros(n)]))

    sol = least_squares(res, np.zeros(n), jac=jres, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    scale = max(spin**2, 1e-12)
    if np.max(np.abs(res(sol.x))) > 1e-9 * scale:
        raise RuntimeError(
            f"no steady spin found: residual acceleration {np.max(np.abs(res(sol.x))):.3g} "
            f"({sol.message}); check that the analogs have a relative equilibrium in the "
            "centrifugal field (e.g. a pendulum hanging outward: `tank_axis=\"inward\"`)")
    return dict(zip(dm.coordinates, sol.x.tolist()))


def linearize(model: DerivedModel | Model, params: Mapping[str, float] | None = None,
              equilibrium: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """State matrix ``A = d xdot / d x`` (CasADi AD) of ``model`` with the values
    ``params`` at steady spin (``equilibrium``: its coordinates, default
    :func:`steady_spin`), and the state there.

    States are ``[q; qd]`` in the derived model's order.
    """
    dm = derive(model) if isinstance(model, Model) else model
    _spacecraft(dm)
    p = dm.parameter_vector(params)
    eq = steady_spin(dm, params) if equilibrium is None else dict(equilibrium)
    x_eq = np.r_[[eq[c] for c in dm.coordinates], np.zeros(len(dm.coordinates))]
    x, xdot = _functions(dm, p)
    A = ca.Function("A", [x], [ca.jacobian(xdot, x)])(x_eq)
    return np.asarray(A), x_eq


def _transverse_rate_gradient(dm: DerivedModel, rig: FreeSpacecraft, spin: float,
                              x_eq: np.ndarray) -> np.ndarray:
    x = ca.MX.sym("x", dm.nx)
    idx = {s: i for i, s in enumerate(dm.states)}
    g = [x[idx[f"{rig.name}.{c}"]] for c in ("phi", "theta", "psi", "phi_dot", "theta_dot",
                                              "psi_dot")]
    wx, wy, _ = body_angular_velocity(*g, spin, lib=ca)
    return np.asarray(ca.Function("C", [x], [ca.jacobian(ca.vertcat(wx, wy), x)])(x_eq))


def envelope_growth_rate(t: np.ndarray, signal: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Exponential rate ``sigma`` (1/s) of the envelope of an oscillating ``signal`` sampled
    at the times ``t`` (s).

    The local maxima (refined by a parabola through the three samples around each) of a
    mode ``A exp(sigma t) cos(w t + c)`` form a geometric sequence; ``sigma`` is the slope
    of a least-squares line through ``log(peak)`` against peak time. Needs at least 3
    peaks. Returns ``(sigma, peak_times, peak_values)``.
    """
    from scipy.signal import find_peaks

    t, y = np.asarray(t, float), np.asarray(signal, float)
    i, _ = find_peaks(y)
    i = i[(i > 0) & (i < y.size - 1) & (y[i] > 0)] if i.size else i
    if i.size < 3:
        raise InputError(
            f"the envelope fit needs at least 3 peaks of the transverse rate, found {i.size}; "
            "simulate longer (`duration`) or sample finer")
    ym, y0, yp = y[i - 1], y[i], y[i + 1]
    curv = ym - 2 * y0 + yp
    h = t[i + 1] - t[i]
    offset = np.where(curv != 0, 0.5 * (ym - yp) / np.where(curv != 0, curv, 1), 0.0)
    peak_t = t[i] + offset * h
    peak_y = y0 - 0.25 * (ym - yp) * offset
    sigma = float(np.polyfit(peak_t, np.log(peak_y), 1)[0])
    return sigma, peak_t, peak_y


def nutation_time_constant(
    model: DerivedModel | Model,
    params: Mapping[str, float] | None = None,
    *,
    duration: float | None = None,
    initial_rate: float | None = None,
    samples_per_period: int = 40,
    fit_start: float = 0.15,
    integrator: Adaptive = Adaptive(rtol=1e-10, atol=1e-14),
    progress: bool | None = None,
) -> NutationTimeConstant:
    """NTC of a :class:`~analogs.spacecraft.FreeSpacecraft` model, simulated and linearised.

    Parameters
    ----------
    model : DerivedModel or analogs.Model
        A model on a ``FreeSpacecraft`` rig (derived first if needed).
    params : mapping
        Parameter values by dotted name (over the declared defaults).
    duration : float, optional
        Simulated time (s). Default: 60 rigid-bus nutation periods ``2 pi / |lambda|``,
        ``lambda = (I_z - I_t) / I_t Omega`` with ``I_t`` the mean transverse bus inertia.
    initial_rate : float, optional
        Transverse body rate (rad/s) added to steady spin at ``t = 0`` (``bus.phi_dot``).
        Default ``1e-4 |Omega|``: small, so that the linearisation holds.
    samples_per_period : int, default 40
        Output samples per rigid-bus nutation period.
    fit_start : float, default 0.15
        Fraction of ``duration`` skipped before the fit (faster analog modes decay there).
    integrator : Adaptive
        CVODES settings of the nonlinear simulation.
    progress : bool, optional
        Show a bar of the stages (derive, steady spin, linearise, simulate); default: on a
        terminal only.

    Examples
    --------
    >>> from analogs import Rotor
    >>> from analogs.spacecraft import FreeSpacecraft
    >>> model = (FreeSpacecraft(translation=False, spin_rate=3.0, mass=100.0, inertia_x=10.0,
    ...                         inertia_y=10.0, inertia_z=15.0)
    ...          + Rotor("rx", axis="x", inertia=0.2, damping=0.2)
    ...          + Rotor("ry", axis="y", inertia=0.2, damping=0.2))
    >>> ntc = nutation_time_constant(model)
    >>> ntc.grows  # oblate spinner with an energy sink: nutation decays
    False
    """
    from .._progress import progress as bar

    with bar(total=4, desc="NTC", unit="stage", enabled=progress) as b:
        b.set_postfix_str("deriving the equations")
        dm = derive(model) if isinstance(model, Model) else model
        b.update()
        return _ntc(dm, params, duration, initial_rate, samples_per_period, fit_start, integrator,
                    b)


def _ntc(dm: DerivedModel, params: Mapping[str, float] | None, duration: float | None,
         initial_rate: float | None, samples_per_period: int, fit_start: float,
         integrator: Adaptive, bar) -> NutationTimeConstant:
    rig = _spacecraft(dm)
    p = dm.parameter_vector(params)
    pv = dict(zip(dm.parameter_names, p))
    spin = float(pv[f"{rig.name}.spin_rate"])
    if spin == 0:
        raise InputError(f"`{rig.name}.spin_rate` is 0 rad/s: an NTC needs a spinning body")
    it = 0.5 * (pv[f"{rig.name}.inertia_x"] + pv[f"{rig.name}.inertia_y"])
    lam0 = max(abs(pv[f"{rig.name}.inertia_z"] - it) / it * abs(spin), 0.05 * abs(spin))
    period = 2 * np.pi / lam0
    duration = 60 * period if duration is None else float(duration)
    if not duration > 0:
        raise InputError(f"duration must be positive (s), got {duration!r}")
    eps = 1e-4 * abs(spin) if initial_rate is None else float(initial_rate)

    # linearised
    bar.set_postfix_str("steady spin")
    eq = steady_spin(dm, params)
    bar.update()
    bar.set_postfix_str("linearising")
    A, x_eq = linearize(dm, params, eq)
    bar.update()
    w, V = np.linalg.eig(A)
    kick = np.zeros(dm.nx)
    kick[dm.states.index(f"{rig.name}.phi_dot")] = eps
    c = np.linalg.lstsq(V, kick, rcond=None)[0]
    C = _transverse_rate_gradient(dm, rig, spin, x_eq)
    share = np.abs(C @ V).sum(axis=0) * np.abs(c)
    share[np.abs(w.imag) < 1e-9 * abs(spin)] = 0.0  # the nutation mode oscillates
    k = int(np.argmax(share))
    sigma_lin = float(w[k].real)

    # nonlinear simulation and envelope fit
    n = int(np.ceil(duration / period * samples_per_period))
    t = np.linspace(0.0, duration, n + 1)
    bar.set_postfix_str(f"simulating {duration:.0f} s")
    sim = simulate(dm, params, t, integrator=integrator, x0=x_eq + kick)
    bar.update()
    s = {nm: sim.state(f"{rig.name}.{nm}") for nm in ("phi", "theta", "psi", "phi_dot",
                                                       "theta_dot", "psi_dot")}
    wx, wy, _ = body_angular_velocity(s["phi"], s["theta"], s["psi"], s["phi_dot"],
                                      s["theta_dot"], s["psi_dot"], spin)
    wx0, wy0, _ = body_angular_velocity(*(x_eq[dm.states.index(f"{rig.name}.{nm}")]
                                          for nm in ("phi", "theta", "psi", "phi_dot",
                                                     "theta_dot", "psi_dot")), spin)
    keep = t >= fit_start * duration
    sigma_sim, pt, py = envelope_growth_rate(t[keep], (wx - wx0)[keep])
    return NutationTimeConstant(
        simulated=1.0 / sigma_sim, linearized=1.0 / sigma_lin,
        growth_rate_simulated=sigma_sim, growth_rate_linearized=sigma_lin,
        nutation_frequency=float(abs(w[k].imag)), eigenvalues=w, equilibrium=eq,
        time=t, transverse_rate=np.hypot(wx - wx0, wy - wy0), peaks=(pt, py))
