"""Elements acting on a host's hinge angles: springs, dampers, an elastomeric diaphragm."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .component import Attachment
from .parameter import Param

if TYPE_CHECKING:  # pragma: no cover
    from .declaration import Declaration

__all__ = ["HingeSpring", "HingeDamper", "SwingDamper", "QuadraticDamper", "DiaphragmSpring"]


class HingeSpring(Attachment):
    """Torsional spring on the host's hinge: torque ``-k * angle`` (k in N m/rad).

    Parameter ``<host>.stiffness``.
    """

    parameters = {"stiffness": Param("N m/rad", 0.0, 0.0, description="hinge spring constant")}

    def __init__(self, host: str = "p1", *, stiffness: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(host, bounds=bounds, stiffness=stiffness)

    def hinge_terms(self, v):
        return v.get("stiffness", 0.0), 0.0

    def declare(self, k: "Declaration") -> None:
        k.add_potential(sum(k.p.stiffness * a**2 / 2 for a in k.hinge))


class HingeDamper(Attachment):
    """Linear viscous damper on the host's hinge: torque ``-c * rate`` (c in N m s/rad).

    Parameter ``<host>.damping``.
    """

    parameters = {"damping": Param("N m s/rad", 0.0, 0.0, description="linear hinge damping")}

    def __init__(self, host: str = "p1", *, damping: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(host, bounds=bounds, damping=damping)

    def hinge_terms(self, v):
        return 0.0, v.get("damping", 0.0)

    def declare(self, k: "Declaration") -> None:
        k.add_dissipation(sum(k.p.damping * r**2 / 2 for r in k.hinge_rates))


class SwingDamper(HingeDamper):
    """Linear viscous damper on a :class:`~analogs.SphericalPendulum`'s swing: torque
    ``-c * omega`` (c in N m s/rad) with ``omega`` the rod's angular velocity relative to
    the tank, whatever the direction of the swing.

    Rayleigh dissipation ``c (cos(beta)^2 alpha_dot^2 + beta_dot^2) / 2``: the rod's
    squared angular rate. :class:`HingeDamper` damps each angle's rate instead,
    ``c (alpha_dot^2 + beta_dot^2) / 2``; the two agree for a swing along tank x or y and
    to second order in the swing angle otherwise. Parameter ``<host>.damping``.
    """

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        if len(k.hinge) != 2:
            raise ValueError(f"{self.label}: a swing damper needs a spherical pendulum's two "
                             f"angles (alpha, beta), its host has {len(k.hinge)}")
        (_, beta), (alpha_dot, beta_dot) = k.hinge, k.hinge_rates
        k.add_dissipation(k.p.damping * (sp.cos(beta) ** 2 * alpha_dot**2 + beta_dot**2) / 2)


class QuadraticDamper(Attachment):
    """Quadratic (amplitude-dependent) damper: torque ``-c2 * rate * |rate|``.

    Parameter ``<host>.quadratic_damping`` (N m s^2/rad^2). Its equivalent linear damping
    grows with the swing amplitude, as turbulent and separated flow damping does.
    """

    parameters = {
        "quadratic_damping": Param("N m s^2/rad^2", 0.0, 0.0, description="quadratic hinge damping")
    }

    def __init__(self, host: str = "p1", *, quadratic_damping: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(host, bounds=bounds, quadratic_damping=quadratic_damping)

    def declare(self, k: "Declaration") -> None:
        import sympy as sp

        for a, r in zip(k.hinge, k.hinge_rates):
            k.add_force(a, -k.p.quadratic_damping * r * sp.Abs(r))


class DiaphragmSpring(Attachment):
    """An elastomeric diaphragm seen at the hinge: stiffness and damping together.

    Parameters ``<host>.diaphragm_stiffness`` (N m/rad) and ``<host>.diaphragm_damping``
    (N m s/rad). A diaphragm raises the slosh frequency and adds damping; amplitude
    dependence is not modelled yet.
    """

    parameters = {
        "diaphragm_stiffness": Param("N m/rad", None, 0.0, description="diaphragm restoring stiffness"),
        "diaphragm_damping": Param("N m s/rad", 0.0, 0.0, description="diaphragm damping"),
    }

    def __init__(self, host: str = "p1", *, diaphragm_stiffness: float | None = None,
                 diaphragm_damping: float | None = None,
                 bounds: dict[str, tuple[float, float]] | None = None) -> None:
        super().__init__(host, bounds=bounds, diaphragm_stiffness=diaphragm_stiffness,
                         diaphragm_damping=diaphragm_damping)

    def hinge_terms(self, v):
        return v.get("diaphragm_stiffness", 0.0), v.get("diaphragm_damping", 0.0)

    def declare(self, k: "Declaration") -> None:
        k.add_potential(sum(k.p.diaphragm_stiffness * a**2 / 2 for a in k.hinge))
        k.add_dissipation(sum(k.p.diaphragm_damping * r**2 / 2 for r in k.hinge_rates))
