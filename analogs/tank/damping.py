"""Viscous slosh damping from the NASA SP-106 correlations (wall boundary layer only).

Checked against the sources
---------------------------
* Upright cylinder, flat bottom (Mikishev & Dorozhkin, quoted in NASA SP-106, Abramson
  1966, ch. 4, and in Dodge 2000, "The New Dynamic Behavior of Liquids in Moving
  Containers", ch. 4): logarithmic decrement
  ``delta = 4.98 nu^0.5 R^-0.75 g^-0.25 (1 + (0.318 / sinh(1.84 h/R)) (1 + (1 - h/R) /
  cosh(1.84 h/R)))``. Dodge 2000 writes it as a damping ratio
  ``zeta = 0.79 Re^-0.5 [...]`` with ``Re = sqrt(g R^3) / nu``; ``4.98 / (2 pi) = 0.7926``,
  so the issue's form ``zeta = delta / (2 pi)`` is the same correlation.
* Sphere (Stephens, Leonard & Silveira / Sumner & Stofan, NASA TN D-1991, as fitted in
  SP-106 ch. 4): ``delta = 0.131 B^0.359 f(h/R)`` with the "Boussinesq-type" number
  ``B = 1e4 nu / (2 sqrt 2 R^1.5 g^0.5)`` (SP-106 uses the tank diameter ``d = 2R`` in
  ``nu / (d^1.5 g^0.5)``; ``(2R)^1.5 = 2 sqrt 2 R^1.5`` gives the issue's factor) and
  ``f = (1 + 0.46 (2 - h/R)) / (1.46 (2 - h/R))`` above half full, ``f = R / h`` below;
  ``f`` is continuous (= 1) at half full. The sources give it for the first mode, in the
  range ``1e-6 < nu/(d^1.5 g^0.5) < 1e-2`` roughly (water to glycerine in
  laboratory tanks); the SLOSH code (seed Table 8) applies the same value to every mode,
  and so do we. We could not open the original scans here: the formulas above are as
  quoted by the issue, and they reproduce the seed's Table 8 damping (water, glycerine
  and corn syrup, 60-80 % fill) to better than 0.1 %, which is the check we rely on.

The correlations hold for clean walls without baffles or diaphragms; a diaphragm adds
damping that must be estimated from data.

Validity
--------
:func:`damping_validity` says when a value is an extrapolation: the depth factor (``f``
of the sphere, the bracket of the cylinder) more than :data:`DEPTH_FACTOR_LIMIT` times its
reference value (half full; deep liquid) - both diverge towards empty, and the sphere's
towards full (a 99.9 % fill gives 216 % of critical), where a wall boundary layer no longer
describes the damping - or a sphere's ``nu / (d^1.5 g^0.5)`` outside the range above.
"""

from __future__ import annotations

import math

__all__ = ["DEPTH_FACTOR_LIMIT", "SPHERE_NUMBER_RANGE", "cylinder_damping", "damping_validity",
           "sphere_damping"]

#: Largest depth factor, relative to its half-full (sphere) or deep-liquid (cylinder) value,
#: used without a validity note: fills of about 17-87 % of a sphere's height, h/R > 0.15 in
#: a cylinder.
DEPTH_FACTOR_LIMIT = 3.0
#: Range of ``nu / (d^1.5 g^0.5)`` (d the diameter) of the sphere correlation's data.
SPHERE_NUMBER_RANGE = (1e-6, 1e-2)


def _sphere_factor(hr: float) -> float:
    return (1.0 + 0.46 * (2.0 - hr)) / (1.46 * (2.0 - hr)) if hr >= 1.0 else 1.0 / hr


def _cylinder_factor(hr: float) -> float:
    x = 1.84 * hr
    return 1.0 + (0.318 / math.sinh(x)) * (1.0 + (1.0 - hr) / math.cosh(x))


def sphere_damping(radius: float, depth: float, viscosity: float, gravity: float) -> float:
    """Damping ratio (fraction of critical) of slosh in a sphere.

    Parameters
    ----------
    radius : float
        Sphere radius R in m.
    depth : float
        Liquid depth h in m, 0 < h < 2R.
    viscosity : float
        Kinematic viscosity in m^2/s.
    gravity : float
        Axial acceleration in m/s^2.

    Examples
    --------
    >>> round(100 * sphere_damping(0.1016, 0.6 * 0.2032, 0.893e-6, 9.81), 3)
    0.703
    """
    b = 1e4 / (2.0 * math.sqrt(2.0)) * viscosity / (radius**1.5 * math.sqrt(gravity))
    return 0.131 / (2.0 * math.pi) * b**0.359 * _sphere_factor(depth / radius)


def cylinder_damping(radius: float, depth: float, viscosity: float, gravity: float) -> float:
    """Damping ratio (fraction of critical) of slosh in an upright flat-bottomed cylinder.

    Parameters
    ----------
    radius : float
        Cylinder radius R in m.
    depth : float
        Liquid depth h in m.
    viscosity : float
        Kinematic viscosity in m^2/s.
    gravity : float
        Axial acceleration in m/s^2.

    Examples
    --------
    >>> round(cylinder_damping(1.0, 3.0, 1e-6, 9.81), 6)  # deep liquid: 0.79 Re^-1/2
    0.000449
    """
    return (4.98 / (2.0 * math.pi) * math.sqrt(viscosity) * radius**-0.75 * gravity**-0.25
            * _cylinder_factor(depth / radius))


def damping_validity(shape: str, radius: float, depth: float, viscosity: float,
                     gravity: float) -> str | None:
    """Why the damping correlation of ``shape`` (``"sphere"`` or ``"cylinder"``) does not
    hold at this depth and liquid, or None when it does (see the module docstring).

    Parameters
    ----------
    shape : str
        ``"sphere"`` or ``"cylinder"``.
    radius, depth : float
        Tank radius and liquid depth in m.
    viscosity : float
        Kinematic viscosity in m^2/s.
    gravity : float
        Axial acceleration in m/s^2.

    Examples
    --------
    >>> damping_validity("sphere", 0.1016, 0.6 * 0.2032, 1.004e-6, 9.81) is None
    True
    """
    hr = depth / radius
    factor = (_sphere_factor if shape == "sphere" else _cylinder_factor)(hr)
    why = []
    if factor > DEPTH_FACTOR_LIMIT:  # both factors are 1 half full (sphere), deep (cylinder)
        where = f"fill {100 * depth / (2 * radius):.3g} % of the height" if shape == "sphere" \
            else f"depth {hr:.3g} radii"
        why.append(f"{where}: its depth factor is {factor:.3g} times the "
                   f"{'half-full' if shape == 'sphere' else 'deep-liquid'} value, used up to "
                   f"{DEPTH_FACTOR_LIMIT:g} times")
    if shape == "sphere":
        number = viscosity / ((2 * radius) ** 1.5 * math.sqrt(gravity))
        lo, hi = SPHERE_NUMBER_RANGE
        if not lo <= number <= hi:
            why.append(f"nu/(d^1.5 g^0.5) = {number:.3g}, outside its data ({lo:g} to {hi:g})")
    if not why:
        return None
    return (f"damping_ratio is outside the validity range of the SP-106 {shape} correlation ("
            + "; ".join(why) + "): an extrapolation, not a prediction")
