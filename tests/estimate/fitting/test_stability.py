"""The rotor's RK4 stability bound (:mod:`estimate.fitting.stability`)."""

from __future__ import annotations

import numpy as np
import pytest
import reference_spinning as rs
from synthetic_cases import make_spinning_case

from estimate import FitProblem, model_from_spec
from estimate.fitting.stability import RK4_MARGIN, rotor_bounds


def _rk4_gain(z: float) -> float:
    """One classical RK4 step's amplification of ``x' = lambda x`` at ``z = h lambda``
    (the Taylor polynomial of exp to fourth order)."""
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def test_the_margin_lies_inside_rk4s_stability_interval():
    """At ``h c / I = RK4_MARGIN`` a step shrinks the rotor's relative spin (|gain| < 1);
    at 2.8 it grows it: the bound keeps the simulation stable with room."""
    assert abs(_rk4_gain(-RK4_MARGIN)) < 1.0
    assert abs(_rk4_gain(-2.8)) > 1.0


@pytest.fixture(scope="module")
def spinning(tmp_path_factory):
    rig = rs.Rig(spin_rate=6.0, radius=0.4, height=0.1, nutation_angle=0.06,
                 nutation_frequency=0.3, dry_mass=2.0)
    case, _ = make_spinning_case(tmp_path_factory.mktemp("s"), "S1", rig,
                                 pendulum=rs.SphericalPendulum(1.25, 0.062, 0.035,
                                                               damping=0.0005),
                                 rotor=rs.Rotor(0.01, 0.04, axis="y"), fixed_mass=1.5,
                                 noise=0.01, seed=3, tank_radius=0.1016, duration=2.0)
    return case


def test_a_rotor_with_both_estimated_is_bounded_by_the_sample_step(spinning):
    """``r1.damping - (2 / h) r1.inertia <= 0`` at the record's 10 ms step (200 1/s);
    nothing when the damper is held; none for a model without a rotor."""
    case = spinning
    h = float(case.sample_interval)
    prob = FitProblem.build(case, model_from_spec("fixed,p1:nospring,r1", case),
                            hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0})
    (bound,) = rotor_bounds([case], prob.model, prob.names)
    assert bound.stability and bound.upper == 0.0
    terms = dict(bound.terms)
    assert terms["r1.damping"] == 1.0
    assert terms["r1.inertia"] == pytest.approx(-RK4_MARGIN / h, rel=1e-12)
    # the truth (4 1/s) lies far inside; the overflowing iterate of the 20 s record's fit
    # (inertia 0.00041, damper 0.127: 310 1/s) outside
    assert bound.slack(["r1.damping", "r1.inertia"], np.array([0.04, 0.01])) > 0
    assert bound.slack(["r1.damping", "r1.inertia"], np.array([0.127, 0.00041])) < 0
    held = FitProblem.build(case, model_from_spec("fixed,p1:nospring,r1", case),
                            hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0,
                                  "r1.damping": 0.04})
    assert rotor_bounds([case], held.model, held.names) == ()
    plain = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case),
                             hold={"fixed.inertia": 0.0, "fixed.axial_inertia": 0.0})
    assert rotor_bounds([case], plain.model, plain.names) == ()
