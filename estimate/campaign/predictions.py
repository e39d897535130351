"""The tank module's prediction of the campaign's quantities, exact and legacy, at the
groups' fills and as curves against fill.

The analog the fits estimate keeps ``pendulums`` modes, so its fixed mass is the liquid less
those modes' masses: the prediction is made with as many modes as the fitted model has
pendulums.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..fitting.initial import tank_prediction
from .discovery import Setup

__all__ = ["METHODS", "PredictionCurves", "pendulum_count", "predicted", "prediction_curves"]

#: The tank module's methods shown: the converged answer and the SLOSH code's basis.
METHODS = ("exact", "legacy")
#: Fill points of a curve, and how far it reaches beyond the campaign's fills.
POINTS, MARGIN = 17, 0.1


def pendulum_count(quantities: Iterable[str]) -> int:
    """Pendulums of the fitted model, from its quantity names (``p2.mass`` -> 2)."""
    found = [int(m.group(1)) for q in quantities if (m := re.match(r"p(\d+)\.", q))]
    return max(found, default=0)


@lru_cache(maxsize=256)
def predicted(setup: Setup, fill: float, *, pendulums: int, method: str) -> dict[str, float]:
    """Predicted ``fixed.mass`` (kg) and, per pendulum ``pN``, ``mass`` (kg), ``length``
    (m), ``frequency_hz`` (Hz) and ``damping_ratio`` (-) at ``fill`` (cached: do not
    modify the returned dict)."""
    p = tank_prediction(setup.geometry(), fill, density=setup.density,
                        viscosity=setup.viscosity, gravity=setup.gravity,
                        modes=max(pendulums, 1), method=method, diaphragm=setup.diaphragm)
    out = {"fixed.mass": p.fixed_mass.mass}
    for m in p.modes[:pendulums]:
        out |= {f"p{m.index}.mass": m.mass, f"p{m.index}.length": m.length,
                f"p{m.index}.frequency_hz": m.frequency_hz,
                f"p{m.index}.damping_ratio": m.damping_ratio}
    return out


@dataclass(frozen=True)
class PredictionCurves:
    """Predicted quantities of one tank series against fill (liquid depth / height)."""

    setup: Setup
    fills: np.ndarray
    #: method -> quantity -> values at ``fills`` (NaN where the method has no answer).
    values: dict[str, dict[str, np.ndarray]]
    notes: tuple[str, ...] = field(default=())


def prediction_curves(setup: Setup, fills: Iterable[float], *, pendulums: int) -> PredictionCurves:
    """Curves over the campaign's fills (``MARGIN`` beyond, within 5-95 %) for each method;
    a method that fails (the legacy basis knows spheres only) is left out with a note."""
    fills = [f for f in fills if math.isfinite(f)]
    grid = np.linspace(max(0.05, min(fills) - MARGIN), min(0.95, max(fills) + MARGIN), POINTS)
    values, notes = {}, []
    for method in METHODS:
        try:
            points = [predicted(setup, float(f), pendulums=pendulums, method=method) for f in grid]
        except (ValueError, NotImplementedError) as err:
            notes.append(f"no {method} prediction for a {setup.shape}: {err}")
            continue
        values[method] = {q: np.array([p[q] for p in points]) for q in points[0]}
    return PredictionCurves(setup, grid, values, tuple(notes))
