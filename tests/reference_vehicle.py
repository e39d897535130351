"""References for the vehicle and Basilisk exports: a lateral drive of the tank frame and
two spherical pendulums written by hand from their equations (ours, in the exports' angles
and Basilisk's documented model), integrated with SciPy (DOP853, rtol 1e-10).

Nothing here comes from the project but the :class:`derive.Excitation` interface that
feeds the drive to ``derive.simulate``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from derive import Excitation

G = 9.80665
#: The A1 fit (examples/A1_params.json) with the heights and inertia the README sets.
FIT = {"fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.05529, "p1.stiffness": 0.0,
       "p1.damping": 0.0010585309742484883}
SETS = {"p1.hinge_height": 0.1, "fixed.height": 0.05, "fixed.inertia": 0.004,
        "fixed.axial_inertia": 0.006}
#: The README drive: 0.5 m/s^2 at the slosh frequency (2.12 Hz), swings of about 1 rad.
AMPLITUDE, FREQUENCY = 0.5, 2.12


def drive(t, direction):
    """Tank-frame acceleration (m/s^2) of a sine of AMPLITUDE at FREQUENCY along
    ``direction`` (a unit vector in the x-y plane)."""
    s = AMPLITUDE * np.sin(2 * np.pi * FREQUENCY * np.asarray(t, float))
    return np.multiply.outer(np.asarray(direction, float), s)


def spherical_pendulum(t, direction, *, m=FIT["p1.mass"], L=FIT["p1.length"],
                       c=FIT["p1.damping"], k=FIT["p1.stiffness"], rigid=FIT["fixed.mass"]):
    """Spherical pendulum (bob ``m`` on a rod ``L`` hinged on the tank axis) in a tank
    frame that translates with acceleration ``a(t)`` under gravity ``-G z``.

    Bob direction n(al, be) = (sin al cos be, sin be, -cos al cos be); apparent gravity
    g_app = g - a. Lagrangian L = m L^2 (cos^2 be al_dot^2 + be_dot^2) / 2 + m L g_app.n
    - k (al^2 + be^2) / 2 (the spring acts on each angle), dissipation
    c (cos^2 be al_dot^2 + be_dot^2) / 2 (the damper acts on the rod's angular velocity,
    whose square is that sum):

        m L^2 (cos^2 be al_dd - 2 sin be cos be al_d be_d) = m L g_app.n_al - c cos^2 be al_d
                                                             - k al
        m L^2 (be_dd + sin be cos be al_d^2)               = m L g_app.n_be - c be_d - k be

    Force the mount applies to the tank assembly: -(rigid + m) g_app + m L n_dd.
    Returns (angles (2, n), force (3, n)).
    """

    def n_derivatives(al, be):
        sa, ca, sb, cb = math.sin(al), math.cos(al), math.sin(be), math.cos(be)
        n_a = np.array([ca * cb, 0.0, sa * cb])
        n_b = np.array([-sa * sb, cb, ca * sb])
        n_aa = np.array([-sa * cb, 0.0, ca * cb])
        n_ab = np.array([-ca * sb, 0.0, -sa * sb])
        n_bb = np.array([-sa * cb, -sb, ca * cb])
        return n_a, n_b, n_aa, n_ab, n_bb

    def g_app(time):
        a = drive(time, direction).ravel()
        return np.array([-a[0], -a[1], -G])

    def accelerations(time, y):
        al, be, ad, bd = y
        n_a, n_b, *_ = n_derivatives(al, be)
        g = g_app(time)
        cb, sb = math.cos(be), math.sin(be)
        add = (m * L * g @ n_a - c * cb**2 * ad - k * al + 2 * m * L**2 * sb * cb * ad * bd) \
            / (m * L**2 * cb**2)
        bdd = (m * L * g @ n_b - c * bd - k * be - m * L**2 * sb * cb * ad**2) / (m * L**2)
        return add, bdd

    def rhs(time, y):
        return [y[2], y[3], *accelerations(time, y)]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0, 0.0, 0.0], t_eval=t, method="DOP853",
                    rtol=1e-10, atol=1e-12)
    force = np.empty((3, t.size))
    for i, (time, y) in enumerate(zip(t, sol.y.T)):
        al, be, ad, bd = y
        add, bdd = accelerations(time, y)
        n_a, n_b, n_aa, n_ab, n_bb = n_derivatives(al, be)
        n_dd = n_a * add + n_b * bdd + n_aa * ad**2 + 2 * n_ab * ad * bd + n_bb * bd**2
        force[:, i] = -(rigid + m) * g_app(time) + m * L * n_dd
    return sol.y[:2], force


def basilisk_pendulum(p, t, direction):
    """Basilisk's sphericalPendulum (parameters ``p`` of a BasiliskPendulum) on a body that
    translates with acceleration ``a(t)`` under gravity ``-G z`` (body = tank axes).

    With c1 = cos(phi), s1 = sin(phi), c2 = cos(theta), s2 = sin(theta):
    l = L (c1 c2 P1 + s1 c2 P2 - s2 P3), |l'|^2 = L^2 (theta'^2 + c2^2 phi'^2),
    Lagrange with the apparent gravity g_app = g - a and the generalized damping forces
    Q_q = (-D l') . dl/dq:

        m L^2 (c2^2 phi'' - 2 s2 c2 theta' phi') = m g_app . l_phi + Q_phi
        m L^2 (theta'' + s2 c2 phi'^2)          = m g_app . l_theta + Q_theta

    Returns the force (3, n) the body exerts on the mass, ``m (l'' - g_app)``, and its
    torque about the body origin, ``(d + l) x force``.
    """
    m, L = p.mass, p.radius
    P1, P2, P3 = (np.asarray(v) for v in (p.pHat_01, p.pHat_02, p.pHat_03))
    D, d = np.asarray(p.D), np.asarray(p.d)

    def geometry(ph, th):
        c1, s1, c2, s2 = math.cos(ph), math.sin(ph), math.cos(th), math.sin(th)
        l = L * (c1 * c2 * P1 + s1 * c2 * P2 - s2 * P3)
        l_ph = L * (-s1 * c2 * P1 + c1 * c2 * P2)
        l_th = L * (-c1 * s2 * P1 - s1 * s2 * P2 - c2 * P3)
        l_phph = L * (-c1 * c2 * P1 - s1 * c2 * P2)
        l_phth = L * (s1 * s2 * P1 - c1 * s2 * P2)
        l_thth = L * (-c1 * c2 * P1 - s1 * c2 * P2 + s2 * P3)
        return l, l_ph, l_th, l_phph, l_phth, l_thth

    def g_app(time):
        a = drive(time, direction).ravel()
        return np.array([-a[0], -a[1], -G])

    def accelerations(time, y):
        ph, th, phd, thd = y
        _, l_ph, l_th, *_ = geometry(ph, th)
        ldot = l_ph * phd + l_th * thd
        g = g_app(time)
        c2, s2 = math.cos(th), math.sin(th)
        phdd = (m * g @ l_ph - (D @ ldot) @ l_ph + 2 * m * L**2 * s2 * c2 * thd * phd) \
            / (m * L**2 * c2**2)
        thdd = (m * g @ l_th - (D @ ldot) @ l_th - m * L**2 * s2 * c2 * phd**2) / (m * L**2)
        return phdd, thdd

    sol = solve_ivp(lambda time, y: [y[2], y[3], *accelerations(time, y)], (t[0], t[-1]),
                    [0.0, 0.0, 0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12)
    force, torque = np.empty((3, t.size)), np.empty((3, t.size))
    for i, (time, y) in enumerate(zip(t, sol.y.T)):
        ph, th, phd, thd = y
        phdd, thdd = accelerations(time, y)
        l, l_ph, l_th, l_phph, l_phth, l_thth = geometry(ph, th)
        ldd = l_ph * phdd + l_th * thdd + l_phph * phd**2 + 2 * l_phth * phd * thd + l_thth * thd**2
        force[:, i] = m * (ldd - g_app(time))
        torque[:, i] = np.cross(d + l, force[:, i])
    return force, torque



class LateralDrive(Excitation):
    """The vehicle inputs (``names``) of a lateral drive along ``direction`` under gravity
    ``-G z``."""

    analytic = False

    def __init__(self, names, direction):
        self.names, self.direction, self.size = tuple(names), direction, len(names)

    def values(self, t):
        t = np.asarray(t, float)
        out = np.zeros((self.size, t.size))
        a = drive(t, self.direction)
        for i, axis in enumerate("xy"):
            out[self.names.index(f"vehicle.accel_{axis}")] = a[i]
        out[self.names.index("vehicle.gravity_z")] = -G
        return out
