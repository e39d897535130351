"""Mounted: a component in its own tank frame, placed off the rig's tank origin."""

import math

import numpy as np
import pytest
import sympy as sp

from analogs import HingeDamper, HingeSpring, Rotor, SphericalPendulum
from analogs.mounted import Mounted
from analogs.spacecraft import FreeSpacecraft
from analogs.spinning import SpinningRig
from derive._lagrange import assemble

#: Acceptance of issue 7 for the NTC (simulation vs linearisation).
NTC_AGREEMENT = 0.02


def _equations(model, values):
    """M and f with parameters as plain symbols by name, ``values`` substituted."""
    sym = assemble(model)
    plain = {p: sp.Symbol(n, real=True) for n, p in zip(sym.parameters, sym.p)}
    fixed = {plain[sym.p[sym.parameters.index(n)]]: v for n, v in values.items()}
    return tuple(e.xreplace(plain).subs(fixed) for e in (sym.mass_matrix, sym.forcing))


_NO_NUTATION = {"rig.nutation_angle": 0, "rig.nutation_frequency": 0}


@pytest.mark.parametrize("axis, tank_axis", [("inward", "inward"), ("parallel", "spin")])
def test_mount_on_a_spinning_table_equals_the_rig_offset(axis, tank_axis):
    # the same pendulum placed by the rig (tank origin at radius r) or by the mount
    r = sp.Symbol("r", real=True)
    M1, f1 = _equations(SpinningRig(tank_axis=tank_axis) + SphericalPendulum("p1")
                        + HingeSpring("p1"), {**_NO_NUTATION, "rig.radius": r})
    M2, f2 = _equations(SpinningRig() + Mounted(SphericalPendulum("p1"), axis=axis)
                        + HingeSpring("p1"),
                        {**_NO_NUTATION, "rig.radius": 0, "p1.mount_radius": r,
                         "p1.mount_azimuth": 0, "p1.mount_height": 0})
    assert sp.simplify(M1 - M2) == sp.zeros(2, 2)
    assert sp.simplify(f1 - f2) == sp.zeros(2, 1)


def test_mount_azimuth_turns_a_rotor_axis():
    # a rotor about the mount's x axis at azimuth 90 deg spins about the rig's y axis
    M1, f1 = _equations(SpinningRig() + Rotor("r1", axis="y"), {})
    M2, f2 = _equations(SpinningRig() + Mounted(Rotor("r1", axis="x")),
                        {"r1.mount_azimuth": sp.pi / 2})
    assert sp.simplify(M1 - M2) == sp.zeros(1, 1)
    assert sp.simplify(f1 - f2) == sp.zeros(1, 1)
    # and at azimuth 0 it does not (the check can fail)
    _, f0 = _equations(SpinningRig() + Mounted(Rotor("r1", axis="x")), {"r1.mount_azimuth": 0})
    assert sp.simplify(f1 - f0) != sp.zeros(1, 1)


def test_mount_keeps_name_hinges_and_adds_parameters():
    m = Mounted(SphericalPendulum("p1", mass=2.0), axis="inward", mount_radius=0.5)
    assert m.name == "p1" and m.coordinates == ("alpha", "beta")
    names = [p.name for p in m.bound_parameters()]
    assert names[-3:] == ["p1.mount_radius", "p1.mount_azimuth", "p1.mount_height"]
    assert m.parameter("mass").default == 2.0 and m.parameter("mount_radius").default == 0.5
    model = SpinningRig() + m + HingeDamper("p1")
    assert model.validate() is model
    assert Mounted(SphericalPendulum("p1")).structure() != m.structure()


def test_mount_rejects_what_it_cannot_wrap():
    with pytest.raises(TypeError, match="Mounted wraps an analog component"):
        Mounted(SpinningRig())
    with pytest.raises(TypeError, match="Mounted wraps an analog component"):
        Mounted(HingeDamper("p1"))
    with pytest.raises(ValueError, match="axis must be one of"):
        Mounted(SphericalPendulum("p1"), axis="outward")


@pytest.mark.slow
def test_two_opposite_tanks_on_a_spacecraft_ntc_and_major_axis_rule():
    from estimate.analysis.ntc import nutation_time_constant

    def tank(name, azimuth):
        return (Mounted(SphericalPendulum(name, mass=20.0, length=0.25, hinge_height=0.1),
                        axis="inward", mount_radius=0.8, mount_height=0.3,
                        mount_azimuth=azimuth) + HingeDamper(name, damping=2.0))

    model = FreeSpacecraft() + tank("p1", 0.0) + tank("p2", math.pi)
    bus = {"bus.spin_rate": 5.0, "bus.mass": 500.0, "bus.inertia_x": 400.0,
           "bus.inertia_y": 420.0}
    for iz, grows in ((600.0, False), (300.0, True)):
        ntc = nutation_time_constant(model, {**bus, "bus.inertia_z": iz})
        assert ntc.grows is grows
        assert ntc.relative_difference < NTC_AGREEMENT
        # symmetric tanks: the centre of mass stays on the spin axis at steady spin
        assert np.hypot(ntc.equilibrium["bus.x"], ntc.equilibrium["bus.y"]) < 1e-9
