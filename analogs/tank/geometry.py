"""Axisymmetric tank shapes, the liquid, and quadrature over the liquid's meridian section.

Frame: origin on the tank axis at the lowest point of the tank, ``z`` up, SI units.
Every shape is described by its meridian wall profile, a chain of line segments and
circular arcs from the bottom point on the axis to the top point on the axis. The
liquid below a level ``h`` is integrated by horizontal slices: on each non-horizontal
wall piece with parameter ``s`` the map ``r = t r_w(s), z = z_w(s)`` (``t`` in
[0, 1]) is smooth, so Gauss rules in ``(t, s)`` converge exponentially for smooth
integrands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.optimize import brentq

__all__ = ["Capsule", "Cylinder", "Liquid", "Profile", "Sphere", "Tank", "WATER"]


def _check_positive(name: str, value: float, unit: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a positive number in {unit}; got {value!r}.") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"`{name}` must be a positive number in {unit}; got {value!r}.")
    return value


@dataclass(frozen=True)
class Liquid:
    """A Newtonian liquid.

    Parameters
    ----------
    density : float
        Density in kg/m^3 (default water at 20 C, 998.2).
    viscosity : float
        Kinematic viscosity in m^2/s (default water at 20 C, 1.004e-6).
    name : str
        Label for reports.

    Examples
    --------
    >>> round(Liquid(density=1260.0, viscosity=1.3 / 1260.0, name="glycerine").viscosity, 9)
    0.001031746
    """

    density: float = 998.2
    viscosity: float = 1.004e-6
    name: str = "water"

    def __post_init__(self) -> None:
        _check_positive("density", self.density, "kg/m^3")
        _check_positive("viscosity", self.viscosity, "m^2/s")


#: Water at 20 C, the default liquid of :func:`~analogs.tank.predict` and ``slosh tank``.
WATER = Liquid()


def fill_fraction(fill: float | None, volume_fill: float | None) -> tuple[str, float]:
    """``("fill", value)`` or ``("volume_fill", value)``: the one fraction given, checked to
    lie in (0, 1)."""
    if (fill is None) == (volume_fill is None):
        raise ValueError("give exactly one of `fill` (depth fraction) and `volume_fill` "
                         f"(volume fraction); got fill={fill!r}, volume_fill={volume_fill!r}.")
    name, value = ("fill", fill) if fill is not None else ("volume_fill", volume_fill)
    try:
        value = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number in (0, 1); got {value!r}.") from None
    if not 0.0 < value < 1.0:
        raise ValueError(f"`{name}` must be a fraction in (0, 1) (exclusive); got {value!r}. "
                         "Give 60 % as 0.6.")
    return name, value


# A wall piece: ("line", (r0, z0), (r1, z1)) or ("arc", (rc, zc), radius, angle0, angle1),
# angles measured from the +r axis, counter-clockwise, running bottom to top.
_Piece = tuple


@dataclass(frozen=True)
class _Slice:
    """One non-horizontal wall piece used for horizontal slicing, ``s`` in [s0, s1]."""

    piece: _Piece
    z0: float
    z1: float

    def point(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Wall point and its derivative at parameter ``s``: (r, z, dr/ds, dz/ds)."""
        kind = self.piece[0]
        if kind == "line":
            (r0, z0), (r1, z1) = self.piece[1], self.piece[2]
            s = np.asarray(s, dtype=float)
            one = np.ones_like(s)
            return r0 + (r1 - r0) * s, z0 + (z1 - z0) * s, (r1 - r0) * one, (z1 - z0) * one
        _, (rc, zc), a, _, _ = self.piece
        return (rc + a * np.cos(s), zc + a * np.sin(s), -a * np.sin(s), a * np.cos(s))

    def param_range(self) -> tuple[float, float]:
        return (0.0, 1.0) if self.piece[0] == "line" else (self.piece[3], self.piece[4])

    def param_at(self, z: float) -> float:
        """Parameter where the piece reaches height ``z`` (z0 <= z <= z1)."""
        if self.piece[0] == "line":
            (_, z0), (_, z1) = self.piece[1], self.piece[2]
            return (z - z0) / (z1 - z0)
        _, (_, zc), a, _, _ = self.piece
        return math.asin(max(-1.0, min(1.0, (z - zc) / a)))


