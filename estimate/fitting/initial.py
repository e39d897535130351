"""Initial values, bounds and scales of estimated parameters, from the tank prediction."""

from __future__ import annotations

import math
import weakref
from collections.abc import Iterable, Mapping
from typing import Any

from analogs import Model
from analogs.errors import InputError

from ..data.case import Case

__all__ = ["predicted_values", "predicted_sources", "source_notes", "prediction_conflicts",
           "length_bounds", "nominal_scale", "tank_prediction", "case_prediction", "LENGTH_BAND",
           "PREDICTION_FACTOR"]

#: Pendulum lengths are kept within +/-20 % of the prediction, as classical slosh-test fits do.
LENGTH_BAND = 0.20

#: A ``[prediction]`` mass or length more than this factor above or below the tank's own
#: modal prediction is reported: slosh codes and the modal analysis agree to a few per cent
#: on clean tanks, and a diaphragm moves the first mode by tens of per cent, not 3x.
PREDICTION_FACTOR = 3.0


def tank_prediction(tank, fill: float, *, density: float, viscosity: float, gravity: float,
                    modes: int = 1, method: str = "exact", diaphragm: bool = False):
    """The tank modal analysis (:func:`analogs.tank.predict`) of a case file's tank.

    ``tank`` is an :mod:`analogs.tank` geometry (a case file's ``[tank]`` gives it:
    :meth:`estimate.data.case.Tank.geometry`); fill as liquid depth / tank height, density
    in kg/m^3, kinematic viscosity in m^2/s, gravity in m/s^2. The modal analysis is kept
    on disk (:mod:`estimate.fitting._tank_cache`): a tank and fill seen before costs no
    solve (a rectangular tank's modes are in closed form)."""
    from analogs.tank import METHODS, Liquid, predict

    from ._tank_cache import CachedSolver

    if method not in METHODS:
        raise InputError(f"tank modal analysis method must be one of {', '.join(METHODS)}, "
                         f"got {method!r}")
    return predict(tank, fill=fill, liquid=Liquid(density=density, viscosity=viscosity),
                   gravity=gravity, modes=modes, method=CachedSolver(METHODS[method]()),
                   diaphragm=diaphragm)


#: The tank predictions of live cases: ``id(case) -> (weak reference, {modes: prediction})``
#: (a case holds arrays, so it is no dictionary key itself).
_PREDICTIONS: dict[int, tuple[weakref.ref, dict[int, Any]]] = {}


def case_prediction(case: Case, modes: int):
    """The tank modal analysis of ``case`` with ``modes`` modes (:func:`tank_prediction` of
    its ``[tank]``, ``[liquid]`` and gravity), computed once per case and number of modes:
    a fit asks for it when it loads (:func:`prediction_conflicts`), for the first stage's
    frequency and for the initial values. A failure is not kept (it is raised each time).

    Parameters
    ----------
    case : Case
        A loaded case (never changed: a case is immutable).
    modes : int
        Number of slosh modes.
    """
    key = id(case)
    entry = _PREDICTIONS.get(key)
    if entry is None or entry[0]() is not case:
        entry = (weakref.ref(case, lambda _: _PREDICTIONS.pop(key, None)), {})
        _PREDICTIONS[key] = entry
    kept = entry[1]
    if modes not in kept:
        kept[modes] = _tank_prediction(case, modes)
    return kept[modes]


def _tank_prediction(case: Case, modes: int):
    return tank_prediction(case.tank.geometry(), case.tank.fill_fraction,
                           density=case.liquid.density,
                           viscosity=case.liquid.kinematic_viscosity, gravity=case.rig.gravity,
                           modes=modes, diaphragm=case.tank.diaphragm)


