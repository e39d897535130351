"""Vehicle-coupled interface: same physics as the rigs, different inputs.

References: the LateralRig model (prescribed translation through the rig's position
input), a rig written in the test that moves the tank frame through SymPy orientations
and an origin path (the path `LateralRig` uses, independent of the vehicle's apparent
gravity and prescribed angular velocity), and the closed-form rigid-body force and torque.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum, Rig, Rotor, SphericalPendulum
from analogs.vehicle import VehicleFrame
from derive import RK4, Excitation, Sine, derive, simulate

#: Both sides run the same RK4 on the same grid with inputs at the same stage times; the
#: equations differ only in how SymPy arranged them (rounding, ~1e-13).
SAME_PHYSICS = 1e-9

G = 9.80665


class Signals(Excitation):
    """Inputs computed by a NumPy function of time (rows = inputs)."""

    analytic = False

    def __init__(self, fn, size: int) -> None:
        self.fn = fn
        self.size = size

    def values(self, t):
        t = np.asarray(t, float)
        return np.vstack([np.broadcast_to(np.asarray(r, float), t.shape) for r in self.fn(t)])


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("planar", [True, False])
def test_translating_vehicle_force_equals_lateral_rig_force(planar):
    comps = FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
    values = {"fixed.mass": 1.456, "fixed.height": 0.05, "fixed.inertia": 0.003, "fixed.axial_inertia": 0.004,
              "p1.mass": 1.338, "p1.length": 0.057, "p1.hinge_height": 0.1,
              "p1.stiffness": 0.02, "p1.damping": 1e-4}
    t = np.linspace(0, 5, 501)
    sine = Sine(0.005, 1.855)
    rig = simulate(LateralRig() + comps, {**values, "rig.dry_mass": 1.2, "rig.gravity": G},
                   t, sine, integrator=RK4(), x0={"p1.theta": 0.02})
    vehicle = derive(VehicleFrame(planar=planar) + comps)
    by_name = {"vehicle.accel_x": lambda s: sine.values(s)[2], "vehicle.gravity_z": lambda s: -G}
    exc = Signals(lambda s: [by_name.get(n, lambda s: 0.0)(s) for n in vehicle.inputs],
                  vehicle.nu)
    veh = simulate(vehicle, {**values, "vehicle.dry_mass": 1.2}, t, exc, integrator=RK4(),
                   x0={"p1.theta": 0.02})
    for name in ("force_x", "force_z", "torque_y"):
        assert np.ptp(rig.output(name)) > 1e-3
        assert _rel(veh.output(name), rig.output(name)) < SAME_PHYSICS, name
    assert _rel(veh.state("p1.theta"), rig.state("p1.theta")) < SAME_PHYSICS


def test_rigid_mass_force_and_torque_closed_form():
    # Fixed mass (a rigid body at height h) under arbitrary tank-frame inputs:
    # F = m (a + alpha x r + w x (w x r) - g), tau_O = r x F + I alpha + w x (I w).
    dm = derive(VehicleFrame() + FixedMass("fixed"))
    m, h, I, J = 2.0, 0.3, 0.05, 0.08
    p = dm.parameter_vector({"fixed.mass": m, "fixed.height": h, "fixed.inertia": I,
                             "fixed.axial_inertia": J})
    rng = np.random.default_rng(3)
    for _ in range(5):
        a, w, al, g = (rng.normal(size=3) for _ in range(4))
        y = np.asarray(dm.outputs([], np.concatenate([a, w, al, g]), p, 0.0)).ravel()
        r = np.array([0, 0, h])
        F = m * (a + np.cross(al, r) + np.cross(w, np.cross(w, r)) - g)
        Ic = np.diag([I, I, J])
        tau = np.cross(r, F) + Ic @ al + np.cross(w, Ic @ w)
        np.testing.assert_allclose(y[:3], F, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(y[3:6], tau, rtol=1e-12, atol=1e-12)


class _TumblingRig(Rig):
    """Tank frame oriented by yaw psi(t) then tilt theta(t), origin on a curved path,
    gravity -G along the inertial z: the rig path of ``LateralRig``, with rotation."""

    measured = ("force_x",)
    parameters = {}

    def declare_frame(self, f):
        from sympy.physics.mechanics import ReferenceFrame

        N, T, t = f.inertial, f.tank, f.t
        psi, th = _angles(t, sp)
        A = ReferenceFrame("A")
        A.orient_axis(N, N.z, psi)
        T.orient_axis(A, A.x, th)
        f.origin_position = sum(c * v for c, v in zip(_origin(t, sp), (N.x, N.y, N.z)))
        f.gravity = -G * N.z


def _angles(t, lib):
    return 0.3 * lib.sin(1.1 * t) + 0.5 * t, 0.2 * lib.sin(0.7 * t)


def _origin(t, lib):
    return 0.1 * lib.sin(2 * t), 0.05 * lib.cos(1.3 * t), 0.02 * t**2


def _vehicle_inputs():
    """accel, omega, alpha, gravity in tank components as NumPy functions of time, from
    SymPy kinematics of the tumbling rig."""
    from sympy.physics.mechanics import ReferenceFrame

    t = sp.Symbol("t")
    N, A, T = ReferenceFrame("N"), ReferenceFrame("A"), ReferenceFrame("T")
    psi, th = _angles(t, sp)
    A.orient_axis(N, N.z, psi)
    T.orient_axis(A, A.x, th)
    r = sum(c * v for c, v in zip(_origin(t, sp), (N.x, N.y, N.z)))
    w = T.ang_vel_in(N)
    exprs = [*r.diff(t, N).diff(t, N).to_matrix(T), *w.to_matrix(T),
             *w.diff(t, T).to_matrix(T), *(-G * N.z).to_matrix(T)]
    return sp.lambdify(t, [sp.simplify(e) for e in exprs], "numpy")


def test_tumbling_vehicle_matches_rig_with_orientation():
    comps = FixedMass("fixed") + SphericalPendulum("p1") + HingeDamper("p1") + Rotor("r")
    values = {"fixed.mass": 1.4, "fixed.height": 0.05, "fixed.inertia": 0.004,
              "fixed.axial_inertia": 0.006, "p1.mass": 1.3, "p1.length": 0.06,
              "p1.hinge_height": 0.1, "p1.damping": 2e-4, "r.inertia": 0.002, "r.damping": 0.01}
    t = np.linspace(0, 3, 601)
    x0 = {"p1.alpha": 0.1, "p1.beta": -0.05, "r.psi_dot": 0.5}
    ref = simulate(_TumblingRig("rig") + comps, values, t, None, integrator=RK4(), x0=x0)
    fn = _vehicle_inputs()
    veh = simulate(VehicleFrame() + comps, values, t, Signals(fn, 12), integrator=RK4(), x0=x0)
    for name in ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z"):
        assert np.ptp(ref.output(name)) > 1e-3
        assert _rel(veh.output(name), ref.output(name)) < SAME_PHYSICS, name
    for s in ref.state_names:
        assert _rel(veh.state(s), ref.state(s)) < SAME_PHYSICS, s


def test_alpha_is_derivative_of_omega_and_missing_derivative_is_reported():
    from analogs.model import Model
    from derive._lagrange import assemble

    class _NoRate(Rig):
        measured = ("force_x",)
        parameters = {}

        def declare_frame(self, f):
            from sympy.physics.mechanics import Vector

            w = f.add_input("omega", "rad/s", derivatives=0)
            f.tank.set_ang_vel(f.inertial, w * f.tank.z)
            f.gravity = Vector(0)

    with pytest.raises(ValueError, match=r"need Derivative\(rig.omega, t\), which no input supplies"):
        assemble(Model((_NoRate("rig"),)) + FixedMass("fixed"))
    with pytest.raises(ValueError, match="derivatives must be 0, 1 or 2"):
        class _Bad(_NoRate):
            def declare_frame(self, f):
                f.add_input("x", "m", derivatives=3)

        assemble(Model((_Bad("rig"),)) + FixedMass("fixed"))