@dataclass(frozen=True)
class Tank:
    """Base class of axisymmetric tanks; use :class:`Sphere`, :class:`Cylinder`,
    :class:`Capsule` or :class:`Profile`."""

    def _pieces(self) -> list[_Piece]:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def height(self) -> float:
        """Inside height of the tank in m."""
        raise NotImplementedError  # pragma: no cover

    @property
    def shape(self) -> str:
        return type(self).__name__.lower()

    @property
    def radius(self) -> float:
        """Largest inside radius in m."""
        return max(max(abs(p[1][0]), abs(p[2][0])) if p[0] == "line" else p[1][0] + p[2]
                   for p in self._pieces())

    # -- slicing ------------------------------------------------------------------------
    def wall_slices(self) -> list[_Slice]:
        """The wall cut into pieces of rising height (m), bottom first: each with its
        heights ``z0 < z1`` and its parametrisation (the finite elements mesh these)."""
        out = []
        for p in self._pieces():
            if p[0] == "line":
                z0, z1 = p[1][1], p[2][1]
            else:
                _, (_, zc), a, a0, a1 = p
                z0, z1 = zc + a * math.sin(a0), zc + a * math.sin(a1)
            if z1 > z0 + 1e-15 * max(1.0, self.height):
                out.append(_Slice(p, z0, z1))
        return out

    def wall_radius(self, z: float) -> float:
        """Inside radius of the wall in m at height ``z`` (m) above the tank bottom."""
        for sl in self.wall_slices():
            if sl.z0 <= z <= sl.z1:
                return float(sl.point(np.array(sl.param_at(z)))[0])
        raise ValueError(f"`z` must lie in [0, {self.height}] m; got {z!r}.")

    def section_rule(self, depth: float, nt: int, ns: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Gauss rule over the liquid's meridian section ``0 <= r <= r_w(z), z <= depth``.

        Returns points ``r, z`` (m) and weights ``w`` (m^2) such that
        ``sum(w * f(r, z))`` approximates the area integral of ``f`` up to ``depth`` (m).
        ``nt`` points across, ``ns`` points along each wall piece.
        """
        xt, wt = np.polynomial.legendre.leggauss(nt)
        xs, ws = np.polynomial.legendre.leggauss(ns)
        t, wt = 0.5 * (xt + 1.0), 0.5 * wt
        rs, zs, ww = [], [], []
        for sl in self.wall_slices():
            if sl.z0 >= depth:
                break
            s0, s1 = sl.param_range()
            if sl.z1 > depth:
                s1 = sl.param_at(depth)
            s = 0.5 * (s0 + s1) + 0.5 * (s1 - s0) * xs
            w_s = 0.5 * (s1 - s0) * ws
            rw, zw, _, dz = sl.point(s)
            rs.append(np.outer(t, rw).ravel())
            zs.append(np.outer(np.ones_like(t), zw).ravel())
            ww.append(np.outer(wt, w_s * rw * dz).ravel())
        if not rs:
            return np.zeros(0), np.zeros(0), np.zeros(0)
        return np.concatenate(rs), np.concatenate(zs), np.concatenate(ww)

    # -- fill ---------------------------------------------------------------------------
    def volume(self, depth: float | None = None) -> float:
        """Volume in m^3 below ``depth`` (m); the whole tank if ``depth`` is None."""
        depth = self.height if depth is None else depth
        r, _, w = self.section_rule(depth, 4, 24)
        return float(2.0 * math.pi * np.sum(w * r))

    def depth_from_fill(self, fill: float | None = None, *, volume_fill: float | None = None
                        ) -> float:
        """Liquid depth in m from a depth fraction ``fill`` (depth / tank height) or a
        volume fraction ``volume_fill``; give exactly one.

        Examples
        --------
        >>> round(Sphere(0.1).depth_from_fill(volume_fill=0.5), 12)
        0.1
        """
        name, value = fill_fraction(fill, volume_fill)
        if name == "fill":
            return value * self.height
        target = value * self.volume()
        return float(brentq(lambda h: self.volume(h) - target, 0.0, self.height,
                            xtol=1e-15 * self.height, rtol=1e-15))

    def liquid_mass(self, fill: float, density: float) -> float:
        """Mass in kg of liquid of ``density`` (kg/m^3) filled to the depth fraction
        ``fill`` (depth / tank height).

        Examples
        --------
        >>> round(Sphere(0.1).liquid_mass(0.5, 1000.0), 6)   # half of a 0.1 m sphere
        2.094395
        """
        return float(density * self.volume(self.depth_from_fill(fill)))

    def centroid_height(self, depth: float) -> float:
        """Height in m of the liquid's centre of mass for liquid depth ``depth`` (m)."""
        r, z, w = self.section_rule(depth, 4, 24)
        return float(np.sum(w * r * z) / np.sum(w * r))

    def rigid_inertia(self, depth: float, about: float) -> float:
        """Pitch moment of inertia per unit density (m^5) of the liquid frozen solid up to
        ``depth`` (m), about a horizontal axis through the tank axis at height ``about``
        (m)."""
        r, z, w = self.section_rule(depth, 6, 24)
        # integral of (x^2 + (z - a)^2) dV with x = r cos(theta): pi r^3 + 2 pi r (z-a)^2
        return float(np.sum(w * (math.pi * r**3 + 2.0 * math.pi * r * (z - about) ** 2)))


@dataclass(frozen=True)
class Sphere(Tank):
    """Spherical tank of inside radius ``radius`` (m); centre at height ``radius``.

    Examples
    --------
    >>> Sphere(0.1016).height
    0.2032
    """

    radius_: float = field(metadata={"unit": "m"})

    def __init__(self, radius: float) -> None:
        object.__setattr__(self, "radius_", _check_positive("radius", radius, "m"))

    @property
    def radius(self) -> float:  # type: ignore[override]
        return self.radius_

    @property
    def height(self) -> float:
        return 2.0 * self.radius_

    def _pieces(self) -> list[_Piece]:
        a = self.radius_
        return [("arc", (0.0, a), a, -math.pi / 2, math.pi / 2)]

    def __repr__(self) -> str:
        return f"Sphere(radius={self.radius_!r})"


@dataclass(frozen=True)
class Cylinder(Tank):
    """Upright circular cylinder with flat bottom and top.

    Parameters
    ----------
    radius : float
        Inside radius in m.
    length : float
        Inside height in m; the depth fraction ``fill`` is measured against it.

    Examples
    --------
    >>> Cylinder(0.1, length=0.4).height
    0.4
    """

    radius_: float = field(metadata={"unit": "m"})
    length: float = field(metadata={"unit": "m"})

    def __init__(self, radius: float, length: float) -> None:
        radius = _check_positive("radius", radius, "m")
        length = _check_positive("length", length, "m")
        object.__setattr__(self, "radius_", radius)
        object.__setattr__(self, "length", length)

    @property
    def radius(self) -> float:  # type: ignore[override]
        return self.radius_

    @property
    def height(self) -> float:
        return self.length

    def _pieces(self) -> list[_Piece]:
        a, H = self.radius_, self.length
        return [("line", (0.0, 0.0), (a, 0.0)), ("line", (a, 0.0), (a, H)),
                ("line", (a, H), (0.0, H))]

    def __repr__(self) -> str:
        return f"Cylinder(radius={self.radius_!r}, length={self.length!r})"


@dataclass(frozen=True)
class Capsule(Tank):
    """Cylinder of ``cylinder_length`` (m) with hemispherical ends of ``radius`` (m)."""

    radius_: float = field(metadata={"unit": "m"})
    cylinder_length: float = field(metadata={"unit": "m"})

    def __init__(self, radius: float, cylinder_length: float) -> None:
        object.__setattr__(self, "radius_", _check_positive("radius", radius, "m"))
        if not (isinstance(cylinder_length, (int, float)) and cylinder_length >= 0):
            raise ValueError("`cylinder_length` must be a number >= 0 in m; "
                             f"got {cylinder_length!r}.")
        object.__setattr__(self, "cylinder_length", float(cylinder_length))

    @property
    def radius(self) -> float:  # type: ignore[override]
        return self.radius_

    @property
    def height(self) -> float:
        return 2.0 * self.radius_ + self.cylinder_length

    def _pieces(self) -> list[_Piece]:
        a, c = self.radius_, self.cylinder_length
        out: list[_Piece] = [("arc", (0.0, a), a, -math.pi / 2, 0.0)]
        if c > 0:
            out.append(("line", (a, a), (a, a + c)))
        out.append(("arc", (0.0, a + c), a, 0.0, math.pi / 2))
        return out

    def __repr__(self) -> str:
        return f"Capsule(radius={self.radius_!r}, cylinder_length={self.cylinder_length!r})"


@dataclass(frozen=True)
class Profile(Tank):
    """General axisymmetric tank from a piecewise-linear meridian ``(r, z)`` in m.

    ``z`` must start at 0, be non-decreasing and end at the tank top; ``r >= 0``. A first
    point with ``r > 0`` means a flat bottom, a last point with ``r > 0`` a flat top.

    Examples
    --------
    >>> Profile(r=[0.1, 0.1], z=[0.0, 0.3]).height  # a flat-bottomed cylinder
    0.3
    """

    r: tuple[float, ...]
    z: tuple[float, ...]

    def __init__(self, r: Sequence[float], z: Sequence[float]) -> None:
        r_, z_ = np.asarray(r, dtype=float), np.asarray(z, dtype=float)
        problems = []
        if r_.ndim != 1 or r_.shape != z_.shape or r_.size < 2:
            problems.append(f"`r` and `z` must be 1-D of equal length >= 2; got shapes "
                            f"{r_.shape} and {z_.shape}")
        else:
            if np.any(r_ < 0) or not np.all(np.isfinite(r_)):
                problems.append(f"`r` must be finite and >= 0 m; got {r_.tolist()}")
            if z_[0] != 0.0:
                problems.append(f"`z` must start at 0 (the tank bottom); got {z_[0]!r}")
            if np.any(np.diff(z_) < 0) or not np.all(np.isfinite(z_)):
                problems.append(f"`z` must be non-decreasing (no overhangs); got {z_.tolist()}")
            if z_[-1] <= 0:
                problems.append(f"`z` must end above 0; got {z_[-1]!r}")
        if problems:
            raise ValueError("invalid Profile: " + "; ".join(problems) + ".")
        object.__setattr__(self, "r", tuple(r_.tolist()))
        object.__setattr__(self, "z", tuple(z_.tolist()))

    @property
    def height(self) -> float:
        return self.z[-1]

    def _pieces(self) -> list[_Piece]:
        pts = list(zip(self.r, self.z))
        if pts[0][0] > 0:
            pts.insert(0, (0.0, 0.0))
        if pts[-1][0] > 0:
            pts.append((0.0, self.z[-1]))
        return [("line", p, q) for p, q in zip(pts[:-1], pts[1:]) if p != q]


def surface_rule(tank: Tank, depth: float, n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Gauss rule on the free-surface radius [0, r_s]: points (m), weights (m), r_s (m)."""
    rs = tank.wall_radius(depth)
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * rs * (x + 1.0), 0.5 * rs * w, rs
