"""Green et al.'s SSTR analogs (rotary oscillator, 3-DOF pendulum): auto-derived equations
against Lagrangians written out by hand (exact symbolic comparison)."""

import math

import pytest
import sympy as sp
from symbolic_helpers import as_functions
from tolerances import SYMBOLIC

from analogs import LateralRig, RotaryOscillator, ThreeDofPendulum
from analogs.spinning import SpinningRig
from derive._lagrange import assemble


def _params(sym):
    return dict(zip(sym.parameters, sym.p))


def _lagrange(L, rayleigh, q, t):
    """Lagrange's equations ``d/dt dL/dq' - dL/dq + dR/dq' = 0`` (left-hand sides)."""
    return [sp.diff(L, qi.diff(t)).diff(t) - sp.diff(L, qi) + sp.diff(rayleigh, qi.diff(t))
            for qi in q]


def _residual(sym, rule):
    return list((sym.mass_matrix * sp.Matrix(sym.qdd) - sym.forcing).xreplace(rule))


def test_rotary_oscillator_on_spinning_table_matches_hand_lagrangian():
    sym = assemble(SpinningRig(gravity=False) + RotaryOscillator("o1"))
    P = _params(sym)
    J, k, c, W = (P[n] for n in ("o1.inertia", "o1.stiffness", "o1.damping", "rig.spin_rate"))
    t = sym.t
    (a1, a2), rule = as_functions(sym, ("a1", "a2"))
    # body B = Rx(a1) Ry(a2) in the tank; tank spin W about z, in body components:
    # R^T e_z = (-sin a2 cos a1, sin a1, cos a1 cos a2); relative (a1' cos a2, a2', a1' sin a2)
    wx = -W * sp.sin(a2) * sp.cos(a1) + a1.diff(t) * sp.cos(a2)
    wy = W * sp.sin(a1) + a2.diff(t)
    L = J * (wx**2 + wy**2) / 2 - k * (a1**2 + a2**2) / 2
    R = c * (a1.diff(t) ** 2 + a2.diff(t) ** 2) / 2
    hand = _lagrange(L, R, (a1, a2), t)
    nut = {P["rig.nutation_angle"]: 0, P["rig.nutation_frequency"]: 0}
    for d, h in zip(_residual(sym, rule), hand):
        assert sp.simplify(d.subs(nut) - h) == SYMBOLIC
    # a torque-only analog: no force besides the dry mass's centripetal force
    md, r = P["rig.dry_mass"], P["rig.radius"]
    assert sp.simplify(sym.outputs[0].subs(nut) + md * W**2 * r) == SYMBOLIC
    assert sp.simplify(sym.outputs[2].subs(nut)) == 0 and sp.simplify(sym.outputs[1].subs(nut)) == 0
    # torque about O = rate of the body's angular momentum, in tank components:
    # d/dt (R (I w)) with R = Rx(a1) Ry(a2) and the tank turning at W about z
    Rm = sp.rot_axis1(-a1) * sp.rot_axis2(-a2)  # sympy's rot_axis matrices rotate frames
    h_tank = Rm * sp.Matrix([J * wx, J * wy, 0])
    omega = sp.Matrix([0, 0, W])
    torque = h_tank.diff(t) + omega.cross(h_tank)
    for d, e in zip(sym.outputs[3:6], torque):
        assert sp.simplify(d.subs(nut).xreplace(rule) - e) == SYMBOLIC


def test_three_dof_pendulum_on_carriage_matches_hand_lagrangian():
    sym = assemble(LateralRig() + ThreeDofPendulum("p1"))
    P = _params(sym)
    m, L_, h = (P[f"p1.{n}"] for n in ("mass", "length", "hinge_height"))
    I, Ia, kg, cg = (P[f"p1.{n}"] for n in ("inertia", "axial_inertia", "twist_stiffness",
                                             "twist_damping"))
    g, md = P["rig.gravity"], P["rig.dry_mass"]
    t = sym.t
    (a, b, gam), rule = as_functions(sym, ("a", "b", "g"))
    x = sp.Function("x")(t)
    rule_u = {sym.u[0]: x, sym.u[1]: x.diff(t), sym.u[2]: x.diff(t, 2)}
    # bob centre: carriage x, hinge height h, L along (sin a cos b, sin b, -cos a cos b)
    r = sp.Matrix([x + L_ * sp.sin(a) * sp.cos(b), L_ * sp.sin(b),
                   h - L_ * sp.cos(a) * sp.cos(b)])
    v = r.diff(t)
    # rod frame = Ry(-a) Rx(b): its angular velocity in rod components is
    # (b', -a' cos b, a' sin b); the bob adds the twist g' about the rod
    w_rod = (b.diff(t), -a.diff(t) * sp.cos(b), a.diff(t) * sp.sin(b))
    T = m * v.dot(v) / 2 + I * (w_rod[0] ** 2 + w_rod[1] ** 2) / 2 \
        + Ia * (w_rod[2] + gam.diff(t)) ** 2 / 2
    V = m * g * r[2] + kg * gam**2 / 2
    R = cg * gam.diff(t) ** 2 / 2
    hand = _lagrange(T - V, R, (a, b, gam), t)
    derived = [d.xreplace(rule_u) for d in _residual(sym, rule)]
    for d, e in zip(derived, hand):
        assert sp.simplify(sp.expand(d - e)) == SYMBOLIC
    # the transducer force: total mass times (acceleration - gravity), bob at its centre
    fx = md * x.diff(t, 2) + m * r[0].diff(t, 2)
    fz = md * g + m * (r[2].diff(t, 2) + g)
    assert sp.simplify(sym.outputs[0].xreplace(rule).xreplace(rule_u) - fx) == SYMBOLIC
    assert sp.simplify(sym.outputs[2].xreplace(rule).xreplace(rule_u) - fz) == SYMBOLIC


def test_three_dof_pendulum_swing_frequency_includes_the_bob_inertia():
    p = ThreeDofPendulum("p1")
    v = {"mass": 1.3, "length": 0.055, "inertia": 1e-3}
    out = p.derived_values(v, gravity=9.80665, hinge_stiffness=0.01, hinge_damping=2e-4)
    stiff, inert = 1.3 * 9.80665 * 0.055 + 0.01, 1.3 * 0.055**2 + 1e-3
    assert out["frequency_hz"] == pytest.approx(math.sqrt(stiff / inert) / (2 * math.pi), rel=1e-14)
    assert out["damping_ratio"] == pytest.approx(2e-4 / (2 * math.sqrt(stiff * inert)), rel=1e-14)
    assert p.derived_values(v, gravity=None, hinge_stiffness=0, hinge_damping=0) == {}


def test_rotary_oscillator_derived_frequency_and_bad_axes():
    o = RotaryOscillator("o1")
    out = o.derived_values({"inertia": 2e-3, "stiffness": 0.5, "damping": 1e-3}, gravity=None,
                           hinge_stiffness=0, hinge_damping=0)
    assert out["frequency_hz"] == pytest.approx(math.sqrt(250) / (2 * math.pi), rel=1e-14)
    assert out["damping_ratio"] == pytest.approx(1e-3 / (2 * math.sqrt(1e-3)), rel=1e-14)
    with pytest.raises(ValueError, match="two distinct letters of 'xyz'"):
        RotaryOscillator("o1", axes="xx")
    assert RotaryOscillator("o1", axes="zy").structure() != o.structure()
