"""Initial values, bounds and scales of estimated parameters, from the tank prediction."""

from __future__ import annotations

import math
from collections.abc import Mapping

from analogs import Model

from ..data.case import Case

__all__ = ["predicted_values", "length_bounds", "nominal_scale", "tank_prediction", "LENGTH_BAND"]

#: Pendulum lengths are kept within +/-20 % of the prediction, as the seed did.
LENGTH_BAND = 0.20


def tank_prediction(shape: str, radius: float, fill: float, *, density: float,
                    viscosity: float, gravity: float, modes: int = 1, method: str = "exact",
                    diaphragm: bool = False):
    """The tank modal analysis (:func:`analogs.tank.predict`) of a case file's tank: a
    sphere, or a cylinder as tall as its diameter; radius in m, fill as liquid depth / tank
    height, density in kg/m^3, kinematic viscosity in m^2/s, gravity in m/s^2."""
    from analogs.tank import Cylinder, Liquid, Sphere, predict

    tank = Sphere(radius) if shape == "sphere" else Cylinder(radius, 2 * radius)
    return predict(tank, fill=fill, liquid=Liquid(density=density, viscosity=viscosity),
                   gravity=gravity, modes=modes, method=method, diaphragm=diaphragm)


def _tank_prediction(case: Case, modes: int):
    return tank_prediction(case.tank.shape, case.tank.radius, case.tank.fill_fraction,
                           density=case.liquid.density,
                           viscosity=case.liquid.kinematic_viscosity, gravity=case.rig.gravity,
                           modes=modes, diaphragm=case.tank.diaphragm)


def predicted_values(case: Case, model: Model) -> dict[str, float]:
    """Predicted analog parameters for the components of ``model``.

    ``[prediction]`` of the case gives the first mode and the fixed mass; the tank modal
    analysis (:mod:`analogs.tank`, exact potential flow) gives higher modes, hinge heights
    and everything when the case has no ``[prediction]``. Hinge springs and extra dampers
    start at zero; hinge dampers from the predicted damping ratio:
    ``c = 2 zeta m L^2 omega`` with ``omega = sqrt(g / L)``.
    """
    g = case.rig.gravity
    pendulums = [n for n in model.names if n.startswith("p") and n[1:].isdigit()]
    n_modes = max([int(n[1:]) for n in pendulums] or [1])
    out: dict[str, float] = {}
    # the modal analysis is needed for higher modes or when the case predicts nothing
    if case.prediction is None or n_modes > 1:
        pred = _tank_prediction(case, max(n_modes, 1))
        modes = {f"p{i + 1}": m for i, m in enumerate(pred.modes)}
        for name, mode in modes.items():
            out |= {f"{name}.mass": mode.mass, f"{name}.length": mode.length,
                    f"{name}.hinge_height": mode.hinge_height}
            zeta = mode.damping_ratio if math.isfinite(mode.damping_ratio) else 0.01
            out[f"{name}.zeta"] = zeta
        out |= {"fixed.mass": pred.fixed_mass.mass, "fixed.height": pred.fixed_mass.height,
                "fixed.inertia": pred.fixed_mass.inertia}
    if case.prediction is not None:
        pr = case.prediction
        out |= {"p1.mass": pr.pendulum_mass, "p1.length": pr.pendulum_length,
                "fixed.mass": pr.fixed_mass, "p1.zeta": pr.damping_ratio}
    for name in pendulums:
        if f"{name}.mass" not in out:
            continue
        m, L = out[f"{name}.mass"], out[f"{name}.length"]
        zeta = out.pop(f"{name}.zeta")
        out[f"{name}.damping"] = 2 * zeta * m * L**2 * math.sqrt(g / L)
        out[f"{name}.stiffness"] = 0.0
        out[f"{name}.quadratic_damping"] = 0.0
        out[f"{name}.diaphragm_stiffness"] = 0.0
        out[f"{name}.diaphragm_damping"] = 0.0
    if "fixed.inertia" in out:
        out.setdefault("fixed.axial_inertia", out["fixed.inertia"])
    from analogs import Rotor

    for comp in model.components:
        if isinstance(comp, Rotor):
            # a guess, not a prediction: 5 % of the liquid's inertia about a diameter of a
            # sphere of the tank radius, coupled with a 1 s time constant
            R = case.tank.radius
            liquid = case.liquid.density * 4 / 3 * math.pi * R**3 * case.tank.fill_fraction
            out[f"{comp.name}.inertia"] = 0.05 * 0.4 * liquid * R**2
            out[f"{comp.name}.damping"] = out[f"{comp.name}.inertia"] / 1.0
    return {k: v for k, v in out.items() if not k.endswith(".zeta")}


