"""The diagnosis's stability bounds (``estimate.diagnosis.fitter``): a pendulum whose start
comes from a prediction or a scan keeps its bob above a share of its start mass and its
damper below the RK4 margin, a new mode's in a warm-started fit too (a second mode's
candidate without them ran 23 minutes over a 15 s budget), while a mode the warm start
already fitted keeps its plain bounds."""

from types import SimpleNamespace

import pytest
import reference_models as ref
from synthetic_cases import make_case, pendulum

from analogs import HingeDamper, Pendulum
from estimate.diagnosis.fitter import MIN_MASS_SHARE, RK4_MARGIN, Fitter, _new_pendulums
from estimate.diagnosis.search import baseline_model


def test_a_new_mode_is_bounded_in_a_warm_fit_and_the_fitted_mode_is_not(tmp_path):
    case, _ = make_case(tmp_path, "bounds", ref.Sine(0.004, 1.9), pendulums=[pendulum()],
                        duration=4.0, seed=3)
    fitter = Fitter([case], None, "estimated", None)
    model = baseline_model(case) + Pendulum("p2") + HingeDamper("p2")
    start = {"p2.mass": 0.09, "p2.length": 0.0108, "p2.damping": 1e-5}
    warm = SimpleNamespace(names=("fixed.mass", "p1.mass", "p1.length", "p1.damping"))
    new = _new_pendulums(model, warm)
    assert new == {"p2"}
    plain = {e.name: e for e in fitter.problem(model, (), start).estimated}
    bounded = {e.name: e for e in fitter.problem(model, (), start, stable=new).estimated}
    h = case.sample_interval
    m_lo = MIN_MASS_SHARE * 0.09
    assert bounded["p2.mass"].lower == pytest.approx(m_lo, rel=1e-12)
    # the damper's bound: h c / (m L^2) = RK4_MARGIN on the lightest, shortest pendulum
    L_lo = bounded["p2.length"].lower
    assert bounded["p2.damping"].upper == pytest.approx(RK4_MARGIN * m_lo * L_lo**2 / h,
                                                        rel=1e-12)
    assert plain["p2.damping"].upper > 1e3 * bounded["p2.damping"].upper
    for name in ("p1.mass", "p1.damping"):  # the warm start's own mode: as built
        assert (bounded[name].lower, bounded[name].upper) == (plain[name].lower,
                                                              plain[name].upper)
