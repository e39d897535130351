"""The spinning rig's first stage: a start for the six-channel fit that needs no good start.

On a rig whose motion is prescribed (spin, coning), every component's contribution to the
six force/torque channels is independent of the others': the outputs are the rig's own
(dry mass), the fixed mass's and the first-mode pendulum's, summed. The fixed mass has no
states, so its outputs are linear in ``(m, m h, m h^2, I, I_axial)``; the pendulum's
motion depends on its mass only through its hinge damping per unit mass ``c / m``, so at a
given ``(L, h_hinge, c / m)`` its outputs are linear in its mass. For each point of a grid
over the pendulum's length (its +/-20 % band) and hinge height (the tank's height) one
simulation of the analog gives the pendulum's outputs per kilogram; the masses, the fixed
mass's moments and inertias follow by bounded linear least squares over the six channels
(each scaled by its RMS, as the fit scales them), and the best grid point is refined by
SciPy's ``least_squares`` over ``(L, h_hinge, log c/m)`` with the linear part projected out.

Why: the NLP from the tank prediction walks along the valley where the fixed mass's
inertias and heights trade against the pendulum's hinge height (a 10 s prograde-coning
record ended after 150 iterations with inertias of 600-1400 kg m^2 for 2.8 kg of water);
from this stage's start it converges in ~20 iterations.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["SpinStage", "spin_stage", "LENGTH_GRID", "HEIGHT_GRID"]

#: Grid points over the pendulum's length band and over its hinge height.
LENGTH_GRID = 7
HEIGHT_GRID = 9
#: Mass [kg] of the pendulum in the two simulations that separate its outputs from the
#: rest's; any two distinct values give the same columns (the outputs are linear in it).
_UNIT = 1.0


@dataclass(frozen=True)
class SpinStage:
    """The stage's outcome: starting values by parameter name, the share of the six
    channels' (scaled) variance the stage explains, grid points tried and simulations."""

    values: Mapping[str, float]
    explained: float
    grid_points: int
    simulations: int

    def to_dict(self) -> dict:
        """The JSON form (SI units)."""
        return {"kind": "spinning rig", "values": dict(self.values),
                "explained": self.explained, "grid_points": self.grid_points,
                "simulations": self.simulations}

    def describe(self) -> str:
        """One sentence for the fit's notes."""
        v = self.values
        return (f"first stage (spinning rig: {self.grid_points} grid points of the pendulum's "
                f"length and hinge height, the masses and the fixed mass's moments by linear "
                f"least squares; {self.simulations} simulations): `p1.length` "
                f"{v.get('p1.length', math.nan):.4g} m, `p1.hinge_height` "
                f"{v.get('p1.hinge_height', math.nan):.4g} m, `p1.mass` "
                f"{v.get('p1.mass', math.nan):.4g} kg, explains {100 * self.explained:.1f} % "
                "of the channels' variance")


def applies(model, estimated: Sequence[str]) -> bool:
    """Whether the stage can start ``model``: a fixed mass and a pendulum ``p1`` with a
    linear hinge damper are the only components besides the rig, and the pendulum's mass
    and length are estimated."""
    from analogs import FixedMass, HingeDamper, Pendulum, SphericalPendulum
    from analogs.rigs import Rig

    kinds = {type(c) for c in model.components if not isinstance(c, Rig)}
    names = {c.name for c in model.components if isinstance(c, (Pendulum, SphericalPendulum))}
    return (kinds <= {FixedMass, Pendulum, SphericalPendulum, HingeDamper} and names == {"p1"}
            and {"p1.mass", "p1.length"} <= set(estimated))


