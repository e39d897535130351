"""Tank modal analysis: analog (pendulum) parameters from tank geometry, fill and liquid.

The linear potential-flow sloshing problem for the lateral (m = 1) modes of an
axisymmetric tank is solved with a converged method (``method="exact"``: Ritz with solid
harmonics, or graded axisymmetric finite elements) or with the SLOSH code's Lomen basis
(``method="legacy"``); an upright rectangular tank's modes are in closed form
(:mod:`analogs.tank.rectangular`). Heights are measured from the tank bottom on the tank
axis, ``z`` up, SI units.

Examples
--------
>>> from analogs.tank import Sphere, predict
>>> p = predict(Sphere(0.1016), fill=0.6)
>>> round(p.modes[0].frequency_hz, 3)
2.091
"""

from .damping import cylinder_damping, damping_validity, sphere_damping
from .geometry import WATER, Capsule, Cylinder, Liquid, Profile, Sphere, Tank
from .prediction import (
                         METHODS,
                         Exact,
                         FiniteElements,
                         FixedMassPrediction,
                         Legacy,
                         Ritz,
                         SloshMode,
                         TankPrediction,
                         predict,
)
from .rectangular import Rectangular

__all__ = [
    "WATER",
    "Capsule",
    "Cylinder",
    "Exact",
    "FiniteElements",
    "FixedMassPrediction",
    "Legacy",
    "METHODS",
    "Liquid",
    "Profile",
    "Rectangular",
    "Ritz",
    "SloshMode",
    "Sphere",
    "Tank",
    "TankPrediction",
    "cylinder_damping",
    "damping_validity",
    "predict",
    "sphere_damping",
]