def prediction_conflicts(case: Case, *, factor: float = PREDICTION_FACTOR) -> list[str]:
    """Warnings for the ``[prediction]`` values of ``case`` (pendulum mass and length, fixed
    mass) that differ from the tank geometry's modal prediction by more than ``factor``,
    each naming both numbers; empty without ``[prediction]``."""
    pr = case.prediction
    if pr is None:
        return []
    pred = case_prediction(case, 1)
    pairs = (("pendulum_mass", pr.pendulum_mass, pred.modes[0].mass, "kg"),
             ("pendulum_length", pr.pendulum_length, pred.modes[0].length, "m"),
             ("fixed_mass", pr.fixed_mass, pred.fixed_mass.mass, "kg"))
    t = case.tank
    out = []
    for key, given, modal, unit in pairs:
        ratio = given / modal if modal > 0 else math.inf
        if not 1 / factor <= ratio <= factor:
            out.append(f"{case.path.name}: [prediction] {key} = {given:.4g} {unit} contradicts "
                       f"the modal prediction {modal:.4g} {unit} of the tank ({t.size_text}, "
                       f"fill {t.fill_fraction:g}) by a factor {ratio:.3g} (more "
                       f"than {factor:g}): check [tank] and [prediction]; the fit starts from "
                       "[prediction]")
    return out


def predicted_values(case: Case, model: Model) -> dict[str, float]:
    """Predicted analog parameters for the components of ``model`` (see
    :func:`predicted_sources`, which also says where each value comes from)."""
    return predicted_sources(case, model)[0]


#: Where an initial value comes from (:func:`predicted_sources`).
FROM_PREDICTION = "[prediction]"
FROM_GUESS = "a guess"


def predicted_sources(case: Case, model: Model, needed: Iterable[str] | None = None
                      ) -> tuple[dict[str, float], dict[str, str], str | None]:
    """Predicted analog parameters for the components of ``model``, where each comes from,
    and why the tank modal analysis could not supply any (``None`` when it did or was not
    needed).

    ``[prediction]`` of the case gives the first mode (mass, length, damping ratio) and the
    fixed mass; the tank modal analysis (:mod:`analogs.tank`, exact potential flow) gives
    higher modes, hinge heights, the fixed mass's height and inertias, and everything when
    the case has no ``[prediction]``. It runs when the case has no ``[prediction]``, when the
    model has higher modes, or when a parameter in ``needed`` (default: every parameter of
    the model) is not in ``[prediction]``. Hinge springs and extra dampers start at zero;
    hinge dampers from the predicted damping ratio: ``c = 2 zeta m L^2 omega`` with
    ``omega = sqrt(g / L)``. Rotors, rotary oscillators and the bob inertias of a 3-DOF
    pendulum start from guesses (source :data:`FROM_GUESS`).
    """
    g = case.rig.gravity
    pendulums = [n for n in model.names if n.startswith("p") and n[1:].isdigit()]
    n_modes = max([int(n[1:]) for n in pendulums] or [1])
    needed = set(p.name for p in model.parameters) if needed is None else set(needed)
    out: dict[str, float] = {}
    source: dict[str, str] = {}
    pred = case.prediction
    from_prediction = {} if pred is None else {
        "p1.mass": pred.pendulum_mass, "p1.length": pred.pendulum_length,
        "fixed.mass": pred.fixed_mass, "p1.zeta": pred.damping_ratio}
    analysis_needed = pred is None or n_modes > 1 or any(
        n not in from_prediction and _from_analysis(n) for n in needed)
    failure = None
    if analysis_needed:
        try:
            analysis = case_prediction(case, max(n_modes, 1))
        except (InputError, ValueError, ArithmeticError) as err:
            analysis, failure = None, f"the tank modal analysis failed: {err}"
        if analysis is not None:
            tank = case.tank
            label = (f"the tank modal analysis ({tank.size_text}, "
                     f"{100 * tank.fill_fraction:g} % fill)")
            for i, mode in enumerate(analysis.modes):
                name = f"p{i + 1}"
                zeta = mode.damping_ratio if math.isfinite(mode.damping_ratio) else 0.01
                out |= {f"{name}.mass": mode.mass, f"{name}.length": mode.length,
                        f"{name}.hinge_height": mode.hinge_height, f"{name}.zeta": zeta}
            fm = analysis.fixed_mass
            out |= {"fixed.mass": fm.mass, "fixed.height": fm.height, "fixed.inertia": fm.inertia,
                    "fixed.axial_inertia": fm.inertia}
            source |= dict.fromkeys(out, label)
    out |= from_prediction
    source |= dict.fromkeys(from_prediction, FROM_PREDICTION)
    for name in pendulums:
        if f"{name}.mass" not in out:
            continue
        m, L = out[f"{name}.mass"], out[f"{name}.length"]
        zeta = out.pop(f"{name}.zeta")
        out[f"{name}.damping"] = 2 * zeta * m * L**2 * math.sqrt(g / L)
        source[f"{name}.damping"] = source.pop(f"{name}.zeta")
        for k in ("stiffness", "quadratic_damping", "diaphragm_stiffness", "diaphragm_damping",
                  "twist_stiffness", "twist_damping"):
            out[f"{name}.{k}"] = 0.0
            source[f"{name}.{k}"] = "zero (no hinge element predicted)"
    _guesses(case, model, out, source)
    keep = {k: v for k, v in out.items() if not k.endswith(".zeta")}
    return keep, {k: source[k] for k in keep}, failure


