"""OncePerPoint serves a function's outputs, dense and sparse, from its buffer: the same
numbers as calling the function, at every point, in any order of points."""

import casadi as ca
import numpy as np
import pytest

from estimate.fitting._once import OncePerPoint


def _wrapped():
    w = ca.MX.sym("w", 3)
    # a sparse output whose structure is not the dense one's, and a dense one
    J = ca.sparsify(ca.DM([[1, 0, 2], [0, 0, 3]])) * ca.sin(w[0]) + ca.DM([[0, 0, 1], [0, 0, 0]]) * w[2]
    return ca.Function("f", [w], [w[1] ** 2 * ca.exp(w), J])


def test_outputs_equal_the_functions_at_every_point_and_after_a_revisit():
    f = _wrapped()
    once = OncePerPoint("once", f)
    w = ca.MX.sym("w", 3)
    # two consumers of the same iterate, as IPOPT's gradient and Hessian functions are
    g = ca.Function("g", [w], [once(w)[0] * 2, ca.mtimes(once(w)[1].T, once(w)[1])])
    rng = np.random.default_rng(1)
    points = [rng.normal(size=3) for _ in range(3)]
    for p in points + points[::-1]:  # revisiting a point after another recomputes it
        a, b = g(p)
        fa, fb = f(p)
        np.testing.assert_allclose(np.asarray(a), 2 * np.asarray(fa), rtol=1e-15)
        np.testing.assert_allclose(np.asarray(b), np.asarray(ca.mtimes(fb.T, fb)), rtol=1e-15)
        assert once(p)[1].sparsity() == f.sparsity_out(1)


def test_released_buffers_are_made_again_at_the_next_point():
    f = _wrapped()
    once = OncePerPoint("once", f)
    p = np.array([0.3, -1.2, 0.7])
    first = [np.asarray(v) for v in once(p)]
    once.release()
    again = [np.asarray(v) for v in once(p)]  # the same point: recomputed, not stale zeros
    for a, b, c in zip(first, again, f(p)):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_allclose(b, np.asarray(c), rtol=1e-15)


def test_ipopt_objective_and_constraints_come_from_the_once_per_point_jacobians(monkeypatch):
    """The objective and constraints IPOPT evaluates at a point are read from the
    once-per-point Jacobians of that point (IPOPT then asks for their derivatives there),
    not simulated by functions of their own: a new point costs one evaluation whichever
    function asks first, and the objective equals the residuals' sum of squares."""
    from pathlib import Path

    from estimate import FitProblem, load_case, model_from_spec
    from estimate.fitting.assembly import assemble_nlp
    from estimate.fitting.nlp import Hessian
    from estimate.fitting.transcription import MultipleShooting

    evaluations = []
    allocate = OncePerPoint._allocate

    def counted(self):
        allocate(self)
        run = self._evaluate
        self._evaluate = lambda: (evaluations.append(1), run())

    monkeypatch.setattr(OncePerPoint, "_allocate", counted)
    case = load_case(Path(__file__).resolve().parents[3] / "examples" / "A1.toml")
    problem = FitProblem.build(case, model_from_spec("fixed,p1:nospring", case))
    kinds = [e.initial_state_kind for e in problem.experiments]
    nlp, _ = assemble_nlp(problem, MultipleShooting(), "squared", kinds, True, None, None)
    opts, f, g = nlp.derivative_options(Hessian(), True)
    F = ca.Function("f", [nlp.w], [f, g])
    direct = ca.Function("direct", [nlp.w], [nlp.f, nlp.g])
    w0 = nlp.w0
    w1 = w0 * (1 + 1e-3 * np.random.default_rng(2).normal(size=w0.size))
    for k, w in enumerate((w0, w1), start=1):
        fv, gv = F(w)  # a trial point: the objective and constraints first
        assert len(evaluations) == k
        opts["grad_f"](w, [])  # then their derivatives at the same point
        opts["jac_g"](w, [])
        assert len(evaluations) == k
        fd, gd = direct(w)
        assert float(fv) == pytest.approx(float(fd), rel=1e-12)
        np.testing.assert_allclose(np.asarray(gv), np.asarray(gd), rtol=1e-10, atol=1e-14)
