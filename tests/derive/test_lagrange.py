"""Auto-derived equations against hand derivations (exact symbolic comparison)."""

import sympy as sp

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum, crank_displacement
from derive._lagrange import assemble


def _baseline():
    return LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")


def test_planar_pendulum_on_carriage_matches_hand_derivation():
    sym = assemble(_baseline())
    P = dict(zip(sym.parameters, sym.p))
    m, L, k, c, g = (P[n] for n in ("p1.mass", "p1.length", "p1.stiffness", "p1.damping", "rig.gravity"))
    m_dry, m_f = P["rig.dry_mass"], P["fixed.mass"]
    th, thd, thdd = sym.q[0], sym.qd[0], sym.qdd[0]
    xdd = sym.u[sym.inputs.index("rig.x_ddot")]

    derived = (sym.mass_matrix * sp.Matrix([thdd]) - sym.forcing)[0]
    hand = m * L**2 * thdd + m * L * xdd * sp.cos(th) + m * g * L * sp.sin(th) + k * th + c * thd
    assert sp.simplify(derived - hand) == 0

    force = sym.outputs[0]
    hand_force = (m_dry + m_f) * xdd + m * (xdd + L * thdd * sp.cos(th) - L * thd**2 * sp.sin(th))
    assert sp.simplify(force - hand_force) == 0


def test_pendulum_force_has_no_lateral_torque_components():
    sym = assemble(_baseline())
    # planar motion in x-z: no force along y, no torque about x or z
    assert sym.outputs[1] == 0
    assert sym.outputs[3] == 0 and sym.outputs[5] == 0


def test_vertical_force_carries_weight_and_pitch_torque_matches_hand_derivation():
    sym = assemble(_baseline())
    P = dict(zip(sym.parameters, sym.p))
    m, L, h, g = P["p1.mass"], P["p1.length"], P["p1.hinge_height"], P["rig.gravity"]
    m_dry, m_f, h_f = P["rig.dry_mass"], P["fixed.mass"], P["fixed.height"]
    th, thd, thdd = sym.q[0], sym.qd[0], sym.qdd[0]
    xdd = sym.u[sym.inputs.index("rig.x_ddot")]
    # bob relative to the tank origin O: (L sin th, h - L cos th); its acceleration in N
    bx, bz = L * sp.sin(th), h - L * sp.cos(th)
    ax = xdd + L * thdd * sp.cos(th) - L * thd**2 * sp.sin(th)
    az = L * thdd * sp.sin(th) + L * thd**2 * sp.cos(th)
    fz = (m_dry + m_f) * g + m * (az + g)
    assert sp.simplify(sym.outputs[2] - fz) == 0
    # torque about +y at O: (r x F)_y = z F_x - x F_z
    ty = h_f * m_f * xdd + bz * m * ax - bx * m * (az + g)
    assert sp.simplify(sym.outputs[4] - ty) == 0


def test_crank_rig_drives_a_rigid_tank_with_hand_derived_acceleration():
    sym = assemble(LateralRig(excitation="crank") + FixedMass("fixed"))
    P = dict(zip(sym.parameters, sym.p))
    t = sym.t
    names = ("crank_radius", "rod_length", "drive_frequency", "omega_correction", "flywheel_angle")
    r, l, f, dw, phi0 = (P[f"rig.{n}"] for n in names)
    phi = phi0 + (2 * sp.pi * f + dw) * t
    x = r * sp.cos(phi) + sp.sqrt(l**2 - r**2 * sp.sin(phi) ** 2) - l
    expected = (P["rig.dry_mass"] + P["fixed.mass"]) * sp.diff(x, t, 2)
    assert sp.simplify(sym.outputs[0] - expected) == 0
    assert sym.inputs == ()
    assert sp.simplify(crank_displacement(phi, r, l, sp) - x) == 0
