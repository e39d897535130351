"""The vehicle export of a lateral fit sloshes along tank x and y (an axisymmetric tank).

Reference: the spherical pendulum's equations of motion in a translating tank frame,
derived by hand in ``tests/reference_vehicle.py`` and integrated with SciPy (``solve_ivp``,
DOP853, rtol 1e-10). The exported model (Python simulation, compiled C driver
and FMU) driven along tank y must give the x-drive response turned by 90 degrees.
"""

from __future__ import annotations

import numpy as np
import pytest
from reference_vehicle import FIT, SETS, LateralDrive, spherical_pendulum

from analogs import FixedMass, LateralRig, Pendulum, SwingDamper
from analogs.errors import InputError
from derive import RK4, derive, simulate
from derive.export_c import has_c_compiler, run_driver, write_input_csv
from estimate.cli import main
from estimate.cli.export import export_model

#: RK4 at 1 ms against DOP853 at rtol 1e-10: the RK4 error over 10 s of a 2.1 Hz
#: resonance swinging 1 rad, relative to the peak (observed 2e-9 along an axis, 8e-8
#: diagonally); 1e-6 leaves margin.
RK4_VS_REFERENCE = 1e-6
#: The acceptance bound: the same peak force from a y drive as from an x drive.
SAME_PEAK = 0.01


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.fixture(scope="module")
def vehicle():
    model, used = export_model("fixed,p1", FIT | SETS, interface="vehicle")
    return derive(model), used


@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, 1.0), (0.6, 0.8)],
                         ids=["x", "y", "diagonal"])
def test_exported_vehicle_model_matches_hand_written_spherical_pendulum(vehicle, direction):
    dm, used = vehicle
    t = np.linspace(0.0, 10.0, 10001)
    sim = simulate(dm, used, t, LateralDrive(dm.inputs, direction), integrator=RK4())
    angles, force = spherical_pendulum(t, direction)
    assert np.max(np.abs(angles)) > 0.5  # the resonance swings the pendulum ~1 rad
    for i, name in enumerate(("p1.alpha", "p1.beta")):
        if np.ptp(angles[i]) > 0:
            assert _rel(sim.state(name), angles[i]) < RK4_VS_REFERENCE, name
        else:
            assert np.max(np.abs(sim.state(name))) == 0.0, name
    for i, name in enumerate(("force_x", "force_y", "force_z")):
        assert np.max(np.abs(sim.output(name) - force[i])) < RK4_VS_REFERENCE * np.max(np.abs(force)), name


def test_y_drive_is_the_x_drive_turned(vehicle):
    dm, used = vehicle
    t = np.linspace(0.0, 10.0, 10001)
    x = simulate(dm, used, t, LateralDrive(dm.inputs, (1.0, 0.0)), integrator=RK4())
    y = simulate(dm, used, t, LateralDrive(dm.inputs, (0.0, 1.0)), integrator=RK4())
    assert np.max(np.abs(x.output("force_x"))) > 9.0  # slosh, not the 1.4 N of the rigid mass
    assert _rel(y.output("force_y"), x.output("force_x")) < 1e-12
    assert _rel(y.state("p1.beta"), x.state("p1.alpha")) < 1e-12
    # torque about O from a y drive is the x drive's turned by 90 degrees: tau_x = -tau_y
    assert _rel(-y.output("torque_x"), x.output("torque_y")) < 1e-12


def test_vehicle_export_refuses_what_cannot_be_made_3d():
    with pytest.raises(InputError, match=r"QuadraticDamper on 'p1' acts on each angle .* "
                                         r"`--planar`"):
        export_model("fixed,p1:quadratic", FIT, interface="vehicle")
    model, _ = export_model("fixed,p1:quadratic", FIT, interface="vehicle", planar=True)
    assert "p1.theta" in derive(model).states


needs_cc = pytest.mark.skipif(not has_c_compiler(), reason="no C compiler (cc/gcc/$CC) found")


def _export_args(tmp_path):
    fit = tmp_path / "fit.json"
    fit.write_text(
        '{"model_spec": "fixed,p1", "parameters": {'
        + ", ".join(f'"{k}": {{"value": {v!r}}}' for k, v in FIT.items()) + "}}")
    return [str(fit), "--interface", "vehicle",
            *[a for k, v in SETS.items() for a in ("--set", f"{k}={v}")]]


@needs_cc
def test_c_export_sloshes_alike_along_x_and_y(tmp_path, capsys):
    out = tmp_path / "vehicle_c"
    assert main(["export", *_export_args(tmp_path), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "p1: SphericalPendulum, 2 DOF (p1.alpha, p1.beta): slosh along tank x" in text, text
    assert "slosh along tank x (p1.alpha) and y (p1.beta)" in (out / "slosh_model.h").read_text()
    names = tuple(l.split()[2] for l in (out / "slosh_model.h").read_text().splitlines()
                  if l.startswith(" *   u["))
    t = np.arange(0.0, 10.0, 0.001)
    peaks = {}
    for axis, direction in (("x", (1.0, 0.0)), ("y", (0.0, 1.0))):
        write_input_csv(tmp_path / f"{axis}.csv", t, LateralDrive(names, direction).values(t).T, names)
        res = run_driver(out / "simulate", tmp_path / f"{axis}.csv", tmp_path / f"o{axis}.csv")
        header = (tmp_path / f"o{axis}.csv").read_text().splitlines()[0].split(",")
        force = res[:, header.index(f"force_{axis}")]
        peaks[axis] = np.max(np.abs(force))
        _, ref = spherical_pendulum(t, direction)
        # linear input interpolation at 1 ms against the exact sine: ~(h w)^2/8 = 2e-6
        assert _rel(force, ref["xy".index(axis)]) < 1e-4, axis
    assert peaks["x"] > 9.0
    assert abs(peaks["y"] - peaks["x"]) < SAME_PEAK * peaks["x"]


@needs_cc
def test_fmu_sloshes_alike_along_x_and_y(tmp_path, capsys):
    fmpy = pytest.importorskip("fmpy", reason="FMU tests need FMPy (extra `fmu`)")
    fmu = tmp_path / "vehicle.fmu"
    assert main(["export", *_export_args(tmp_path), "--fmu", str(fmu)]) == 0
    assert "slosh along tank x (p1.alpha) and y (p1.beta)" in capsys.readouterr().out
    md = fmpy.read_model_description(str(fmu))
    names = tuple(v.name for v in md.modelVariables if v.causality == "input")
    t = np.arange(0.0, 10.0 + 1e-9, 0.001)
    peaks = {}
    for axis, direction in (("x", (1.0, 0.0)), ("y", (0.0, 1.0))):
        u = LateralDrive(names, direction).values(t)
        signals = np.array(list(zip(t, *u)), dtype=[("time", float)] + [(n, float) for n in names])
        res = fmpy.simulate_fmu(str(fmu), stop_time=10.0, output_interval=0.001, input=signals,
                                output=[f"force_{axis}"])
        peaks[axis] = np.max(np.abs(res[f"force_{axis}"]))
    assert peaks["x"] > 9.0
    assert abs(peaks["y"] - peaks["x"]) < SAME_PEAK * peaks["x"]


def test_swing_damper_needs_a_spherical_pendulum():
    with pytest.raises(ValueError, match=r"a swing damper needs a spherical pendulum's two angles "
                                         r"\(alpha, beta\), its host has 1"):
        derive(LateralRig() + FixedMass("fixed") + Pendulum("p1") + SwingDamper("p1"))
