"""Model composition and validation: every problem reported at once."""

import pytest

from analogs import (
    Component,
    FixedMass,
    HingeDamper,
    HingeSpring,
    LateralRig,
    ModelError,
    Param,
    Pendulum,
    QuadraticDamper,
)
from derive import ParameterError, derive, simulate


def test_models_compose_with_plus_without_changing_operands():
    base = LateralRig() + FixedMass("fixed")
    extended = base + Pendulum("p1") + HingeDamper("p1")
    assert base.names == ["fixed"]
    assert extended.names == ["fixed", "p1"]
    assert [p.name for p in extended.parameters] == [
        "rig.dry_mass", "rig.gravity", "fixed.mass", "fixed.height", "fixed.inertia",
        "fixed.axial_inertia", "p1.mass", "p1.length", "p1.hinge_height", "p1.damping"]
    assert extended.parameter("p1.length").unit == "m"


def test_validation_reports_every_problem_at_once():
    bad = Pendulum("p1") + HingeSpring("p9") + Pendulum("p1") + FixedMass("fixed") + HingeSpring("fixed")
    with pytest.raises(ModelError) as err:
        bad.validate()
    msg = str(err.value)
    assert "no rig" in msg
    assert "duplicate component name 'p1'" in msg
    assert "unknown attachment target 'p9'" in msg
    assert "FixedMass('fixed') has no hinge" in msg
    assert len(err.value.problems) >= 4


def test_unknown_constructor_parameter_and_bad_bounds_are_reported():
    with pytest.raises(TypeError, match="unexpected keyword argument 'lenght'"):
        Pendulum("p1", lenght=0.05)
    with pytest.raises(TypeError, match=r"Pendulum\('p1'\) has no parameter 'lenght'"):
        Pendulum("p1", bounds={"lenght": (0.01, 0.1)})
    with pytest.raises(ModelError, match="leave the physical range"):
        (LateralRig() + Pendulum("p1", bounds={"mass": (-1.0, 2.0)})).validate()
    with pytest.raises(ModelError, match="outside its bounds"):
        (LateralRig() + Pendulum("p1", length=-0.05)).validate()


def test_missing_unknown_and_out_of_bound_parameters_are_named():
    dm = derive(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1"))
    ok = {"rig.dry_mass": 1.0, "fixed.mass": 1.0, "p1.mass": 1.0, "p1.length": 0.05}
    dm.parameter_vector(ok)  # heights are not needed for the lateral force
    with pytest.raises(ParameterError, match=r"missing parameter `p1.length` \(m\)"):
        dm.parameter_vector({k: v for k, v in ok.items() if k != "p1.length"})
    with pytest.raises(ParameterError, match="unknown parameter `p1.lenght`"):
        dm.parameter_vector({**ok, "p1.lenght": 0.05})
    with pytest.raises(ParameterError, match=r"`p1.damping` = -1.0 N m s/rad is outside"):
        dm.parameter_vector({**ok, "p1.damping": -1.0})
    with pytest.raises(ParameterError, match="missing parameter `p1.hinge_height`"):
        dm.parameter_vector(ok, outputs=("torque_y",))


def test_a_user_declares_a_new_analog_in_a_few_lines():
    class SlidingMass(Component):
        """A mass on a lateral spring, at a height in the tank frame."""

        coordinates = ("s",)
        coordinate_units = {"s": "m"}
        parameters = {"mass": Param("kg", lower=0.0), "stiffness": Param("N/m", lower=0.0),
                      "height": Param("m", 0.0)}

        def declare(self, k):
            k.add_particle(k.p.mass, k.q.s * k.tank.x + k.p.height * k.tank.z)
            k.add_potential(k.p.stiffness * k.q.s**2 / 2)

    import numpy as np
    m, k = 0.2, 80.0
    sim = simulate(LateralRig() + SlidingMass("s1", mass=m, stiffness=k), {"rig.dry_mass": 0.0},
                   np.linspace(0, 1, 201), x0={"s1.s": 0.01})
    # RK4 at 5 ms steps on a 3.2 Hz oscillator: phase error ~ (w h)^4 / 120 per step
    assert np.allclose(sim.state("s1.s"), 0.01 * np.cos(np.sqrt(k / m) * sim.time), atol=2e-6)


def test_quadratic_damper_lowers_amplitude_more_at_large_swings():
    base = (LateralRig() + Pendulum("p1", mass=1.0, length=0.05)
            + QuadraticDamper("p1", quadratic_damping=0.01))
    import numpy as np
    t = np.linspace(0, 2, 401)
    small = simulate(base, {"rig.dry_mass": 0.0}, t, x0={"p1.theta": 0.02}).state("p1.theta")
    large = simulate(base, {"rig.dry_mass": 0.0}, t, x0={"p1.theta": 0.4}).state("p1.theta")
    assert np.max(np.abs(large[200:])) / 0.4 < np.max(np.abs(small[200:])) / 0.02
