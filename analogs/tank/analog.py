"""The analog a tank prediction gives (:func:`analogs.tank.predict`): its slosh modes as
pendulums (:class:`SloshMode`), the fixed mass (:class:`FixedMassPrediction`) and the whole
(:class:`TankPrediction`: report, JSON, the parameters of an analog model)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

from .geometry import Liquid, Tank

__all__ = ["FixedMassPrediction", "SloshMode", "TankPrediction"]


@dataclass(frozen=True)
class SloshMode:
    """One lateral slosh mode as a pendulum. SI units; heights from the tank bottom."""

    index: int  #: mode number, 1 for the first
    frequency_hz: float  #: natural frequency, Hz
    lam: float  #: eigenvalue omega^2 / g, 1/m
    mass: float  #: pendulum (slosh) mass, kg
    length: float  #: pendulum length, m
    hinge_height: float  #: hinge height, m
    bob_height: float  #: height of the bob (spring-mass location), m
    amplitude_ratio: float  #: wave height at the wall / bob lateral amplitude, -
    damping_ratio: float  #: viscous damping, fraction of critical (nan if no correlation)

    @property
    def omega(self) -> float:
        """Natural frequency in rad/s."""
        return 2.0 * math.pi * self.frequency_hz


@dataclass(frozen=True)
class FixedMassPrediction:
    """The non-sloshing part of the liquid."""

    mass: float  #: kg
    height: float  #: m, from the tank bottom
    inertia: float  #: pitch inertia about its own height, kg m^2 (inferred convention)


@dataclass(frozen=True)
class TankPrediction:
    """Predicted analog parameters for a tank, fill and liquid (see :func:`predict`).

    Attributes
    ----------
    tank : Tank or Rectangular
        The tank geometry.
    liquid : Liquid
        Density and kinematic viscosity.
    gravity : float
        Axial acceleration, m/s^2.
    depth : float
        Liquid depth, m.
    fill_fraction, volume_fraction : float
        Depth over the tank's height, liquid volume over the tank's volume.
    liquid_mass : float
        Mass of the liquid, kg.
    liquid_cg_height : float
        Height of the liquid's centre of mass above the tank bottom, m.
    method, solver : str
        The method asked for (``"exact"``, ``"legacy"``, ...) and the solver it used
        (``"ritz"``, ``"fem"``, ``"closed form"``).
    modes : tuple of SloshMode
        The lateral slosh modes kept, as pendulums.
    fixed_mass : FixedMassPrediction
        The liquid that does not slosh: mass, height and pitch inertia.
    diaphragm : bool
        The tank has a diaphragm (the prediction is still the free-surface one).
    size : int
        Unknowns of the modal analysis (0 in closed form).
    seconds : float
        Time the modal analysis took, s.
    notes : tuple of str
        What the prediction says about itself (validity, the higher modes' damping, ...).
    """

    tank: Tank
    liquid: Liquid
    gravity: float
    depth: float
    fill_fraction: float
    volume_fraction: float
    liquid_mass: float
    liquid_cg_height: float
    method: str
    solver: str
    modes: tuple[SloshMode, ...]
    fixed_mass: FixedMassPrediction
    diaphragm: bool = False
    size: int = 0
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of ``slosh tank --json`` (fixed keys)."""
        return {
            "shape": self.tank.shape,
            "radius": self.tank.radius,
            "fill_fraction": self.fill_fraction,
            "depth": self.depth,
            "liquid_mass": self.liquid_mass,
            "method": self.method,
            "modes": [{"frequency_hz": m.frequency_hz, "lambda_R": m.lam * self.tank.radius,
                       "mass": m.mass, "length": m.length, "hinge_height": m.hinge_height,
                       "amplitude_ratio": m.amplitude_ratio, "damping_ratio": m.damping_ratio}
                      for m in self.modes],
            "fixed_mass": {"mass": self.fixed_mass.mass, "height": self.fixed_mass.height,
                           "inertia": self.fixed_mass.inertia},
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    def report(self) -> str:
        """A readable table of the prediction."""
        t = self.tank
        lines = [
            f"{t!r}, {self.liquid.name} (rho = {self.liquid.density:g} kg/m^3, "
            f"nu = {self.liquid.viscosity:.4g} m^2/s), g = {self.gravity:g} m/s^2",
            f"fill {100 * self.fill_fraction:.2f} % of height ({100 * self.volume_fraction:.2f} %"
            f" of volume), depth {self.depth:.4f} m, liquid mass {self.liquid_mass:.4f} kg, "
            f"c.g. {self.liquid_cg_height:.4f} m",
            f"method {self.method} ({self.solver}, {self.size} unknowns, "
            f"{1e3 * self.seconds:.1f} ms)",
            "",
            f"{'mode':>4} {'f [Hz]':>8} {'lambda R':>9} {'mass [kg]':>10} {'L [m]':>8} "
            f"{'hinge [m]':>10} {'wave/bob':>9} {'zeta [%]':>9}",
        ]
        copied = False
        for m in self.modes:
            mark = " *" if m.index > 1 and math.isfinite(m.damping_ratio) else ""
            copied = copied or bool(mark)
            lines.append(f"{m.index:>4} {m.frequency_hz:8.4f} {m.lam * t.radius:9.5f} "
                         f"{m.mass:10.4f} {m.length:8.4f} {m.hinge_height:10.4f} "
                         f"{m.amplitude_ratio:9.4f} {100 * m.damping_ratio:9.4f}{mark}")
        f = self.fixed_mass
        lines += ["", "L: pendulum length; hinge: hinge height above the tank bottom; wave/bob: "
                      "wave height at the wall over the bob's lateral amplitude; zeta: damping "
                      "ratio (SP-106 wall boundary layer)"]
        if copied:
            lines.append("* the first mode's value (see the note below)")
        lines += ["", f"fixed mass {f.mass:.4f} kg at {f.height:.4f} m, pitch inertia "
                      f"{f.inertia:.5f} kg m^2 (frozen-liquid convention)"]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def analog(self, *, bound_fraction: float = 0.2) -> Any:
        """A ready analog model: rig + fixed mass + one damped pendulum per kept mode.

        Predicted values are the defaults; the pendulum length is bounded to
        ``(1 -+ bound_fraction)`` times its prediction (``bound_fraction`` default 0.2).
        The hinge damper coefficient is ``c = 2 zeta m L^2 omega`` (N m s/rad).

        Examples
        --------
        >>> model = predict(Sphere(0.1016), fill=0.6).analog()  # doctest: +SKIP
        """
        from analogs import FixedMass, HingeDamper, LateralRig, Pendulum

        f = self.fixed_mass
        model = LateralRig() + FixedMass("fixed", mass=f.mass, height=f.height,
                                         inertia=f.inertia)
        for m in self.modes:
            name = f"p{m.index}"
            lo, hi = (1.0 - bound_fraction) * m.length, (1.0 + bound_fraction) * m.length
            model = model + Pendulum(name, mass=m.mass, length=m.length,
                                     hinge_height=m.hinge_height, bounds={"length": (lo, hi)})
            if math.isfinite(m.damping_ratio):
                c = 2.0 * m.damping_ratio * m.mass * m.length**2 * m.omega
                model = model + HingeDamper(name, damping=c)
        return model


# -- the problem ---------------------------------------------------------------------------
