"""Exported C: compiled warning-free with gcc -std=c99 -Wall -Wextra -O2 -Werror, run
through its standalone driver, and compared with ``simulate`` (same RK4 on the same grid)."""

from __future__ import annotations

import numpy as np
import pytest

from analogs import FixedMass, HingeDamper, HingeSpring, LateralRig, Pendulum
from derive import RK4, Sine, derive, simulate
from derive.export_c import export_c, has_c_compiler, run_driver, write_input_csv

#: The driver runs the same RK4 arithmetic as CasADi's virtual machine, compiled; only
#: rounding order may differ (~1e-13 observed), the acceptance bound is 1e-9.
C_VS_SIMULATE = 1e-9

needs_cc = pytest.mark.skipif(not has_c_compiler(), reason="no C compiler (cc/gcc/$CC) found")

PARAMS = {
    "rig.dry_mass": 1.2, "fixed.mass": 1.456, "fixed.height": 0.05, "fixed.inertia": 0.01,
    "fixed.axial_inertia": 0.02, "p1.mass": 1.338, "p1.length": 0.057, "p1.hinge_height": 0.1,
    "p1.stiffness": 0.01, "p1.damping": 1e-4, "p2.mass": 0.12, "p2.length": 0.021,
    "p2.hinge_height": 0.11, "p2.damping": 2e-4,
}


def two_pendulums():
    return (LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1")
            + HingeDamper("p1") + Pendulum("p2") + HingeDamper("p2"))


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    if not has_c_compiler():
        pytest.skip("no C compiler (cc/gcc/$CC) found")
    folder = tmp_path_factory.mktemp("export")
    ex = export_c(two_pendulums(), folder, PARAMS)
    return ex, ex.build()  # build() raises on any compiler warning (-Werror, stderr checked)


def _relative_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-channel max error relative to the channel's max magnitude."""
    return np.max(np.abs(a - b), axis=0) / np.maximum(np.max(np.abs(b), axis=0), 1e-300)


@needs_cc
def test_driver_matches_simulate_rk4(built, tmp_path):
    ex, exe = built
    t = np.linspace(0.0, 10.0, 1001)
    exc = Sine(0.005, 1.855)
    x0 = {"p1.theta": 0.05, "p2.theta_dot": -0.2}
    sim = simulate(two_pendulums(), PARAMS, t, exc, integrator=RK4(), x0=x0)
    # --stages: rows at the RK4 stage times (half steps), exactly the inputs simulate uses
    ts = np.linspace(0.0, 10.0, 2001)
    ts[::2] = t
    write_input_csv(tmp_path / "in.csv", ts, exc.values(ts).T, ex.inputs)
    (tmp_path / "x0.csv").write_text("name,value\n# initial state\np1.theta,0.05\np2.theta_dot,-0.2\n")
    out = run_driver(exe, tmp_path / "in.csv", tmp_path / "out.csv",
                     params_csv=tmp_path / "x0.csv", stages=True)
    assert out.shape == (t.size, 1 + len(ex.states) + len(ex.outputs))
    np.testing.assert_array_equal(out[:, 0], t)
    states, outputs = out[:, 1:1 + len(ex.states)], out[:, 1 + len(ex.states):]
    for name in ("force_x", "torque_y", "kinetic_energy"):
        assert np.ptp(sim.output(name)) > 0  # the comparison is not between zeros
    moving = np.max(np.abs(sim.outputs), axis=0) > 0
    assert np.all(_relative_error(outputs[:, moving], sim.outputs[:, moving]) < C_VS_SIMULATE)
    assert np.all(_relative_error(states, sim.states) < C_VS_SIMULATE)