def length_bounds(predicted_length: float) -> tuple[float, float]:
    """Bounds of a pendulum length around its prediction (+/-20 %)."""
    return (1 - LENGTH_BAND) * predicted_length, (1 + LENGTH_BAND) * predicted_length


def nominal_scale(name: str, value: float, values: Mapping[str, float], gravity: float) -> float:
    """Typical magnitude of a parameter, used to scale the NLP variables to about 1."""
    comp, local = name.split(".", 1)
    m, L = values.get(f"{comp}.mass", 1.0), values.get(f"{comp}.length", 0.05)
    omega = math.sqrt(gravity / L) if L > 0 else 10.0
    physical = {
        "stiffness": m * gravity * L, "diaphragm_stiffness": m * gravity * L,
        "damping": 0.05 * m * L**2 * omega, "diaphragm_damping": 0.05 * m * L**2 * omega,
        "quadratic_damping": 0.05 * m * L**2, "flywheel_angle": 1.0, "omega_correction": 0.1,
    }
    if local in physical:
        return max(abs(value), physical[local])
    return abs(value) if value != 0 else 1.0


def crank_start(problem, *, grid: int = 24) -> dict[str, float]:
    """Robust initial values of the crank nuisance parameters of every crank case.

    The flywheel speed correction comes from the measured force's spectral peak near the
    nominal drive frequency; the initial flywheel angle from a grid over its bounds,
    keeping the angle whose simulated force (at the initial parameters, best scaled by a
    positive factor) is closest to the measurement. Returns values by estimate label.
    """
    import numpy as np

    from derive import RK4, simulate

    from ..data.signals import find_spectral_peaks

    out: dict[str, float] = {}
    for i, exp in enumerate(problem.experiments):
        case = exp.case
        if case.test.excitation != "crank" or case.crank is None:
            continue
        labels = {e.parameter: e for e in problem.estimated if e.case == i}
        if not {"rig.omega_correction", "rig.flywheel_angle"} & set(labels):
            continue
        f_nom = case.crank.frequency
        values = problem.case_values(i, problem.initial)
        if "rig.omega_correction" in labels:
            e = labels["rig.omega_correction"]
            peaks = find_spectral_peaks(case.time, case.force, min_frequency=0.85 * f_nom,
                                        max_frequency=1.15 * f_nom, max_peaks=1)
            if peaks:
                dw = 2 * math.pi * (peaks[0].frequency - f_nom)
                values["rig.omega_correction"] = out[e.name] = min(max(dw, e.lower), e.upper)
        if "rig.flywheel_angle" in labels:
            e = labels["rig.flywheel_angle"]
            F = np.asarray(case.force, float)
            best = (math.inf, e.initial)
            for phi in np.linspace(e.lower, e.upper, grid):
                sim = simulate(exp.derived, {**values, "rig.flywheel_angle": float(phi)}, case.time,
                               exp.excitation, integrator=RK4(), outputs=exp.derived.measured[:1])
                S = sim.outputs[:, 0]
                alpha = max(float(S @ F) / float(S @ S), 0.0) if S @ S > 0 else 0.0
                cost = float(np.sum((F - alpha * S) ** 2))
                if cost < best[0]:
                    best = (cost, float(phi))
            out[e.name] = best[1]
    return out
