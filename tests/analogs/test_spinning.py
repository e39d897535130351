"""SpinningRig: auto-derived equations against hand derivations in the spinning frame
(centrifugal and Coriolis terms written out), and numeric checks against conserved
quantities and a relative equilibrium."""

import math

import numpy as np
import pytest
import sympy as sp
from symbolic_helpers import as_functions
from tolerances import SYMBOLIC

from analogs import FixedMass, Pendulum, Rotor, SphericalPendulum
from analogs.spinning import SpinningRig
from derive import Adaptive, simulate
from derive._lagrange import assemble

#: CVODES at rtol 1e-11: states are accurate to ~1e-9 over a few seconds; 1e-7 leaves a
#: margin of 100 and is still far below any modelling error the checks look for (a wrong
#: Coriolis term changes the rotor rate at the 1e-1 level).
CONSERVED_RELATIVE = 1e-7


def _params(sym):
    return dict(zip(sym.parameters, sym.p))


def _residual(sym):
    """``M qdd - f``: the left-hand sides of the derived equations."""
    return sym.mass_matrix * sp.Matrix(sym.qdd) - sym.forcing


def _no_nutation(sym, e):
    P = _params(sym)
    return e.subs({P["rig.nutation_angle"]: 0, P["rig.nutation_frequency"]: 0})


def test_planar_pendulum_on_spinning_table_matches_closed_form():
    sym = assemble(SpinningRig() + Pendulum("p1"))
    P = _params(sym)
    m, L, h = P["p1.mass"], P["p1.length"], P["p1.hinge_height"]
    W, r, g, md = P["rig.spin_rate"], P["rig.radius"], P["rig.gravity"], P["rig.dry_mass"]
    th, thd, thdd = sym.q[0], sym.qd[0], sym.qdd[0]
    s, c = sp.sin(th), sp.cos(th)

    # hand derivation, rotating frame: centrifugal W^2 (r + L sin th) outward along x,
    # the Coriolis force 2 m W x' is along y, out of the swing plane
    hand = m * L**2 * thdd - m * W**2 * (r + L * s) * L * c + m * g * L * s
    assert sp.simplify(_no_nutation(sym, _residual(sym)[0]) - hand) == SYMBOLIC

    xdd = L * (thdd * c - thd**2 * s)
    zdd = L * (thdd * s + thd**2 * c)
    f_bob = (m * (xdd - W**2 * (r + L * s)), m * 2 * W * L * c * thd, m * (zdd + g))
    force = (md * (-W**2 * r) + f_bob[0], f_bob[1], md * g + f_bob[2])
    rel = (L * s, 0, h - L * c)  # bob relative to O
    torque = (rel[1] * f_bob[2] - rel[2] * f_bob[1],
              rel[2] * f_bob[0] - rel[0] * f_bob[2],
              rel[0] * f_bob[1] - rel[1] * f_bob[0])
    for derived, expected in zip(sym.outputs[:6], (*force, *torque)):
        assert sp.simplify(_no_nutation(sym, derived) - expected) == SYMBOLIC


def _spinning_frame_residual(rho, q, W, g_vec, m, t):
    """d'Alembert in a frame spinning at W about z: sum over q of
    m (rho'' + 2 W x rho' + W x (W x rho) - g) . d rho / d q."""
    w = sp.Matrix([0, 0, W])
    v = rho.diff(t)
    a = v.diff(t) + 2 * w.cross(v) + w.cross(w.cross(rho)) - g_vec
    return [sp.expand(m * a.dot(rho.diff(qi))) for qi in q]


