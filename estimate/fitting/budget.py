"""The liquid mass budget: an analog that is physically possible by construction.

The liquid in the tank (``Case.liquid_mass``: tank geometry, fill, density) is all the mass
the analog's fixed and sloshing masses can share: ``fixed.mass + sum(slosh masses) <=
liquid mass``. A weighed container (``[rig] dry_mass`` a number) leaves both estimated
under that linear bound. An unweighed one (``dry_mass = "estimate"``) makes the rigid mass
(container + fixed liquid) the only mass the lateral force sees besides the slosh masses:
then ``rig.dry_mass`` (the container) is estimated and ``fixed.mass`` follows the slosh
masses, ``liquid - sum(slosh masses)`` (a :class:`Tie`), so the bound reads
``sum(slosh masses) <= liquid mass``.

A bound that is active at the optimum holds the estimates on it: the covariance is the
Gauss-Newton one conditioned on the active bounds (:func:`conditioned`), and the fit says
so (``FitResult.bounds_reached``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Tie", "LinearBound", "liquid_budget", "tank_ranges", "tied_values",
           "conditioned", "BUDGET_RTOL"]

#: Relative tolerance of the liquid masses of several cases fitted together: beyond it they
#: are different fills and no one budget holds.
BUDGET_RTOL = 1e-6


@dataclass(frozen=True)
class Tie:
    """A model parameter that is not estimated but follows the estimates:
    ``parameter = constant + sum(coefficient * estimate)`` (estimates by label)."""

    parameter: str
    constant: float
    terms: tuple[tuple[str, float], ...]
    #: What it is, for reports (``"liquid mass 0.627 kg - p1.mass"``).
    text: str

    def value(self, estimates: Mapping[str, float]) -> float:
        return self.constant + sum(c * estimates[n] for n, c in self.terms)


@dataclass(frozen=True)
class LinearBound:
    """``sum(coefficient * estimate) <= upper`` over estimates by label."""

    terms: tuple[tuple[str, float], ...]
    upper: float
    #: The bound in words, for the verdict (``"p1.mass + fixed.mass <= liquid mass 2.84 kg"``).
    text: str
    #: A bound of the integrator's stability (:mod:`estimate.fitting.stability`), kept when
    #: the fit is retried without the liquid bounds.
    stability: bool = False

    def row(self, names: Sequence[str]) -> np.ndarray:
        """The coefficients as a row over the estimates ``names`` (unscaled)."""
        a = np.zeros(len(names))
        for n, c in self.terms:
            a[list(names).index(n)] = c
        return a

    def slack(self, names: Sequence[str], theta: np.ndarray) -> float:
        """``upper - a theta`` (>= 0 inside)."""
        return float(self.upper - self.row(names) @ np.asarray(theta, float))


def liquid_budget(cases, model, estimated: Sequence[str], values: Mapping[str, float]
                  ) -> tuple[tuple[Tie, ...], tuple[LinearBound, ...], tuple[str, ...]]:
    """The ties and linear bounds that keep ``model``'s masses within the liquid of
    ``cases``, given the parameters to estimate (``estimated``, before ties) and the
    values of the others; and notes saying what was done (or why not).

    ``rig.dry_mass`` among ``estimated`` means the container is not weighed: ``fixed.mass``
    (when the model has it and it is not held) is then tied to the slosh masses."""
    from analogs import FixedMass
    from analogs.rigs import Rig

    liquid, why = _liquid_mass(cases)
    if liquid is None:
        return (), (), ((f"no liquid mass budget: {why}",) if why else ())
    fixed_names = [f"{c.name}.mass" for c in model.components if isinstance(c, FixedMass)]
    slosh = [f"{c.name}.mass" for c in model.components
             if not isinstance(c, (FixedMass, Rig)) and "mass" in c.parameters]
    est = set(estimated)
    free_slosh = [n for n in slosh if n in est]
    held = sum(float(values.get(n, 0.0) or 0.0) for n in slosh if n not in est)
    unweighed = "rig.dry_mass" in est
    ties: list[Tie] = []
    notes: list[str] = []
    lhs = [(n, 1.0) for n in free_slosh]
    constant = held
    for f in fixed_names:
        if unweighed and f in est:
            ties.append(Tie(f, liquid - held, tuple((n, -1.0) for n in free_slosh),
                            f"liquid mass {liquid:.4g} kg - " + (" - ".join(free_slosh) or "0")))
        elif f in est:
            lhs.append((f, 1.0))
        else:
            constant += float(values.get(f, 0.0) or 0.0)
    if ties:
        notes.append(f"the container is not weighed (`[rig] dry_mass = \"estimate\"`): "
                     f"`rig.dry_mass` is estimated and `{ties[0].parameter}` is the liquid not "
                     f"in the slosh masses ({ties[0].text})")
    if not lhs:
        return tuple(ties), (), tuple(notes)
    upper = liquid - constant
    names = " + ".join(n for n, _ in lhs)
    text = (f"{names} <= liquid mass {liquid:.4g} kg"
            + (f" - {constant:.4g} kg held" if constant else ""))
    notes.append(f"masses kept within the liquid: {text} (tank geometry, fill and density)")
    return tuple(ties), (LinearBound(tuple(lhs), upper, text),), tuple(notes)


def tank_ranges(case, model, estimated: Sequence[str], length_upper: Mapping[str, float]
                ) -> dict[str, tuple[float, float]]:
    """The ranges that keep the analog inside its tank (heights from the tank bottom, m;
    inertias, kg m^2), for the parameters among ``estimated`` that the torques determine:

    * a fixed mass's ``height`` within the tank, ``0 <= h <= H``;
    * a pendulum's ``hinge_height`` with its bob inside: ``0 <= h <= H + L_max``
      (``length_upper``: each pendulum's upper length bound by length parameter name);
    * the inertias of the liquid's analog (a fixed mass's, a rotor's, a rotary
      oscillator's: every ``kg m^2`` parameter of a non-rig component) at most the whole
      liquid's at the tank's farthest wall, ``m_liquid (r^2 + H^2)`` (``r`` the tank's
      lateral half-size).

    They are not bounds of the NLP: finite bounds changed IPOPT's path on a six-channel
    rotor fit started from the prediction (28 iterations to the truth without them, 300
    without converging with any of them). The spinning rig's first stage searches within
    them, and a fit that ends outside them says so (``FitResult.outside_tank``). Empty when
    the tank's size or liquid mass is unknown."""
    from analogs import FixedMass, Pendulum, SphericalPendulum
    from analogs.rigs import Rig

    try:
        geom = case.tank.geometry()
        H = float(geom.height)
        r = 0.5 * math.hypot(geom.length, geom.width) if hasattr(geom, "width") \
            else float(geom.radius)
        liquid = float(case.liquid_mass)
    except (AttributeError, ValueError, ArithmeticError, NotImplementedError, TypeError):
        return {}
    if not all(math.isfinite(v) and v > 0 for v in (H, r, liquid)):
        return {}
    est = set(estimated)
    inertia_max = liquid * (r**2 + H**2)
    out: dict[str, tuple[float, float]] = {}
    for c in model.components:
        if isinstance(c, Rig):
            continue
        if isinstance(c, FixedMass):
            out[f"{c.name}.height"] = (0.0, H)
        if isinstance(c, (Pendulum, SphericalPendulum)):
            out[f"{c.name}.hinge_height"] = (0.0, H + length_upper.get(f"{c.name}.length",
                                                                        math.inf))
        for n, p in c.parameters.items():
            if p.unit == "kg m^2":
                out[f"{c.name}.{n}"] = (0.0, inertia_max)
    return {k: v for k, v in out.items() if k in est}


def _liquid_mass(cases) -> tuple[float | None, str | None]:
    """The liquid mass shared by ``cases`` [kg], or ``None`` and why."""
    masses = []
    for c in cases:
        try:
            masses.append(float(c.liquid_mass))
        except (ValueError, ArithmeticError, NotImplementedError) as err:
            return None, f"the liquid mass of {c.path.name} is unknown ({err})"
    if not masses or not all(math.isfinite(m) and m > 0 for m in masses):
        return None, "the liquid mass is not positive"
    if max(masses) - min(masses) > BUDGET_RTOL * max(masses):
        return None, ("the cases hold different liquid masses ("
                      + ", ".join(f"{m:.4g} kg" for m in masses) + ")")
    return masses[0], None


def tied_values(ties: Sequence[Tie], estimates: Mapping[str, float]) -> dict[str, float]:
    """The tied parameters' values at ``estimates`` (by label)."""
    return {t.parameter: t.value(estimates) for t in ties}


def conditioned(covariance: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The covariance of estimates held on the active linear bounds ``rows`` (``k x p``,
    unscaled): ``C - C A^T (A C A^T)^-1 A C``, the Gauss-Newton covariance of the
    equality-constrained estimate."""
    C = np.asarray(covariance, float)
    A = np.atleast_2d(np.asarray(rows, float))
    if A.size == 0:
        return C
    M = A @ C @ A.T
    out = C - C @ A.T @ np.linalg.pinv(M) @ A @ C
    return 0.5 * (out + out.T)
