"""The analog as Basilisk effectors, checked without Basilisk.

Reference: Basilisk's spherical pendulum as its documentation states it (a mass ``m`` on a
rod of ``pendulumRadius`` from the tank point ``d``, ``l = L (cos phi cos theta pHat_01 +
sin phi cos theta pHat_02 - sin theta pHat_03)``, the damping force ``-D l'`` on the mass),
written by hand in ``tests/reference_vehicle.py`` from the exported parameters and
integrated with SciPy; the vehicle
export of the same fit must give the same force and torque on the tank. The hub's mass
properties are checked against the parallel-axis theorem worked by hand.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from reference_vehicle import FIT, SETS, LateralDrive, basilisk_pendulum

from analogs import FixedMass, HingeSpring, QuadraticDamper, SphericalPendulum, SuspendedMass
from analogs.errors import InputError
from derive import RK4, derive, simulate
from derive.export_basilisk import basilisk_analog
from estimate.cli import main
from estimate.cli.export import export_model

FIT = FIT | SETS

#: RK4 at 1 ms against DOP853 at rtol 1e-10, relative to the peak (see
#: test_export_vehicle.py: 2e-9 to 8e-8 observed).
RK4_VS_REFERENCE = 1e-6


@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, 1.0), (0.6, 0.8)],
                         ids=["x", "y", "diagonal"])
def test_exported_pendulum_is_the_fitted_analog_in_basilisks_equations(direction):
    # the vehicle export's swing damper and Basilisk's damping matrix both act on the rod's
    # angular velocity: the same in every direction of swing
    model, used = export_model("fixed,p1", FIT)
    pend = basilisk_analog(model, FIT).pendulums[0]
    t = np.linspace(0.0, 10.0, 10001)
    force, torque = basilisk_pendulum(pend, t, direction)
    vehicle, vused = export_model("p1:nospring", FIT, interface="vehicle")
    dm = derive(vehicle)
    sim = simulate(dm, vused, t, LateralDrive(dm.inputs, direction), integrator=RK4())
    assert np.max(np.hypot(sim.state("p1.alpha"), sim.state("p1.beta"))) > 0.9
    ours = np.array([sim.output(f"force_{a}") for a in "xyz"])
    # the mount's force on the tank assembly is the force on the mass (no fixed mass here)
    assert np.max(np.abs(ours - force)) < RK4_VS_REFERENCE * np.max(np.abs(force))
    ours_t = np.array([sim.output(f"torque_{a}") for a in "xyz"])
    assert np.max(np.abs(ours_t - torque)) < RK4_VS_REFERENCE * np.max(np.abs(torque))


def test_mapping_of_a_placed_tank():
    # tank axis along body -x (thrust along -x), origin at (0.3, 0.1, -0.2) m
    model, _ = export_model("fixed,p1", FIT)
    a = basilisk_analog(model, FIT, tank_position=(0.3, 0.1, -0.2), tank_axis=(-2.0, 0.0, 0.0))
    (p,), (fixed,) = a.pendulums, a.rigid_masses
    axis = np.array([-1.0, 0, 0])
    np.testing.assert_allclose(p.d, np.array([0.3, 0.1, -0.2]) + 0.1 * axis, atol=1e-15)
    np.testing.assert_allclose(p.pHat_01, -axis, atol=1e-15)
    frame = np.array([p.pHat_01, p.pHat_02, p.pHat_03])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(frame.T) == pytest.approx(1.0)  # right-handed, as Basilisk's P0
    np.testing.assert_allclose(p.D, FIT["p1.damping"] / FIT["p1.length"] ** 2 * np.eye(3))
    assert (p.mass, p.radius) == (FIT["p1.mass"], FIT["p1.length"])
    np.testing.assert_allclose(fixed.r_B, np.array([0.3, 0.1, -0.2]) + 0.05 * axis, atol=1e-15)
    # axial inertia about the tank axis (body x), transverse about body y and z
    np.testing.assert_allclose(fixed.inertia_B, np.diag([0.006, 0.004, 0.004]), atol=1e-15)


def test_hub_with_liquid_is_the_parallel_axis_theorem_by_hand():
    model, _ = export_model("fixed,p1", FIT)
    a = basilisk_analog(model, FIT, tank_position=(0.0, 0.0, 0.5))
    m, r, I = a.hub_with_liquid(100.0, (0.0, 0.0, 0.0), np.diag([10.0, 11.0, 12.0]))
    # fixed liquid 1.5 kg at z = 0.55 m: centre at 1.5 * 0.55 / 101.5 on z; each body's
    # transverse inertia grows by mass * (distance along z to the new centre)^2
    zc = 1.5 * 0.55 / 101.5
    assert m == 101.5 and r == pytest.approx((0.0, 0.0, zc))
    shift = 100.0 * zc**2 + 1.5 * (0.55 - zc) ** 2
    np.testing.assert_allclose(I, np.diag([10.004 + shift, 11.004 + shift, 12.006]), rtol=1e-14)


def test_what_has_no_basilisk_effector_is_refused():
    base = FixedMass("fixed") + SphericalPendulum("p1")
    with pytest.raises(InputError, match=r"`p1` has a hinge stiffness of 0.02 N m/rad: Basilisk's "
                                         r"spherical pendulum has no hinge spring"):
        basilisk_analog(base + HingeSpring("p1"), {**FIT, "p1.stiffness": 0.02})
    with pytest.raises(InputError, match=r"QuadraticDamper on 'p1'.* only a linear damper"):
        basilisk_analog(base + QuadraticDamper("p1", quadratic_damping=0.1), FIT)
    with pytest.raises(InputError, match=r"moves along 2 axes"):
        basilisk_analog(FixedMass("fixed") + SuspendedMass("s1", axes="xy"), FIT)
    with pytest.raises(InputError, match=r"tank axis: expected three finite numbers, not all "
                                         r"zero"):
        basilisk_analog(base, FIT, tank_axis=(0, 0, 0))


def test_suspended_mass_becomes_a_linear_spring_mass_damper():
    s = SuspendedMass("s1", axes="z", mass=2.0, height=0.3, stiffness_z=50.0, damping_z=0.4)
    (lsmd,) = basilisk_analog(s + FixedMass("fixed"), FIT,
                              tank_position=(1.0, 0.0, 0.0)).spring_masses
    assert (lsmd.mass, lsmd.k, lsmd.c) == (2.0, 50.0, 0.4)
    assert lsmd.r_PB_B == (1.0, 0.0, 0.3) and lsmd.pHat_B == (0.0, 0.0, 1.0)


def test_cli_writes_the_basilisk_module(tmp_path, capsys):
    fit = Path(__file__).resolve().parents[2] / "examples" / "A1_params.json"
    out = tmp_path / "slosh_bsk.py"
    args = ["export", str(fit), "--basilisk", str(out), "--tank-position", "0,0,-0.5",
            *[a for k in ("p1.hinge_height", "fixed.height", "fixed.inertia", "fixed.axial_inertia")
              for a in ("--set", f"{k}={FIT[k]}")]]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "1 sphericalPendulum, 0 linearSpringMassDamper, 1 rigid mass" in text, text
    assert "p1: SphericalPendulum, 2 DOF" in text
    ns: dict = {}
    source = out.read_text()
    # the constants, without importing Basilisk
    exec(compile(source[source.index("HUB ="):source.index("\ndef _column")], str(out), "exec"), ns)
    (p,) = ns["PENDULUMS"]
    assert p["d"] == (0.0, 0.0, -0.4) and p["mass"] == 1.3
    assert ns["RIGID_MASSES"][0]["r_B"] == (0.0, 0.0, -0.45)
    assert main(args) == 2  # not replaced without --overwrite
    assert "pass --overwrite to replace" in capsys.readouterr().err
