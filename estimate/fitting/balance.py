"""Balancing the displacement and force residuals of an estimated carriage motion.

The estimated input weighs the displacement residual by the displacement's noise read
above the signal band. That is the right weight for a measurement of the motion, and the
wrong one for a displacement column that is smooth but not the motion: a planned path (the
command a servo follows with a lag and a ripple) or a heavily filtered record. There the
displacement residuals the fit leaves are many times the assumed noise, while the force
residuals sit near theirs, and the carriage motion is pinned to a path the tank did not
follow. One variance-component step fixes the weights: the displacement noise is scaled
so that both residual groups have the same size in units of their noise, and the fit is
repeated from its own solution (:func:`estimate.fitting.fit` does this when
:func:`rebalanced` asks for it).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["rebalanced", "BALANCE_FACTOR"]

#: The displacement residual (in units of its noise) must exceed the force residual (in
#: units of its own) by this factor before the displacement noise is rescaled: a
#: measurement of the motion leaves about one, a planned path tens.
BALANCE_FACTOR = 3.0


def rebalanced(result):
    """``(problem, text)``: the problem of ``result`` with the displacement noise of every
    case whose displacement residuals are over :data:`BALANCE_FACTOR` times too large for
    it scaled to match, and a note saying so; ``None`` when no case needs it."""
    problem = result.problem
    if not problem.carriage or not result.displacement_residuals:
        return None
    levels, notes = [], []
    for i, ci in enumerate(problem.carriage):
        xr = result.displacement_residuals[i] if i < len(result.displacement_residuals) else None
        if ci is None or xr is None or not problem.noise or problem.noise[i] is None:
            levels.append(None)
            continue
        w = result.weights[i] > 0 if result.weights else np.ones(xr.size, bool)
        s_x = math.sqrt(float(np.mean(xr**2))) / ci.displacement_noise
        f = np.asarray(result.residuals[i], float)[w] / problem.noise[i].force_noise
        s_f = math.sqrt(float(np.mean(f**2)))
        if not (s_f > 0 and s_x > BALANCE_FACTOR * s_f):
            levels.append(None)
            continue
        new = ci.displacement_noise * s_x / s_f
        levels.append(new)
        notes.append(f"{problem.experiments[i].case.test.id}: the displacement residuals were "
                     f"{s_x / s_f:.3g} times the force residuals in units of their noise "
                     f"levels (a displacement that is not the measured motion, e.g. a planned "
                     f"path): refitted with displacement noise {new:.3g} m instead of "
                     f"{ci.displacement_noise:.3g} m")
    if not notes:
        return None
    return problem.with_displacement_noise(levels), "; ".join(notes)