@pytest.mark.parametrize("gravity", [True, False])
def test_spherical_pendulum_inward_tank_matches_coriolis_centrifugal_hand_derivation(gravity):
    sym = assemble(SpinningRig(tank_axis="inward", gravity=gravity) + SphericalPendulum("p1"))
    P = _params(sym)
    m, L, h = P["p1.mass"], P["p1.length"], P["p1.hinge_height"]
    W, r = P["rig.spin_rate"], P["rig.radius"]
    g = P["rig.gravity"] if gravity else 0
    t = sym.t
    (a, b), rule = as_functions(sym, ("a", "b"))
    # bob in spin-frame coordinates (x radial, y tangential, z spin axis): the tank axis
    # points inward (T.z = -S.x), T.x = S.z, T.y = S.y
    tank = (L * sp.sin(a) * sp.cos(b), L * sp.sin(b), h - L * sp.cos(a) * sp.cos(b))
    rho = sp.Matrix([r - tank[2], tank[1], tank[0]])
    hand = _spinning_frame_residual(rho, (a, b), W, sp.Matrix([0, 0, -g]), m, t)
    derived = _no_nutation(sym, _residual(sym)).xreplace(rule)
    for d, e in zip(derived, hand):
        assert sp.simplify(sp.expand(d) - e) == SYMBOLIC


#: With nutation, ``sympy.simplify`` does not close the trigonometric identities in
#: reasonable time (minutes); the difference is instead evaluated with 60 significant digits
#: at random rational points of all its symbols (parameters, time, coordinates, rates).
#: Correct equations give round-off at the 1e-50 level; any wrong term is O(1) there.
HIGH_PRECISION_ZERO = 1e-40


def _vanishes_at_random_points(expr, points=3, seed=7):
    rng = np.random.default_rng(seed)
    expr = sp.sympify(expr)
    symbols = sorted(expr.free_symbols, key=str)
    for _ in range(points):
        values = {s: sp.Rational(int(rng.integers(5, 200)), 37) for s in symbols}
        if abs(sp.N(expr.xreplace(values), 60)) > HIGH_PRECISION_ZERO:
            return False
    return True