@needs_cc
def test_parameter_file_overrides_compiled_defaults(built, tmp_path):
    ex, exe = built
    t = np.linspace(0.0, 2.0, 201)
    exc = Sine(0.004, 2.5)
    changed = {**PARAMS, "p1.length": 0.08}
    sim = simulate(derive(two_pendulums()), changed, t, exc, integrator=RK4())
    ts = np.linspace(0.0, 2.0, 401)
    ts[::2] = t
    write_input_csv(tmp_path / "in.csv", ts, exc.values(ts).T, ex.inputs)
    (tmp_path / "p.csv").write_text("p1.length,0.08\n")
    out = run_driver(exe, tmp_path / "in.csv", tmp_path / "out.csv",
                     params_csv=tmp_path / "p.csv", stages=True)
    force = out[:, 1 + len(ex.states)]
    assert _relative_error(force[:, None], sim.output("force_x")[:, None])[0] < C_VS_SIMULATE
    base = run_driver(exe, tmp_path / "in.csv", tmp_path / "base.csv", stages=True)
    assert np.max(np.abs(base[:, 1 + len(ex.states)] - force)) > 1e-3


@needs_cc
def test_interpolating_mode_converges_to_simulate(built, tmp_path):
    # Default mode: inputs at the half steps are linear interpolations of the rows, an
    # O(h^2) input error; on a fine grid the force agrees with simulate to ~1e-4.
    ex, exe = built
    t = np.linspace(0.0, 3.0, 3001)
    exc = Sine(0.005, 1.855)
    sim = simulate(two_pendulums(), PARAMS, t, exc, integrator=RK4())
    write_input_csv(tmp_path / "in.csv", t, exc.values(t).T, ex.inputs)
    out = run_driver(exe, tmp_path / "in.csv", tmp_path / "out.csv")
    err = _relative_error(out[:, 1 + len(ex.states)][:, None], sim.output("force_x")[:, None])[0]
    assert 0 < err < 1e-4


@needs_cc
def test_driver_rejects_wrong_header(built, tmp_path):
    _, exe = built
    (tmp_path / "in.csv").write_text("time,x,x_dot,x_ddot\n0,0,0,0\n")
    with pytest.raises(RuntimeError, match="header column 2 must be 'rig.x'"):
        run_driver(exe, tmp_path / "in.csv", tmp_path / "out.csv")


def test_header_documents_order_units_and_defaults(tmp_path):
    ex = export_c(two_pendulums(), tmp_path, PARAMS, substeps=2, name="tank_a")
    text = ex.header.read_text()
    assert "#define TANK_A_NX 4" in text and "#define TANK_A_NSTAGES 5" in text
    assert "u[2]  rig.x_ddot  m/s^2" in text
    assert "p1.length" in text and "0.057" in text and "N m s/rad" in text
    assert "y[0]  force_x" in text
    assert (tmp_path / "parameters.csv").read_text().splitlines()[0] == "name,value,unit"


def test_export_errors(tmp_path):
    with pytest.raises(ValueError, match="C identifier"):
        export_c(two_pendulums(), tmp_path, PARAMS, name="bad-name")
    with pytest.raises(ValueError, match="substeps must be a positive integer"):
        export_c(two_pendulums(), tmp_path, PARAMS, substeps=0)
    export_c(two_pendulums(), tmp_path, PARAMS)
    with pytest.raises(FileExistsError, match="overwrite"):
        export_c(two_pendulums(), tmp_path, PARAMS)


def test_state_units_come_from_the_component_not_the_coordinate_name(tmp_path):
    """A rotational coordinate called ``angle`` is exported in rad because its component
    says so (the exporter used to guess from names and wrote m)."""
    from analogs import Component, Param

    class Paddle(Component):
        coordinates = ("angle",)
        coordinate_units = {"angle": "rad"}
        parameters = {"mass": Param("kg", lower=0.0), "arm": Param("m", lower=0.0)}

        def declare(self, k):
            import sympy as sp

            k.add_particle(k.p.mass, k.p.arm * (sp.sin(k.q.angle) * k.tank.x
                                                - sp.cos(k.q.angle) * k.tank.z))

    dm = derive(LateralRig() + FixedMass("fixed") + Paddle("b1"))
    assert dm.state_units == ("rad", "rad/s")
    export_c(dm.model, tmp_path, {"rig.dry_mass": 1.0, "fixed.mass": 1.0, "b1.mass": 0.5,
                                  "b1.arm": 0.1})
    sources = " ".join(f.read_text() for f in tmp_path.glob("*.[ch]"))
    assert 'state_units[SLOSH_MODEL_NX + 1] = {"rad", "rad/s", 0}' in sources
