"""Tank shapes, fills and their error messages."""

import math

import pytest

from analogs.tank import Capsule, Cylinder, Liquid, Profile, Sphere, predict


def cap_volume(radius: float, h: float) -> float:
    """Volume of a spherical cap of height h (hand formula)."""
    return math.pi * h * h * (3.0 * radius - h) / 3.0


@pytest.mark.parametrize("fill", [0.1, 0.5, 0.6, 0.93])
def test_sphere_cap_volume_and_centroid(fill):
    R = 0.37
    s = Sphere(R)
    h = fill * 2 * R
    assert s.volume(h) == pytest.approx(cap_volume(R, h), rel=1e-13)
    # centroid of a cap from the bottom: integral of z * pi (2 R z - z^2) dz / V
    zbar = math.pi * (2 * R * h**3 / 3 - h**4 / 4) / cap_volume(R, h)
    assert s.centroid_height(h) == pytest.approx(zbar, rel=1e-12)


def test_volume_fill_is_inverse_of_volume():
    s = Sphere(0.1016)
    h = s.depth_from_fill(volume_fill=0.648)
    assert s.volume(h) / s.volume() == pytest.approx(0.648, abs=1e-12)
    # seed: 60 % depth fill is 64.8 % of the volume (cap formula: 0.36 * (3 - 1.2) / 4 * 4)
    assert s.depth_from_fill(volume_fill=0.648) == pytest.approx(0.6 * 0.2032, rel=1e-9)


def test_capsule_and_profile_volumes():
    a, c = 0.2, 0.5
    cap = Capsule(a, c)
    assert cap.height == pytest.approx(2 * a + c)
    assert cap.volume() == pytest.approx(4 / 3 * math.pi * a**3 + math.pi * a**2 * c, rel=1e-12)
    cone = Profile(r=[0.0, 0.3], z=[0.0, 0.6])
    assert cone.volume() == pytest.approx(math.pi * 0.3**2 * 0.6 / 3, rel=1e-12)
    assert Cylinder(0.2, 1.0).volume(0.4) == pytest.approx(math.pi * 0.04 * 0.4, rel=1e-13)


@pytest.mark.parametrize("fill", [0.0, 1.0, -0.2, 60, float("nan")])
def test_fill_outside_unit_interval_is_rejected(fill):
    with pytest.raises(ValueError, match=r"`fill` must be a fraction in \(0, 1\).*got"):
        predict(Sphere(0.1), fill=fill)


def test_volume_fill_outside_is_rejected_and_both_fills_conflict():
    with pytest.raises(ValueError, match=r"`volume_fill` must be a fraction in \(0, 1\)"):
        predict(Sphere(0.1), volume_fill=1.5)
    with pytest.raises(ValueError, match="exactly one of `fill`"):
        predict(Sphere(0.1), fill=0.5, volume_fill=0.5)
    with pytest.raises(ValueError, match="exactly one of `fill`"):
        predict(Sphere(0.1))


@pytest.mark.parametrize("make", [lambda: Sphere(-0.1), lambda: Cylinder(0.0, 1.0),
                                  lambda: Capsule(-1.0, 0.2), lambda: Sphere("big")])
def test_negative_radius_is_rejected(make):
    with pytest.raises(ValueError, match="`radius` must be a positive number in m; got"):
        make()


def test_bad_profile_lists_every_problem():
    with pytest.raises(ValueError, match=r"`r` must be finite and >= 0.*`z` must start at 0"):
        Profile(r=[-0.1, 0.2], z=[0.1, 0.3])


def test_unknown_shape_method_and_liquid_are_rejected():
    with pytest.raises(ValueError, match="`tank` must be a Sphere, Cylinder, Capsule, Profile or Rect"):
        predict("cube", fill=0.5)
    with pytest.raises(ValueError, match="`method` must be one of"):
        predict(Sphere(0.1), fill=0.5, method="magic")
    with pytest.raises(ValueError, match="`density` must be a positive number in kg/m"):
        Liquid(density=-1.0)
    with pytest.raises(ValueError, match="`gravity` must be a positive"):
        predict(Sphere(0.1), fill=0.5, gravity=0.0)
