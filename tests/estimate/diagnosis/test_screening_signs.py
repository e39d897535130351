"""The screening's step of physical signs (``estimate.diagnosis.screening``): when the free
Gauss-Newton step gives a term's signed parameter the unphysical sign, the term is scored by
the best step with its parameters of their physical signs. The reference is an independent
bound-constrained maximisation of the same quadratic model (SciPy's L-BFGS-B on
``2 b.x - x.S x``, the base parameters free, the signed ones >= 0); tolerance 1e-6 relative
(the optimiser's, on a well-conditioned 4-parameter problem)."""

import numpy as np
import pytest
from scipy.optimize import minimize

from estimate.diagnosis.families.base import Term
from estimate.diagnosis.screening import _physical_step, _unphysical
from estimate.fitting.linearise import Linearisation

NAMES = ("p1.mass", "p1.damping", "rig.friction_viscous", "rig.friction_coulomb")
TERM = Term("rig_friction", "rig_friction", (), (), NAMES[2:],
            dict.fromkeys(NAMES[2:], 1))


def linearisation(S: np.ndarray, b: np.ndarray) -> Linearisation:
    # scales 1 and the new parameters' start (null) values 0: steps are values
    return Linearisation(NAMES, np.ones(4), np.array([1.3, 0.01, 0.0, 0.0]), 10.0, b, S)


def reference(S: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray]:
    """The sign-constrained maximum of 2 b.x - x.S x and where it is."""
    res = minimize(lambda x: x @ S @ x - 2 * b @ x, np.zeros(4),
                   jac=lambda x: 2 * S @ x - 2 * b, method="L-BFGS-B",
                   bounds=[(None, None), (None, None), (0, None), (0, None)],
                   options={"ftol": 1e-15, "gtol": 1e-12})
    return -res.fun, res.x


def test_a_collinear_viscous_part_with_the_wrong_sign_is_held_at_zero():
    # viscous and Coulomb regressors nearly collinear (correlation 0.95): the data want
    # a Coulomb force, the free step splits it into a large Coulomb and a negative viscous
    rng = np.random.default_rng(3)
    A = rng.normal(size=(200, 4))
    A[:, 2] = 0.95 * A[:, 3] + 0.31 * A[:, 2]
    S = A.T @ A
    b = A.T @ (A @ np.array([0.0, 0.0, -0.4, 1.0]) + 0.01 * rng.normal(size=200))
    lin = linearisation(S, b)
    free_reduction, free_values = lin.score(NAMES)
    assert _unphysical(TERM, free_values) == ["rig.friction_viscous"]
    reduction, values, held = _physical_step(lin, NAMES[:2], TERM, free_reduction, free_values)
    best, x = reference(S, b)
    assert held == ("rig.friction_viscous",)
    assert reduction == pytest.approx(best, rel=1e-6)
    assert reduction < free_reduction  # a constraint never gains
    assert [values[n] for n in NAMES] == pytest.approx(
        np.array([1.3, 0.01, 0.0, 0.0]) + x, rel=1e-6, abs=1e-9)


def test_a_term_whose_every_part_has_the_wrong_sign_stays_unphysical():
    S = np.diag([4.0, 3.0, 2.0, 1.0])
    b = np.array([0.0, 0.0, -1.0, -2.0])
    lin = linearisation(S, b)
    free_reduction, free_values = lin.score(NAMES)
    reduction, values, held = _physical_step(lin, NAMES[:2], TERM, free_reduction, free_values)
    assert held == ()  # no face with a free new parameter is physical
    assert (reduction, values) == (free_reduction, free_values)
    assert reference(S, b)[0] == pytest.approx(0.0, abs=1e-12)