def spin_stage(exps, weights, estimated: Sequence[str], start: Mapping[str, float],
               bounds: Mapping[str, tuple[float, float]], *, cutoff_hz: float | None
               ) -> SpinStage | None:
    """Starting values for the spinning-rig fit of experiments ``exps`` (their six channels,
    held-out ``weights`` per case or ``None``), for the parameters ``estimated``, from the
    current start values ``start`` and the box ``bounds`` by name (length and hinge height
    searched within them). ``cutoff_hz``: the force low-pass of the fit (its channels are
    compared low-passed). ``None`` when the model is not the stage's (:func:`applies`)."""
    from scipy.optimize import least_squares, lsq_linear

    from ..data.signals import lowpass

    model = exps[0].model
    if not applies(model, estimated):
        return None
    fixed_names = [c.name for c in model.components if type(c).__name__ == "FixedMass"]
    fx = fixed_names[0] if fixed_names else None
    L_lo, L_hi = bounds.get("p1.length", (0.8 * start["p1.length"], 1.2 * start["p1.length"]))
    h_lo, h_hi = bounds.get("p1.hinge_height", (math.nan, math.nan))
    search_h = "p1.hinge_height" in estimated and math.isfinite(h_lo) and math.isfinite(h_hi)
    c_per_m = start.get("p1.damping", 0.0) / start["p1.mass"]
    measured, scale, keep = [], [], []
    for i, e in enumerate(exps):
        w = np.ones(e.case.time.size) if weights[i] is None else np.asarray(weights[i], float)
        cols = []
        for ch in e.channels:
            y = np.asarray(e.case.channels[ch], float)
            if cutoff_hz is not None:
                y = lowpass(e.case.time, y, cutoff_hz=cutoff_hz)
            cols.append(y)
        Y = np.column_stack(cols)
        measured.append(Y)
        scale.append(np.sqrt(np.mean(Y**2, axis=0)) + 1e-300)
        keep.append(w > 0)
    sims = [0]

    def outputs(values: Mapping[str, float]) -> list[np.ndarray]:
        sims[0] += 1
        out = []
        for e in exps:
            s = e.simulate({**start, **values})
            idx = [s.output_names.index(ch) for ch in e.channels]
            out.append(s.outputs[:, idx])
        return out

    def stack(per_case: list[np.ndarray]) -> np.ndarray:
        return np.concatenate([(Y / s)[k].ravel() for Y, s, k in zip(per_case, scale, keep)])

    # the fixed mass's columns: outputs at (m, h, I, Iax) minus the outputs without it
    zero_fixed = {}
    if fx is not None:
        tiny = next(p.lower for p in model.parameters if p.name == f"{fx}.mass")
        zero_fixed = {f"{fx}.mass": tiny, f"{fx}.height": 0.0, f"{fx}.inertia": 0.0,
                      f"{fx}.axial_inertia": 0.0}
    p_ref = {"p1.mass": _UNIT, "p1.damping": _UNIT * c_per_m}
    base = outputs({**zero_fixed, **p_ref})
    basis = []
    if fx is not None:
        h1 = max(abs(start.get(f"{fx}.height", 0.1)), 0.05)
        combos = [{f"{fx}.mass": 1.0}, {f"{fx}.mass": 1.0, f"{fx}.height": h1},
                  {f"{fx}.mass": 1.0, f"{fx}.height": -h1}]
        if f"{fx}.inertia" in estimated:
            combos.append({f"{fx}.inertia": 1.0})
        if f"{fx}.axial_inertia" in estimated:
            combos.append({f"{fx}.axial_inertia": 1.0})
        raw = [stack([o - b for o, b in zip(outputs({**zero_fixed, **p_ref, **c}), base)])
               for c in combos]
        # (m, m h, m h^2) from the three height samples: f(h) = a + b h + c h^2
        a, plus, minus = raw[0], raw[1], raw[2]
        basis = [a, (plus - minus) / (2 * h1), (plus + minus - 2 * a) / (2 * h1**2)] + raw[3:]

    # the rig's own outputs (the pendulum's are linear in its mass at a fixed c/m)
    double = outputs({**zero_fixed, "p1.mass": 2 * _UNIT, "p1.damping": 2 * _UNIT * c_per_m})
    rest = stack([2 * a - b for a, b in zip(base, double)])

    def pendulum(L: float, h: float | None, cm: float) -> np.ndarray:
        """The pendulum's outputs per kg at (L, h, c/m), scaled and stacked."""
        v = {"p1.length": L, "p1.mass": _UNIT, "p1.damping": _UNIT * cm}
        if h is not None:
            v["p1.hinge_height"] = h
        return (stack(outputs({**zero_fixed, **v})) - rest) / _UNIT

    y = stack(measured)
    n_fixed = len(basis)
    lower = np.r_[0.0, [0.0, -np.inf, 0.0] if n_fixed else [], np.zeros(max(n_fixed - 3, 0))]
    upper = np.full(lower.size, np.inf)

    def solve(L: float, h: float | None, cm: float):
        A = np.column_stack([pendulum(L, h, cm)] + basis)
        sol = lsq_linear(A, y - rest, bounds=(lower, upper), method="bvls")
        return sol.fun, sol.x

    best = None
    heights = np.linspace(h_lo, h_hi, HEIGHT_GRID) if search_h else [None]
    for L in np.linspace(L_lo, L_hi, LENGTH_GRID):
        for h in heights:
            r, x = solve(float(L), None if h is None else float(h), c_per_m)
            cost = float(r @ r)
            if best is None or cost < best[0]:
                best = (cost, float(L), h, x)
    grid = LENGTH_GRID * len(heights)
    _, L0, h0, _ = best
    # refine (L, h, log c/m) with the linear part projected out
    z0 = [L0] + ([h0] if search_h else []) + [math.log(max(c_per_m, 1e-12))]
    lo = [L_lo] + ([h_lo] if search_h else []) + [math.log(1e-12)]
    hi = [L_hi] + ([h_hi] if search_h else []) + [math.log(1e3)]
    z0 = np.clip(z0, lo, hi)

    def unpack(z):
        return float(z[0]), (float(z[1]) if search_h else None), float(math.exp(z[-1]))

    ref = least_squares(lambda z: solve(*unpack(z))[0], z0, bounds=(lo, hi), x_scale="jac",
                        xtol=1e-4, ftol=1e-6, max_nfev=30)
    L, h, cm = unpack(ref.x)
    r, x = solve(L, h, cm)
    explained = 1.0 - float(r @ r) / float(y @ y) if y @ y > 0 else math.nan
    values = {"p1.length": L, "p1.mass": float(x[0]), "p1.damping": float(x[0]) * cm}
    if h is not None:
        values["p1.hinge_height"] = h
    if fx is not None:
        m, mh = float(x[1]), float(x[2])
        values[f"{fx}.mass"] = m
        if m > 0 and f"{fx}.height" in estimated:
            values[f"{fx}.height"] = mh / m
        k = 4
        for n in ("inertia", "axial_inertia"):
            if f"{fx}.{n}" in estimated:
                values[f"{fx}.{n}"] = float(x[k])
                k += 1
    values = {k: v for k, v in values.items() if k in estimated and math.isfinite(v)}
    return SpinStage(values, explained, grid, sims[0])