def _from_analysis(name: str) -> bool:
    """Whether the tank modal analysis supplies ``name`` (heights, inertias, modes)."""
    comp, local = name.split(".", 1)
    if comp == "fixed":
        return local in ("mass", "height", "inertia", "axial_inertia")
    return comp.startswith("p") and comp[1:].isdigit() and local in ("mass", "length",
                                                                     "hinge_height")


def _guesses(case: Case, model: Model, out: dict[str, float], source: dict[str, str]) -> None:
    """Starting values nothing predicts: rotors, rotary oscillators, 3-DOF bob inertias."""
    from analogs import RotaryOscillator, Rotor, ThreeDofPendulum

    R = case.tank.geometry().radius  # a rectangular tank: half its length along the motion
    liquid = case.tank.liquid_mass(case.liquid.density)
    spin = abs(case.spin.rate) if case.spin is not None else 0.0
    for comp in model.components:
        n = comp.name
        if isinstance(comp, Rotor):
            # 5 % of the liquid's inertia about a diameter of a sphere of the tank radius,
            # coupled with a 1 s time constant
            out[f"{n}.inertia"] = 0.05 * 0.4 * liquid * R**2
            out[f"{n}.damping"] = out[f"{n}.inertia"] / 1.0
            source |= dict.fromkeys((f"{n}.inertia", f"{n}.damping"),
                                    f"{FROM_GUESS} (5 % of the liquid's inertia, 1 s coupling)")
        elif isinstance(comp, RotaryOscillator):
            # the same inertia, a natural frequency above the spin rate (where it is stable
            # with damping relative to the tank), 5 % of critical damping
            J = 0.05 * 0.4 * liquid * R**2
            w = max(1.5 * spin, 2 * math.pi)
            out |= {f"{n}.inertia": J, f"{n}.stiffness": J * w**2, f"{n}.damping": 0.1 * J * w}
            source |= dict.fromkeys((f"{n}.inertia", f"{n}.stiffness", f"{n}.damping"),
                                    f"{FROM_GUESS} (natural frequency {w / (2 * math.pi):.3g} Hz)")
        elif isinstance(comp, ThreeDofPendulum) and f"{n}.mass" in out:
            bob = 0.1 * out[f"{n}.mass"] * out[f"{n}.length"] ** 2
            out |= {f"{n}.inertia": bob, f"{n}.axial_inertia": bob}
            source |= dict.fromkeys((f"{n}.inertia", f"{n}.axial_inertia"),
                                    f"{FROM_GUESS} (10 % of m L^2)")


def source_notes(sources: Mapping[str, str], names: Iterable[str]) -> list[str]:
    """One note per source naming the estimated parameters ``names`` it started."""
    by_source: dict[str, list[str]] = {}
    for n in names:
        if n in sources:
            by_source.setdefault(sources[n], []).append(n)
    return [f"initial values from {src}: {', '.join(f'`{n}`' for n in ns)}"
            for src, ns in by_source.items()]


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
        "lag": 0.01,
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
