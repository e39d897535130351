"""Export an analog as Basilisk slosh effectors (``bsk``, the AVS lab's astrodynamics
framework): spherical pendulums (``sphericalPendulum``), linear spring-mass-dampers
(``linearSpringMassDamper``) and the rigid liquid added to the spacecraft hub.

The mapping needs no Basilisk: :func:`basilisk_analog` computes the effectors' parameters
in the spacecraft body frame ``B`` and :meth:`BasiliskAnalog.script` writes them as a
Python module a Basilisk user imports (it imports Basilisk when it runs).

How the analog maps (Basilisk's model: a point mass on a massless rod from the tank point
``d`` (m, in ``B``), at rest along ``pHat_01``; the damping matrix ``D`` (N s/m) acts on
the mass's velocity relative to the body, ``-D l'``):

- a spherical pendulum (mass ``m``, length ``L``, hinge at ``hinge_height`` on the tank
  axis) becomes ``sphericalPendulum`` with ``massInit = m``, ``pendulumRadius = L``, ``d``
  the hinge in ``B`` and ``pHat_01 = -T.z`` (where it hangs), ``pHat_02 = T.y``,
  ``pHat_03 = T.x``; the hinge damping ``c`` (N m s/rad) becomes ``D = c / L^2 I``: the
  force ``-D l'`` on the mass is the torque ``-c omega`` about the hinge for the rod's
  angular velocity ``omega`` relative to the body (Basilisk issue 1484, fixed by pull
  request 1485: before it, an isotropic ``D`` did no work). That is our
  :class:`~analogs.SwingDamper`; a :class:`~analogs.HingeDamper` (each angle's rate) maps
  to the same ``D``, exact for a swing along a tank axis and to second order in the swing
  angle otherwise. Basilisk's pendulum has no hinge spring: an analog with one is refused;
- a planar pendulum of a lateral fit is made spherical first
  (:func:`analogs.vehicle.axisymmetric`: an axisymmetric tank);
- a mass suspended along one tank axis becomes ``linearSpringMassDamper`` (``k``, ``c``,
  ``massInit``, rest position ``r_PB_B``, direction ``pHat_B``);
- a fixed (rigid) liquid mass is added to the hub's mass, centre of mass and inertia.

The effectors' masses are constant. Attached to a Basilisk ``FuelTank``
(``pushFuelSloshParticle``) they drain with the tank; Basilisk issue 1486 (fixed by pull
request 1488) drained the tank by ``(1 + slosh mass fraction)`` times the flow.
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from analogs import (
    Attachment,
    DiaphragmSpring,
    FixedMass,
    FreeSpacecraft,
    HingeDamper,
    HingeSpring,
    Pendulum,
    Rig,
    SphericalPendulum,
    SuspendedMass,
    SwingDamper,
)
from analogs.errors import InputError
from analogs.model import Model
from analogs.vehicle import axisymmetric, degrees_of_freedom

__all__ = ["BasiliskAnalog", "BasiliskPendulum", "BasiliskRigidMass", "BasiliskSpringMass",
           "basilisk_analog"]

_LINEAR_HINGE = (HingeSpring, HingeDamper, DiaphragmSpring, SwingDamper)
Vector = tuple[float, float, float]
Matrix = tuple[Vector, Vector, Vector]


@dataclass(frozen=True)
class BasiliskPendulum:
    """Parameters of a Basilisk ``sphericalPendulum`` (SI units, body frame ``B``)."""

    name: str
    mass: float  #: kg, ``massInit``
    radius: float  #: m, ``pendulumRadius``
    d: Vector  #: m, the hinge (tank point) from ``B``
    D: Matrix  #: N s/m, damping of the mass's velocity relative to the body
    pHat_01: Vector  #: where the mass hangs at rest
    pHat_02: Vector
    pHat_03: Vector


@dataclass(frozen=True)
class BasiliskSpringMass:
    """Parameters of a Basilisk ``linearSpringMassDamper`` (SI units, body frame ``B``)."""

    name: str
    mass: float  #: kg, ``massInit``
    k: float  #: N/m
    c: float  #: N s/m
    r_PB_B: Vector  #: m, rest position of the mass from ``B``
    pHat_B: Vector  #: direction of motion


@dataclass(frozen=True)
class BasiliskRigidMass:
    """A rigid liquid mass to add to the hub: ``mass`` (kg) with its centre at ``r_B``
    (m, from ``B``) and central inertia ``inertia_B`` (kg m^2, body axes)."""

    name: str
    mass: float
    r_B: Vector
    inertia_B: Matrix


@dataclass(frozen=True)
class BasiliskAnalog:
    """An analog as Basilisk effectors; :meth:`script` writes it as a Python module."""

    pendulums: tuple[BasiliskPendulum, ...]
    spring_masses: tuple[BasiliskSpringMass, ...]
    rigid_masses: tuple[BasiliskRigidMass, ...]
    degrees_of_freedom: tuple[str, ...]
    #: Hub mass properties from a ``FreeSpacecraft`` rig (mass kg, inertia kg m^2 about
    #: its centre of mass ``B``), without the liquid; None for a tank alone.
    hub: tuple[float, Matrix] | None = None
    source: str = ""
    placement: str = ""
    notes: tuple[str, ...] = field(default=())

    def hub_with_liquid(self, mass: float, r_BcB_B: Sequence[float],
                        inertia_Bc_B: Sequence[Sequence[float]]) -> tuple[float, Vector, Matrix]:
        """The hub's ``(mHub, r_BcB_B, IHubPntBc_B)`` with the rigid liquid added: total
        mass (kg), centre of mass (m, from ``B``) and central inertia (kg m^2)."""
        return _combine(mass, r_BcB_B, inertia_Bc_B, self.rigid_masses)

    def script(self, module: str = "slosh_bsk") -> str:
        """The analog as a Python module for Basilisk users (see :func:`basilisk_analog`);
        ``module`` is the name its docstring imports it by."""
        from ._basilisk_template import render

        return render(self, datetime.datetime.now(datetime.timezone.utc), module=module)


def _combine(mass, r, inertia, rigid) -> tuple[float, Vector, Matrix]:
    m = float(mass)
    r = np.asarray(r, float).reshape(3)
    first = m * r
    total = m
    for body in rigid:
        total += body.mass
        first = first + body.mass * np.asarray(body.r_B)
    c = first / total
    I = _shift(np.asarray(inertia, float).reshape(3, 3), m, r - c)
    for body in rigid:
        I = I + _shift(np.asarray(body.inertia_B), body.mass, np.asarray(body.r_B) - c)
    return total, _vec(c), _mat(I)


def _shift(I, m, r):
    """Parallel axis: inertia about a point at ``-r`` from the centre of mass."""
    return I + m * (np.dot(r, r) * np.eye(3) - np.outer(r, r))


def _vec(v) -> Vector:
    return tuple(float(x) + 0.0 for x in np.asarray(v, float).reshape(3))  # type: ignore[return-value]


def _mat(M) -> Matrix:
    return tuple(_vec(row) for row in np.asarray(M, float).reshape(3, 3))  # type: ignore[return-value]


def _unit(v, what: str) -> np.ndarray:
    v = np.asarray(v, float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or np.linalg.norm(v) == 0:
        raise InputError(f"{what}: expected three finite numbers, not all zero, got {v.tolist()}")
    return v / np.linalg.norm(v)


def _tank_frame(axis: np.ndarray) -> np.ndarray:
    """Columns: tank x, y, z in ``B``; tank x is ``B.x`` made normal to the axis (``B.y``
    when the axis is near ``B.x``): any choice serves an axisymmetric tank."""
    seed = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    x = seed - seed.dot(axis) * axis
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def basilisk_analog(
    model: Model,
    values: Mapping[str, float],
    *,
    tank_position: Sequence[float] | None = None,
    tank_axis: Sequence[float] | None = None,
    source: str = "",
) -> BasiliskAnalog:
    """Basilisk effector parameters of the analog ``model`` with parameter ``values``.

    Parameters
    ----------
    model : analogs.Model
        The analog: components of a lateral-rig fit (planar pendulums are made spherical,
        :func:`analogs.vehicle.axisymmetric`) or of a ``FreeSpacecraft`` (whose bus is the
        hub: it places the tank and gives the hub's mass and inertia).
    values : mapping
        Parameter values by dotted name (``"p1.mass"``), over the declared defaults.
    tank_position : 3 floats, optional
        The tank origin ``O`` (tank bottom, on its axis) in the body frame ``B`` (m);
        default ``(0, 0, 0)``. Not with a ``FreeSpacecraft``.
    tank_axis : 3 floats, optional
        The tank's z axis in ``B`` (toward the liquid's free surface, against the
        apparent gravity that settles it); default ``(0, 0, 1)``. Not with a
        ``FreeSpacecraft``.
    source : str
        Where the values come from (a fit file), for the script's docstring.

    Raises
    ------
    InputError
        Listing every part that cannot be a Basilisk effector (a hinge spring, an
        amplitude-dependent hinge element, a mass suspended along several axes), and every
        value the mapping needs and does not have.

    Examples
    --------
    >>> from analogs import FixedMass, HingeDamper, SphericalPendulum
    >>> a = basilisk_analog(FixedMass("fixed") + SphericalPendulum("p1") + HingeDamper("p1"),
    ...                     {"fixed.mass": 1.5, "fixed.height": 0.05, "fixed.inertia": 0.004,
    ...                      "fixed.axial_inertia": 0.006, "p1.mass": 1.3, "p1.length": 0.055,
    ...                      "p1.hinge_height": 0.1, "p1.damping": 0.001},
    ...                     tank_position=(0.0, 0.0, 0.5))
    >>> a.pendulums[0].d, a.pendulums[0].pHat_01
    ((0.0, 0.0, 0.6), (0.0, 0.0, -1.0))
    """
    rig = next((c for c in model.components if isinstance(c, Rig)), None)
    hub = None
    if isinstance(rig, FreeSpacecraft):
        if tank_position is not None or tank_axis is not None:
            raise InputError("a FreeSpacecraft places its tank (its `radius`, `height` and "
                             "`tank_axis`): give no tank position or axis")
        v = _values(rig, values, ("radius", "height", "mass", "inertia_x", "inertia_y",
                                  "inertia_z"), [])
        origin = np.array([v["radius"], 0.0, v["height"]])
        frame = np.eye(3) if rig.tank_axis == "spin" else \
            np.column_stack([[0.0, 0, 1], [0.0, 1, 0], [-1.0, 0, 0]])
        hub = (v["mass"], _mat(np.diag([v["inertia_x"], v["inertia_y"], v["inertia_z"]])))
    else:
        origin = np.zeros(3) if tank_position is None else np.asarray(tank_position, float)
        if origin.shape != (3,) or not np.all(np.isfinite(origin)):
            raise InputError(f"tank position: expected three finite numbers (m), got "
                             f"{np.asarray(tank_position).tolist()}")
        frame = _tank_frame(_unit((0, 0, 1) if tank_axis is None else tank_axis, "tank axis"))
    if any(type(c) is Pendulum for c in model.components):
        model = axisymmetric(model)
    problems: list[str] = []
    attached: dict[str, list[Attachment]] = {}
    for c in model.components:
        if isinstance(c, Attachment):
            attached.setdefault(c.host, []).append(c)
    pendulums, springs, rigid = [], [], []
    for c in model.components:
        if isinstance(c, (Rig, Attachment)):
            continue
        if type(c) is FixedMass:
            v = _values(c, values, ("mass", "height", "inertia", "axial_inertia"), problems)
            if len(v) == 4:
                I_T = np.diag([v["inertia"], v["inertia"], v["axial_inertia"]])
                rigid.append(BasiliskRigidMass(c.name, v["mass"],
                                               _vec(origin + v["height"] * frame[:, 2]),
                                               _mat(frame @ I_T @ frame.T)))
        elif type(c) is SphericalPendulum:
            k, damping = _hinge(c, attached.get(c.name, []), values, problems)
            v = _values(c, values, ("mass", "length", "hinge_height"), problems)
            if len(v) == 3 and damping is not None:
                L = v["length"]
                pendulums.append(BasiliskPendulum(
                    c.name, v["mass"], L, _vec(origin + v["hinge_height"] * frame[:, 2]),
                    _mat(damping / L**2 * np.eye(3)), _vec(-frame[:, 2]), _vec(frame[:, 1]),
                    _vec(frame[:, 0])))
        elif type(c) is SuspendedMass and len(c.axes) == 1:
            a = c.axes
            v = _values(c, values, ("mass", "height", f"stiffness_{a}", f"damping_{a}"), problems)
            if len(v) == 4:
                springs.append(BasiliskSpringMass(
                    c.name, v["mass"], v[f"stiffness_{a}"], v[f"damping_{a}"],
                    _vec(origin + v["height"] * frame[:, 2]), _vec(frame[:, "xyz".index(a)])))
            problems += [f"{e.label} on a suspended mass: its springs and dampers are its own "
                         "parameters" for e in attached.get(c.name, [])]
        elif type(c) is SuspendedMass:
            problems.append(f"{c.label} moves along {len(c.axes)} axes: a Basilisk "
                            "linearSpringMassDamper moves along one (one per axis would "
                            "count the mass once per axis)")
        else:
            problems.append(f"{c.label} has no Basilisk slosh effector (spherical pendulum, "
                            "linear spring-mass-damper or rigid mass)")
    if problems:
        raise InputError("cannot write the analog as Basilisk effectors: " + "; ".join(problems))
    placement = (f"tank origin O (tank bottom, on its axis) at {_fmt(origin)} m from B, tank axes "
                 f"in B: x {_fmt(frame[:, 0])}, y {_fmt(frame[:, 1])}, z {_fmt(frame[:, 2])}")
    return BasiliskAnalog(tuple(pendulums), tuple(springs), tuple(rigid),
                          degrees_of_freedom(model), hub, source, placement)


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in np.asarray(v, float) + 0.0) + ")"


def _values(c, values: Mapping[str, float], names, problems: list[str]) -> dict[str, float]:
    out = {}
    for local in names:
        full = f"{c.name}.{local}"
        v = values.get(full, c.parameter(local).default)
        if v is None or not math.isfinite(v):
            problems.append(f"no value for `{full}` ({c.parameter(local).unit}; `--set "
                            f"{full}=VALUE`)")
        else:
            out[local] = float(v)
    return out


def _hinge(c, elements, values, problems) -> tuple[float, float | None]:
    """Small-amplitude hinge stiffness and damping of the linear elements on ``c``; other
    elements and a nonzero stiffness are problems (damping None then)."""
    k = damping = 0.0
    ok = True
    for e in elements:
        if type(e) not in _LINEAR_HINGE:
            problems.append(f"{e.label}: Basilisk's spherical pendulum has only a linear "
                            "damper")
            ok = False
            continue
        local = {n: values.get(f"{c.name}.{n}", e.parameter(n).default) for n in e.parameters}
        missing = [n for n, v in local.items() if v is None]
        if missing:
            problems += [f"no value for `{c.name}.{n}`" for n in missing]
            ok = False
            continue
        dk, dc = e.hinge_terms(local)
        k, damping = k + dk, damping + dc
    if k != 0:
        problems.append(f"`{c.name}` has a hinge stiffness of {k:g} N m/rad: Basilisk's "
                        "spherical pendulum has no hinge spring (fit with `pN:nospring`, or "
                        f"`--set {c.name}.stiffness=0` if it is negligible)")
        ok = False
    return k, damping if ok else None
