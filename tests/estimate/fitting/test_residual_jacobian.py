"""The residual Jacobian assembled from per-sample blocks equals CasADi's automatic
differentiation of the residual expression, for every variant the fit builds: estimated and
filtered input, a fixed and a free start, two pendulums, a measurement model with its own
parameters, two cases at once and weighted samples (a sensor delay zeroes the last ones)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import reference_models as ref
from synthetic_cases import make_case, pendulum

from estimate import FitProblem, model_from_spec
from estimate.fitting.measurement import SensorDelay, SensorOffset
from estimate.fitting.nlp import _setup
from estimate.fitting.transcription import MultipleShooting


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    folder = tmp_path_factory.mktemp("jac")
    # 3 s records: enough to exercise every index; longer ones only cost time
    return [make_case(folder, name, ref.Ramped(ref.Sine(amp, hz), 1.0, 0.0),
                      pendulums=[pendulum()], duration=3.0, seed=seed, tone=ref.Tone(0.05, 25.0))[0]
            for name, amp, hz, seed in (("a", 0.003, 1.9, 1), ("b", 0.002, 2.5, 2))]


VARIANTS = {
    "estimated rest": (1, "fixed,p1", "estimated", (), "rest"),
    "estimated free": (1, "fixed,p1", "estimated", (), "free"),
    "filtered rest": (1, "fixed,p1", "filtered", (), "rest"),
    "two pendulums": (1, "fixed,p1,p2", "estimated", (), "rest"),
    "offset and drift": (1, "fixed,p1", "estimated", (SensorOffset(),), "rest"),
    "delay weights": (1, "fixed,p1", "estimated", (SensorDelay(0.05),), "free"),
    "two cases": (2, "fixed,p1", "estimated", (), "rest"),
}


@pytest.mark.parametrize("variant", VARIANTS)
def test_assembled_residual_jacobian_equals_automatic_differentiation(cases, variant):
    ncases, spec, mode, measurement, start = VARIANTS[variant]
    chosen = cases[:ncases]
    problem = FitProblem.build(chosen if ncases > 1 else chosen[0],
                               model_from_spec(spec, chosen[0]), input=mode,
                               measurement=list(measurement))
    nlp, terms = _setup(problem, MultipleShooting(), "squared", [start] * ncases, True, False,
                        None)
    assert all(t.jacobian is not None for t in terms)  # the assembled path is the one tested
    f = ca.Function("f", [nlp.w], [nlp.jac_r, ca.jacobian(nlp.r, nlp.w)])
    w = nlp.w0 * (1 + 0.05 * np.random.default_rng(3).standard_normal(nlp.w0.size))
    assembled, automatic = (np.asarray(m.full()) for m in f(w))
    # the same derivatives by two routes: equal to rounding (relative 1e-12 of the largest)
    assert np.max(np.abs(assembled - automatic)) <= 1e-12 * np.max(np.abs(automatic))
