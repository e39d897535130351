"""Relative equilibria (``[test] initial_state = "steady"``) against hand-derived balances:
the conical pendulum, a rotor turning with the tank, and the rotating-damping instability of
a rotary oscillator tuned below the spin rate."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from analogs import HingeDamper, RotaryOscillator, Rotor, SphericalPendulum
from analogs.errors import InputError
from analogs.spinning import SpinningRig
from derive import derive
from derive.equilibrium import relative_equilibrium

W, R, L, G = 6.0, 0.4, 0.1, 9.80665
RIG = {"rig.spin_rate": W, "rig.radius": R, "rig.dry_mass": 2.0}
#: The equilibrium is solved to round-off of the generalized forces (1e-9 of the stiffness);
#: 1e-9 rad leaves a margin while a wrong centrifugal term moves it by degrees.
ANGLE_TOL = 1e-9


@pytest.fixture(scope="module")
def pendulum_rotor():
    return derive(SpinningRig() + SphericalPendulum("p1") + HingeDamper("p1")
                  + Rotor("r1", axis="y"))


def _p(dm, **extra):
    values = {**RIG, "p1.mass": 1.2, "p1.length": L, "p1.hinge_height": 0.05, "p1.damping": 1e-3,
              "r1.inertia": 0.01, "r1.damping": 0.04, **extra}
    return dm.parameter_vector({k: v for k, v in values.items() if k in dm.parameter_names})


def test_conical_pendulum_and_rotor_turning_with_the_tank(pendulum_rotor):
    dm = pendulum_rotor
    x0 = relative_equilibrium(dm, _p(dm), np.array([0.0, 0.01]), np.zeros((0, 2)))
    # hand balance in the spinning frame: W^2 (r + L sin a) cos a = g sin a
    a = brentq(lambda a: W**2 * (R + L * math.sin(a)) * math.cos(a) - G * math.sin(a),
               1e-6, math.pi / 2)
    state = dict(zip(dm.states, x0))
    assert state["p1.alpha"] == pytest.approx(a, abs=ANGLE_TOL)
    assert math.degrees(a) > 55  # swung far out: a start from rest would be wrong by that much
    assert abs(state["p1.beta"]) < ANGLE_TOL and state["r1.psi"] == 0.0
    assert all(state[s] == 0.0 for s in dm.states if s.endswith("_dot"))


def test_a_coning_table_has_no_steady_state(pendulum_rotor):
    dm = pendulum_rotor
    p = _p(dm, **{"rig.nutation_angle": 0.06, "rig.nutation_frequency": -0.5})
    with pytest.raises(InputError, match=r"the rig motion is not steady at the first sample "
                                         r"\(t = 0 s\): the relative equilibrium moves by"):
        relative_equilibrium(dm, p, np.array([0.0, 0.01]), np.zeros((0, 2)))


def test_rotary_oscillator_below_the_spin_rate_is_unstable_with_rotating_damping():
    dm = derive(SpinningRig(gravity=False) + RotaryOscillator("o1"))

    def p(frequency_ratio):
        J = 2e-3
        k = J * (frequency_ratio * W) ** 2
        return dm.parameter_vector({**RIG, "o1.inertia": J, "o1.stiffness": k, "o1.damping": 1e-3})

    x0 = relative_equilibrium(dm, p(1.5), np.array([0.0, 0.01]), np.zeros((0, 2)))
    assert np.max(np.abs(x0)) < ANGLE_TOL
    # tuned below the spin, damping relative to the tank destabilises the oscillator (its
    # backward whirl gains energy from the spin): no steady start exists
    with pytest.raises(InputError, match=r"no stable relative equilibrium .* is unstable"):
        relative_equilibrium(dm, p(0.7), np.array([0.0, 0.01]), np.zeros((0, 2)))
