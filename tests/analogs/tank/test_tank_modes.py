"""Exact modes: closed forms, McIver's sphere value, and two independent solvers agreeing."""

import math

import numpy as np
import pytest
from tank_tolerances import CLOSED_FORM, LAMBDA_AGREEMENT, MASS_HEIGHT_AGREEMENT, MCIVER

from analogs.tank import Capsule, Cylinder, FiniteElements, Ritz, Sphere, predict

XI = np.array([1.841183781, 5.331442774, 8.536316366])  # zeros of J1'


def test_half_full_sphere_mciver():
    for radius in (0.1016, 1.0, 3.7):
        p = predict(Sphere(radius), fill=0.5, modes=1)
        assert p.modes[0].lam * radius == pytest.approx(1.5602, abs=MCIVER)


@pytest.mark.parametrize("solver", [Ritz(degree=40), FiniteElements()])
@pytest.mark.parametrize("hr", [0.3, 1.0, 1.7])
def test_cylinder_closed_form(solver, hr):
    R = 0.25
    p = predict(Cylinder(R, 2.0 * R), fill=hr / 2.0, method=solver, modes=3)
    lam = XI * np.tanh(XI * hr) / R
    mass = 2 * np.tanh(XI * hr) / (XI * (XI**2 - 1) * hr)
    h = hr * R
    bob = h - (2 * R / XI) * np.tanh(XI * h / (2 * R))  # SP-106 spring-mass location
    for n, m in enumerate(p.modes):
        assert m.lam == pytest.approx(lam[n], rel=CLOSED_FORM)
        assert m.mass / p.liquid_mass == pytest.approx(mass[n], abs=CLOSED_FORM)
        assert m.bob_height / R == pytest.approx(bob[n] / R, abs=CLOSED_FORM)


@pytest.mark.parametrize("fill", [0.1, 0.3, 0.5, 0.6, 0.7, 0.8, 0.9])
def test_sphere_ritz_and_fem_agree(fill):
    R = 0.1016
    ritz = predict(Sphere(R), fill=fill, method=Ritz(degree=120 if fill > 0.85 else 60))
    fem = predict(Sphere(R), fill=fill, method=FiniteElements())
    for a, b in zip(ritz.modes, fem.modes):
        assert a.lam == pytest.approx(b.lam, rel=LAMBDA_AGREEMENT)
        assert abs(a.mass - b.mass) / ritz.liquid_mass < MASS_HEIGHT_AGREEMENT
        assert abs(a.hinge_height - b.hinge_height) / R < MASS_HEIGHT_AGREEMENT
        assert abs(a.bob_height - b.bob_height) / R < MASS_HEIGHT_AGREEMENT
        assert a.amplitude_ratio == pytest.approx(b.amplitude_ratio, abs=MASS_HEIGHT_AGREEMENT)
    assert abs(ritz.fixed_mass.height - fem.fixed_mass.height) / R < MASS_HEIGHT_AGREEMENT


@pytest.mark.parametrize("fill", [0.2, 0.55, 0.85])
def test_capsule_ritz_and_fem_agree(fill):
    tank = Capsule(0.5, 0.4)
    ritz = predict(tank, fill=fill, method=Ritz(degree=80))
    fem = predict(tank, fill=fill, method=FiniteElements())
    for a, b in zip(ritz.modes, fem.modes):  # measured 1.4e-6 at 85 %
        assert a.lam == pytest.approx(b.lam, rel=LAMBDA_AGREEMENT)
        assert abs(a.mass - b.mass) / ritz.liquid_mass < MASS_HEIGHT_AGREEMENT


@pytest.mark.parametrize("fill", [0.15, 0.45, 0.75, 0.9])
def test_sphere_hinges_are_at_the_centre(fill):
    """Wall pressure on a sphere passes through its centre: every hinge is there."""
    R = 2.3
    p = predict(Sphere(R), fill=fill, modes=3)
    for m in p.modes:
        assert m.hinge_height / R == pytest.approx(1.0, abs=MASS_HEIGHT_AGREEMENT)


def test_scaling_with_radius_and_gravity():
    """lambda R and m / m_liquid depend on the fill only; frequency scales as sqrt(g / R)."""
    a = predict(Sphere(0.1), fill=0.37, gravity=9.81)
    b = predict(Sphere(4.0), fill=0.37, gravity=1.62)
    for ma, mb in zip(a.modes, b.modes):
        assert ma.lam * 0.1 == pytest.approx(mb.lam * 4.0, rel=1e-9)
        assert ma.mass / a.liquid_mass == pytest.approx(mb.mass / b.liquid_mass, rel=1e-8)
        ratio = math.sqrt(9.81 / 0.1) / math.sqrt(1.62 / 4.0)
        assert ma.frequency_hz / mb.frequency_hz == pytest.approx(ratio, rel=1e-9)


def test_mass_sum_rule_deep_cylinder():
    """All modal masses together are below the liquid mass and the first dominates."""
    p = predict(Cylinder(1.0, 10.0), fill=0.3, modes=3)
    total = sum(m.mass for m in p.modes)
    assert 0 < total < p.liquid_mass
    assert p.fixed_mass.mass == pytest.approx(p.liquid_mass - total, rel=1e-12)