def _rot(axis, angle):
    c, s = sp.cos(angle), sp.sin(angle)
    return {"x": sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "z": sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def _table_rotation(sym):
    """Tank-to-inertial rotation matrix written out from the documented 3-1-3 sequence."""
    P = _params(sym)
    t = sym.t
    phi = 2 * sp.pi * P["rig.nutation_frequency"] * t
    return (_rot("z", phi) * _rot("x", P["rig.nutation_angle"])
            * _rot("z", P["rig.spin_rate"] * t - phi))


def test_nutating_rigid_tank_force_and_torque_match_rotation_matrices():
    sym = assemble(SpinningRig() + FixedMass("fixed"))
    P = _params(sym)
    t = sym.t
    R = _table_rotation(sym)
    r, hgt, g = P["rig.radius"], P["rig.height"], P["rig.gravity"]
    m, md, hf = P["fixed.mass"], P["rig.dry_mass"], P["fixed.height"]
    J, Ja = P["fixed.inertia"], P["fixed.axial_inertia"]
    origin = R * sp.Matrix([r, 0, 0]) + R[:, 2] * hgt
    centre = origin + R[:, 2] * hf
    g_vec = sp.Matrix([0, 0, -g])
    f_n = md * (origin.diff(t, 2) - g_vec) + m * (centre.diff(t, 2) - g_vec)
    force = R.T * f_n
    # angular velocity from the skew matrix R^T R', then Euler's equations in tank axes
    Wm = R.T * R.diff(t)
    w = sp.Matrix([Wm[2, 1], Wm[0, 2], Wm[1, 0]])
    I = sp.diag(J, J, Ja)
    hdot = I * w.diff(t) + w.cross(I * w)
    f_c = R.T * (m * (centre.diff(t, 2) - g_vec))
    torque = sp.Matrix([0, 0, hf]).cross(f_c) + hdot
    for derived, expected in zip(sym.outputs[:6], (*force, *torque)):
        assert _vanishes_at_random_points(derived - expected)
    assert not _vanishes_at_random_points(sym.outputs[1] - force[1] + 1e-3 * m)  # can fail


def test_spherical_pendulum_on_nutating_table_matches_inertial_dalembert():
    sym = assemble(SpinningRig() + SphericalPendulum("p1"))
    P = _params(sym)
    m, L, h = P["p1.mass"], P["p1.length"], P["p1.hinge_height"]
    t = sym.t
    (a, b), rule = as_functions(sym, ("a", "b"))
    R = _table_rotation(sym)
    bob_t = sp.Matrix([P["rig.radius"] + L * sp.sin(a) * sp.cos(b), L * sp.sin(b),
                       h - L * sp.cos(a) * sp.cos(b)])
    bob = R * bob_t + R[:, 2] * P["rig.height"]
    acc = bob.diff(t, 2) - sp.Matrix([0, 0, -P["rig.gravity"]])
    derived = _residual(sym).xreplace(rule)
    plain = {f.diff(t, 2): sp.Symbol(f"{f.func}dd") for f in (a, b)}
    plain |= {f.diff(t): sp.Symbol(f"{f.func}d") for f in (a, b)}
    for d, qi in zip(derived, (a, b)):
        hand = m * acc.dot(bob.diff(qi))
        diff = (d - hand).subs(plain).subs({a: sp.Symbol("a"), b: sp.Symbol("b")})
        assert _vanishes_at_random_points(diff)


# -- numeric checks ----------------------------------------------------------------------

_NUTATING = {"rig.spin_rate": 6.0, "rig.radius": 0.4, "rig.height": 0.3,
             "rig.nutation_angle": 0.08, "rig.nutation_frequency": 0.35, "rig.dry_mass": 2.0}


def test_undamped_transverse_rotor_keeps_its_absolute_spin_under_nutation():
    model = SpinningRig(gravity=False) + Rotor("r1", axis="x", inertia=0.02, damping=0.0)
    t = np.linspace(0.0, 4.0, 401)
    sim = simulate(model, _NUTATING, t, integrator=Adaptive(rtol=1e-11, atol=1e-13),
                   x0={"r1.psi_dot": 0.3})
    # tank angular velocity about T.x, from the 3-1-3 sequence: 2 pi f_n sin(theta_n) sin(psi)
    # with psi = (Omega_s - 2 pi f_n) t
    wn = 2 * math.pi * _NUTATING["rig.nutation_frequency"]
    psi = (_NUTATING["rig.spin_rate"] - wn) * t
    omega_x = wn * math.sin(_NUTATING["rig.nutation_angle"]) * np.sin(psi)
    absolute = omega_x + sim.state("r1.psi_dot")
    assert np.ptp(omega_x) > 0.1  # the check is not trivial: the tank rate does vary
    assert np.max(np.abs(absolute - absolute[0])) < CONSERVED_RELATIVE * abs(absolute[0])
    assert absolute[0] == pytest.approx(0.3, rel=1e-12)


def test_spherical_pendulum_rests_at_the_centrifugal_relative_equilibrium():
    W, r, L, g, h = 4.0, 0.3, 0.2, 9.80665, 0.25
    # conical-pendulum balance in the spinning frame: W^2 (r + L sin a) cos a = g sin a
    from scipy.optimize import brentq

    a_eq = brentq(lambda a: W**2 * (r + L * math.sin(a)) * math.cos(a) - g * math.sin(a),
                  1e-6, math.pi / 2 - 1e-6)
    model = SpinningRig() + SphericalPendulum("p1", mass=1.5, length=L, hinge_height=h)
    params = {"rig.spin_rate": W, "rig.radius": r, "rig.dry_mass": 0.0}
    t = np.linspace(0.0, 3.0, 61)
    sim = simulate(model, params, t, integrator=Adaptive(rtol=1e-11, atol=1e-13),
                   x0={"p1.alpha": a_eq})
    assert np.max(np.abs(sim.state("p1.alpha") - a_eq)) < 1e-8
    assert np.max(np.abs(sim.state("p1.beta"))) < 1e-8
    # the mount carries the bob's centripetal force and its weight, nothing tangential
    rho = r + L * math.sin(a_eq)
    assert sim.output("force_x") == pytest.approx(np.full(t.size, -1.5 * W**2 * rho), rel=1e-8)
    assert sim.output("force_z") == pytest.approx(np.full(t.size, 1.5 * g), rel=1e-8)
    assert np.max(np.abs(sim.output("force_y"))) < 1e-8
    # and a slightly displaced pendulum stays near it (the equilibrium is stable)
    sim = simulate(model, params, t, integrator=Adaptive(), x0={"p1.alpha": a_eq + 0.01})
    assert np.max(np.abs(sim.state("p1.alpha") - a_eq)) < 0.03


def test_undamped_pendulum_conserves_the_jacobi_integral_in_the_spinning_frame():
    W, r = 5.0, 0.35
    model = SpinningRig() + SphericalPendulum("p1", mass=1.2, length=0.15, hinge_height=0.2)
    t = np.linspace(0.0, 5.0, 501)
    sim = simulate(model, {"rig.spin_rate": W, "rig.radius": r, "rig.dry_mass": 0.0}, t,
                   integrator=Adaptive(rtol=1e-12, atol=1e-14),
                   x0={"p1.alpha": 0.3, "p1.beta": 0.2, "p1.beta_dot": 0.5})
    # the Jacobi integral: T - W . H_O  (inertial energy minus spin times the angular
    # momentum about the spin axis) + V; here computed by hand in spinning coordinates
    a, b = sim.state("p1.alpha"), sim.state("p1.beta")
    ad, bd = sim.state("p1.alpha_dot"), sim.state("p1.beta_dot")
    L, m, g = 0.15, 1.2, 9.80665
    x = r + L * np.sin(a) * np.cos(b)
    y = L * np.sin(b)
    z = 0.2 - L * np.cos(a) * np.cos(b)
    xd = L * (np.cos(a) * np.cos(b) * ad - np.sin(a) * np.sin(b) * bd)
    yd = L * np.cos(b) * bd
    zd = L * (np.sin(a) * np.cos(b) * ad + np.cos(a) * np.sin(b) * bd)
    jacobi = 0.5 * m * (xd**2 + yd**2 + zd**2) - 0.5 * m * W**2 * (x**2 + y**2) + m * g * z
    assert np.ptp(np.sin(b)) > 0.1  # the bob does swing out of the radial plane
    assert np.max(np.abs(jacobi - jacobi[0])) < CONSERVED_RELATIVE * np.max(np.abs(jacobi))


def test_spinning_rig_rejects_bad_options():
    with pytest.raises(ValueError, match="tank_axis must be one of"):
        SpinningRig(tank_axis="radial")
    with pytest.raises(TypeError, match="says whether gravity acts"):
        SpinningRig(gravity=9.81)
    with pytest.raises(TypeError, match="has no parameter 'spin'"):
        SpinningRig(spin=3.0)


def test_spinning_rig_parameters_and_channels():
    rig = SpinningRig(spin_rate=2.0)
    names = [p.name for p in rig.bound_parameters()]
    assert names == ["rig.dry_mass", "rig.spin_rate", "rig.radius", "rig.height",
                     "rig.nutation_angle", "rig.nutation_frequency", "rig.gravity"]
    assert "rig.gravity" not in [p.name for p in SpinningRig(gravity=False).bound_parameters()]
    assert rig.parameter("nutation_frequency").unit == "Hz"
    assert rig.measured == ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
    assert SpinningRig(tank_axis="inward").structure() != SpinningRig().structure()


def test_suspended_mass_rests_where_the_spring_balances_the_centrifugal_force():
    from analogs import SuspendedMass

    W, r, m, k = 3.0, 0.5, 2.0, 60.0
    # radial spring: k s = m W^2 (r + s)  ->  s = m W^2 r / (k - m W^2)
    s_eq = m * W**2 * r / (k - m * W**2)
    model = SpinningRig(gravity=False) + SuspendedMass("s1", axes="xy", mass=m, height=0.1,
                                                       stiffness_x=k, stiffness_y=k)
    t = np.linspace(0.0, 2.0, 41)
    sim = simulate(model, {"rig.spin_rate": W, "rig.radius": r, "rig.dry_mass": 0.0}, t,
                   integrator=Adaptive(rtol=1e-11, atol=1e-13), x0={"s1.s_x": s_eq})
    assert np.max(np.abs(sim.state("s1.s_x") - s_eq)) < 1e-9
    assert np.max(np.abs(sim.state("s1.s_y"))) < 1e-9
    assert sim.output("force_x") == pytest.approx(np.full(t.size, -m * W**2 * (r + s_eq)), rel=1e-9)
