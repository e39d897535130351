"""The model specification grammar (analogs/spec.py): models built on a rig, no case needed;
Model.spec() gives the specification back as given; every problem in one error."""

import pytest

from analogs import (
    FixedMass,
    HingeDamper,
    LateralRig,
    MotionRig,
    Pendulum,
    QuadraticDamper,
    SphericalPendulum,
    SpinningRig,
    model_from_spec,
    spec_of,
)
from analogs.errors import InputError
from analogs.spec import spec_problems


@pytest.mark.parametrize("spec", ["fixed,p1", "fixed,p1:quadratic", "p1:nospring,fixed",
                                  "fixed,p1:quadratic:nospring", "fixed,p1,p2:diaphragm"])
def test_spec_round_trips_as_given(spec):
    model = model_from_spec(spec, LateralRig())
    assert model.spec() == spec
    again = model_from_spec(model.spec(), LateralRig())
    assert again.structure_key() == model.structure_key()


def test_spec_read_from_components_when_not_built_from_one():
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1") \
        + QuadraticDamper("p1")
    assert model.spec() == spec_of(model) == "fixed,p1:nospring:quadratic"
    assert model_from_spec(model.spec(), LateralRig()).structure_key() == model.structure_key()


def test_a_model_changed_after_its_spec_reads_its_components():
    model = model_from_spec("fixed,p1:quadratic", LateralRig())
    assert model.without("fixed").spec() == "p1:quadratic"


def test_spherical_pendulums_off_the_spinning_rig():
    """``pN:spherical`` (or ``spherical=True``, a six-axis record that sees out of the x-z
    plane) makes a SphericalPendulum; read from the components it comes back as the
    modifier, except on the spinning rig, whose pendulums swirl anyway."""
    model = model_from_spec("fixed,p1:nospring:spherical", MotionRig(axes=("x", "y")))
    assert type(model.components[2]) is SphericalPendulum
    assert spec_of(model) == "fixed,p1:nospring:spherical"
    assert model_from_spec(spec_of(model), MotionRig(axes=("x", "y"))).structure_key() \
        == model.structure_key()
    asked = model_from_spec("fixed,p1", LateralRig(), spherical=True)
    assert type(asked.components[2]) is SphericalPendulum and asked.spec() == "fixed,p1"
    assert spec_of(asked) == "fixed,p1:spherical"
    assert spec_of(model_from_spec("fixed,p1", SpinningRig())) == "fixed,p1"
    with pytest.raises(InputError, match="`:spherical`"):
        model_from_spec("fixed,p1:swirl", LateralRig())


def test_a_component_without_a_token_has_no_spec():
    assert (LateralRig() + FixedMass("slab")).spec() is None


def test_rotors_on_the_spinning_rig():
    model = model_from_spec("fixed,p1,r1", SpinningRig())
    assert model.spec() == "fixed,p1,r1"
    assert "r1" in model.names


def test_every_problem_in_one_error_naming_the_option():
    with pytest.raises(InputError, match=r"^campaign.toml \[model\] 'fixed,q3,r1,p9': `q3`: "
                                         r"unknown component; `r1`: a rotor needs a rig that "
                                         r"rotates .*`p9`: pendulums are numbered by slosh "
                                         r"mode, from p1 to p6; valid tokens"):
        model_from_spec("fixed,q3,r1,p9", LateralRig(), option="campaign.toml [model]")
    assert spec_problems("fixed,p1", LateralRig()) == []
    assert len(spec_problems("p1:wobbly", LateralRig())) == 1
