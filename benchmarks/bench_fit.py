"""Benchmark of issue 3: the 5-parameter baseline fit of a 30 s, 3001-sample case.

Run: ``python benchmarks/bench_fit.py``. Prints the median wall time of ``slosh fit``'s
estimation (problem build + solve) for multiple shooting and collocation, and the seed's
approach in the same run on the same case and start: SciPy ``least_squares`` on a
``solve_ivp`` single-shooting simulation of hand-written equations with finite-difference
Jacobians. Both final costs (sum of squared force residuals, N^2) are printed.
"""

import math
import sys
import time
from pathlib import Path

import _common  # noqa: F401  (pins threads before numpy is imported)
import numpy as np
from _common import median_time
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from estimate import Collocation, FitProblem, MultipleShooting, fit, load_case, model_from_spec
from estimate.data.signals import displacement_derivatives, lowpass

CASE = ROOT / "examples" / "A1.toml"
NAMES = ("fixed.mass", "p1.mass", "p1.length", "p1.damping", "p1.stiffness")


def casadi_fit(case, transcription):
    problem = FitProblem.build(case, model_from_spec("fixed,p1", case))
    return fit(problem, transcription=transcription, progress=False)


def scipy_fit(case, start, bounds):
    """The seed's lsqnonlin approach: single shooting, finite-difference Jacobian."""
    t = case.time
    g, m_dry = case.rig.gravity, case.rig.dry_mass
    x, xd, xdd = displacement_derivatives(t, case.displacement)
    acc = CubicSpline(t, xdd)
    F = lowpass(t, case.force, cutoff_hz=10.0)
    sims = [0]

    def residual(theta):
        mf, m, L, c, k = theta
        sims[0] += 1

        def rhs(tt, y):
            a = acc(tt)
            th, thd = y
            torque = m * L * a * math.cos(th) + m * g * L * math.sin(th) + k * th + c * thd
            return [thd, -torque / (m * L**2)]

        sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-8, atol=1e-10)
        th, thd = sol.y
        thdd = -(m * L * xdd * np.cos(th) + m * g * L * np.sin(th) + k * th + c * thd) / (m * L**2)
        force = (m_dry + mf) * xdd + m * (xdd + L * thdd * np.cos(th) - L * thd**2 * np.sin(th))
        return force - F

    lo = [b[0] for b in bounds]
    hi = [b[1] for b in bounds]
    x0 = np.clip(start, np.array(lo) + 1e-12, hi)
    res = least_squares(residual, x0, bounds=(lo, hi), x_scale=np.maximum(np.abs(x0), 1e-3))
    return res, sims[0], residual


def main() -> None:
    case = load_case(CASE)
    ms = casadi_fit(case, MultipleShooting())
    co = casadi_fit(case, Collocation(degree=3))
    t_ms = median_time(lambda: casadi_fit(case, MultipleShooting()), repeat=7, warmup=1)
    t_co = median_time(lambda: casadi_fit(case, Collocation(degree=3)), repeat=5, warmup=1)
    est = {e.name: e for e in ms.problem.estimated}
    start = np.array([est[n].initial for n in NAMES])
    bounds = [(est[n].lower, est[n].upper) for n in NAMES]
    t0 = time.perf_counter()
    sres, nsim, residual = scipy_fit(case, start, bounds)
    t_sp = time.perf_counter() - t0
    ours = np.array([dict(zip(ms.names, ms.values))[n] for n in NAMES])
    ours_in_scipy = float(np.sum(residual(ours) ** 2))
    print(f"case {CASE.name}: {case.n_samples} samples, 5 parameters ({', '.join(NAMES)})")
    print(f"  CasADi/IPOPT multiple shooting : median {t_ms:7.3f} s  cost {ms.cost:.6g} N^2  "
          f"({ms.iterations} iterations, {ms.status})")
    print(f"  CasADi/IPOPT collocation (R3)  : median {t_co:7.3f} s  cost {co.cost:.6g} N^2  "
          f"({co.iterations} iterations)   collocation / shooting time {t_co / t_ms:.2f}")
    scost = float(sres.cost * 2)
    print(f"  SciPy least_squares+solve_ivp  : single run {t_sp:7.3f} s  cost {scost:.6g} N^2  "
          f"({nsim} simulations, {sres.message})")
    print(f"  same simulator (SciPy solve_ivp rtol 1e-8): cost of our estimates {ours_in_scipy:.6g} N^2, "
          f"of SciPy's {scost:.6g} N^2, ratio {ours_in_scipy / scost:.5f}")
    print(f"  speed-up of multiple shooting over the seed's approach: {t_sp / t_ms:.1f}x")


if __name__ == "__main__":
    main()
