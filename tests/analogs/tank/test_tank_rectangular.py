"""The upright rectangular tank: volumes and the closed-form slosh modes, checked against the
textbook formulas (NASA SP-106 ch. 6; Ibrahim 2005 ch. 1) and against quadrature of the
mode's own integrals."""

import math

import pytest
from scipy import integrate

from analogs.tank import Rectangular, Sphere, predict
from analogs.tank.geometry import Liquid

G = 9.81
#: Closed forms evaluated two ways agree to round-off; quadrature (scipy ``quad``) to its
#: default tolerance (1.5e-8 relative).
ROUND_OFF = 1e-12
QUADRATURE = 1e-7


def textbook_first_mode(a: float, b: float, h: float, rho: float, g: float = G) -> dict:
    """SP-106 / Ibrahim: ``omega^2 = (pi g / a) tanh(pi h / a)``, slosh mass
    ``m1 = m_liquid 8 tanh(pi h / a) / (pi^3 h / a)``, length ``g / omega^2``."""
    m_liquid = rho * a * b * h
    om2 = math.pi * g / a * math.tanh(math.pi * h / a)
    return {"liquid": m_liquid, "mass": m_liquid * 8 * math.tanh(math.pi * h / a)
            / (math.pi**3 * h / a), "length": g / om2,
            "frequency": math.sqrt(om2) / (2 * math.pi)}


@pytest.mark.parametrize("a, b, H, fill", [(0.4, 0.2, 0.3, 0.5), (1.2, 0.8, 1.5, 0.3),
                                           (0.2, 0.5, 0.6, 0.9)])
def test_first_mode_matches_the_textbook(a, b, H, fill):
    liquid = Liquid(density=998.2)
    p = predict(Rectangular(a, b, H), fill=fill, liquid=liquid, gravity=G, modes=1)
    ref = textbook_first_mode(a, b, fill * H, liquid.density)
    m = p.modes[0]
    assert p.liquid_mass == pytest.approx(ref["liquid"], rel=ROUND_OFF)
    assert m.frequency_hz == pytest.approx(ref["frequency"], rel=ROUND_OFF)
    assert m.mass == pytest.approx(ref["mass"], rel=ROUND_OFF)
    assert m.length == pytest.approx(ref["length"], rel=ROUND_OFF)
    assert p.fixed_mass.mass == pytest.approx(ref["liquid"] - ref["mass"], rel=ROUND_OFF)
    assert p.solver == "closed form"


@pytest.mark.parametrize("n", [1, 2, 3])
def test_mode_integrals_by_quadrature(n):
    """Mass, bob height and wave/bob ratio from the potential ``sin(k x) cosh(k z)`` by
    quadrature: ``m = rho b lambda (int x eta)^2 / int eta^2``, bob height ``int (z phi_x
    - x phi_z) dA / (lambda int x eta)`` (the axisymmetric solvers' definitions)."""
    a, b, h = 0.5, 0.3, 0.2
    k = (2 * n - 1) * math.pi / a
    lam = k * math.tanh(k * h)

    def phi_x(z, x):
        return k * math.cos(k * x) * math.cosh(k * z) / math.cosh(k * h)

    def phi_z(z, x):
        return k * math.sin(k * x) * math.sinh(k * z) / math.cosh(k * h)

    A = integrate.quad(lambda x: x * math.sin(k * x), -a / 2, a / 2)[0]
    B = integrate.quad(lambda x: math.sin(k * x) ** 2, -a / 2, a / 2)[0]
    moment = integrate.dblquad(lambda z, x: z * phi_x(z, x) - x * phi_z(z, x),
                               -a / 2, a / 2, 0.0, h, epsabs=0, epsrel=1e-10)[0]
    mode = Rectangular(a, b, 1.0).modes(h, n)[n - 1]
    assert mode.lam == pytest.approx(lam, rel=ROUND_OFF)
    assert mode.volume == pytest.approx(b * lam * A**2 / B, rel=QUADRATURE)
    assert mode.bob_height == pytest.approx(moment / (lam * A), rel=QUADRATURE)
    assert mode.amplitude_ratio == pytest.approx(
        lam * abs(math.sin(k * a / 2) * A) / B, rel=QUADRATURE)


def test_shallow_liquid_sloshes_whole():
    """In shallow liquid every particle sloshes: the modes' masses add up to the liquid's
    (``sum 8 / ((2n - 1)^2 pi^2) = 1``; six modes hold all but 1.7 % of it)."""
    p = predict(Rectangular(1.0, 0.5, 1.0), fill=1e-4, gravity=G, modes=6)
    share = sum(m.mass for m in p.modes) / p.liquid_mass
    expected = sum(8 / ((2 * n - 1) ** 2 * math.pi**2) for n in range(1, 7))
    assert share == pytest.approx(expected, rel=1e-6)  # tanh(x) = x (1 - x^2/3): x ~ 3e-4


def test_deep_liquid_mass_does_not_grow_with_depth():
    """Deep liquid: only the top sloshes, ``m1 -> 8 rho b a^2 / pi^3``."""
    rho = 1000.0
    deep = [predict(Rectangular(0.3, 0.2, 3.0), fill=f, gravity=G, modes=1,
                    liquid=Liquid(density=rho)).modes[0].mass for f in (0.5, 0.9)]
    assert deep == pytest.approx([8 * rho * 0.2 * 0.3**2 / math.pi**3] * 2, rel=1e-9)


def test_liquid_mass_volume_and_inertia():
    tank = Rectangular(0.4, 0.2, 0.3)
    assert tank.liquid_mass(0.25, 1000.0) == pytest.approx(1000.0 * 0.4 * 0.2 * 0.075)
    assert tank.depth_from_fill(volume_fill=0.25) == pytest.approx(0.075)
    assert tank.centroid_height(0.1) == pytest.approx(0.05)
    # box about its own centre: (a^2 + h^2) / 12 per unit mass; parallel axis to `about`
    a, b, h, about = 0.4, 0.2, 0.1, 0.02
    vol = a * b * h
    assert tank.rigid_inertia(h, about) == pytest.approx(
        vol * ((a**2 + h**2) / 12 + (h / 2 - about) ** 2), rel=1e-12)


def test_sphere_liquid_mass_is_the_cap():
    R, fill, rho = 0.1016, 0.6, 998.2
    h = 2 * R * fill
    assert Sphere(R).liquid_mass(fill, rho) == pytest.approx(
        rho * math.pi * h**2 * (3 * R - h) / 3, rel=1e-13)


@pytest.mark.parametrize("args, key", [((0.0, 0.2, 0.3), "length"), ((0.4, -1, 0.3), "width"),
                                       ((0.4, 0.2, "tall"), "height")])
def test_bad_sizes_are_refused(args, key):
    with pytest.raises(ValueError, match=f"`{key}` must be a positive number in m"):
        Rectangular(*args)


def test_rectangular_modes_only_in_closed_form():
    with pytest.raises(ValueError, match="closed form: `method` must be"):
        predict(Rectangular(0.4, 0.2, 0.3), fill=0.5, method="legacy")
