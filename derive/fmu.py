"""Export a derived model as an FMI 2.0 co-simulation FMU.

The FMU wraps the C of :func:`derive.export_c.export_c` in a small FMI 2.0 interface
(``fmi2DoStep`` runs the model's fixed-step RK4); analog parameters are tunable, initial
states are fixed parameters ``<state>_start``. Inputs vary linearly within a
communication step: with the first-order input derivatives the master sets
(``canInterpolateInputs``), else (tunable ``solver.input_extrapolation = 1``, the default)
along the slope from the previous communication point's value, else they are held. The
FMI headers ship with FMPy (extra ``fmu``), which also validates and simulates the result.

Why extrapolate: a master that sets only values (FMPy's ``simulate_fmu`` does; its
``set_input_derivatives=True`` fails for any number of inputs but 9 in FMPy 0.3.32) holds
the inputs over each step, a first-order error in the step: 9.4 % of the peak force at a
10 ms step on the README case. Extrapolated, the error is second order (see the README's
table); a step change of an input is then overshot for one communication step, so masters
with step-like inputs set ``solver.input_extrapolation = 0`` or pass derivatives.
"""

from __future__ import annotations

import datetime
import math
import os
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from analogs.errors import InputError, MissingDependency
from analogs.model import Model
from analogs.vehicle import degrees_of_freedom

from ._compile import c_compiler
from ._fmu_template import FMI2_WRAPPER
from .derived import OUTPUT_NAMES, OUTPUT_UNITS, DerivedModel
from .export_c import CFLAGS, export_c, state_units

__all__ = ["co_simulate", "export_fmu", "fmi_headers"]


def fmi_headers() -> Path:
    """Folder holding ``fmi2Functions.h`` (from FMPy).

    Raises
    ------
    ImportError
        When FMPy is missing: install the extra ``pip install 'slosh-analogs[fmu]'``.
    """
    try:
        import fmpy
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise MissingDependency("FMU export needs FMPy for the FMI headers: "
                                "`python3 -m pip install '.[fmu]'` (from a checkout) or "
                                "`python3 -m pip install fmpy`") from err
    return Path(fmpy.__file__).parent / "c-code"


def _platform() -> tuple[str, str]:
    import fmpy

    return fmpy.platform, fmpy.sharedLibraryExtension


def export_fmu(
    model: DerivedModel | Model,
    path: str | os.PathLike,
    params: Mapping[str, float] | None = None,
    *,
    substeps: int = 1,
    max_step: float = 0.01,
    input_extrapolation: int = 1,
    name: str = "slosh_model",
    description: str | None = None,
    stop_time: float = 10.0,
    overwrite: bool = False,
    cc: str | None = None,
) -> Path:
    """Build an FMI 2.0 co-simulation FMU of ``model`` at ``path`` (``.fmu``).

    Parameters
    ----------
    model : DerivedModel or analogs.Model
        The model (derived first when a ``Model`` is given).
    path : path
        The FMU file to write.
    params : mapping, optional
        Parameter values used as start values (e.g. fitted values). Parameters without a
        value get start 0 and the outputs that depend on them are left out.
    substeps : int, default 1
        RK4 substeps of each internal step.
    max_step : float, default 0.01
        Largest internal step (s), tunable as ``solver.max_step``: a communication step
        ``h`` runs ``ceil(h / max_step)`` equal RK4 steps.
    input_extrapolation : {0, 1, 2}, default 1
        Start value of the tunable ``solver.input_extrapolation``: when the master sets
        no input derivative, continue over the step the polynomial through the input's
        values at this and the previous 1 (linear) or 2 (quadratic) communication points,
        or hold it (0).
    name : str
        Model identifier (a C identifier).
    description : str, optional
        The FMU's description (default: the model and its parameters' source).
    stop_time : float, default 10
        Stop time of the default experiment (s).
    cc : str, optional
        C compiler (default ``$CC``, ``cc`` or ``gcc``).

    Returns
    -------
    Path
        The FMU file.

    Raises
    ------
    RuntimeError
        When no C compiler is found or compilation fails.
    FileExistsError
        When ``path`` exists and ``overwrite`` is false.
    """
    if isinstance(model, Model):
        from ._derive import derive

        model = derive(model)
    dm = model
    path = Path(path)
    if path.suffix != ".fmu":
        raise InputError(f"the FMU file name must end in .fmu, got {path.name!r}")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (`--overwrite`) to replace it")
    if not max_step > 0:
        raise InputError(f"max_step must be positive (s), got {max_step!r}")
    if input_extrapolation not in (0, 1, 2):
        raise InputError("input_extrapolation must be 0 (hold), 1 (linear) or 2 (quadratic), "
                         f"got {input_extrapolation!r}")
    headers = fmi_headers()
    cc = cc or c_compiler()
    if cc is None:
        raise RuntimeError("no C compiler found: set `CC` or install gcc to build the FMU")
    platform, ext = _platform()
    pvec = dm.parameter_vector(params)
    missing = {n for n, v in zip(dm.parameter_names, pvec) if math.isnan(v)}
    outputs = [i for i, o in enumerate(OUTPUT_NAMES) if not missing & set(dm.dependencies[o])]
    guid = "{" + str(uuid.uuid4()) + "}"
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = root / "sources"
        ex = export_c(dm, src, params, substeps=substeps, name=name, description=description)
        for f in (ex.driver, ex.makefile, ex.parameters_csv):
            f.unlink()
        wrapper = src / f"fmi2_{name}.c"
        wrapper.write_text(FMI2_WRAPPER.substitute(name=name, NAME=name.upper(), guid=guid,
                                                   max_step=repr(float(max_step)),
                                                   extrapolate=repr(float(input_extrapolation))))
        bindir = root / "binaries" / platform
        bindir.mkdir(parents=True)
        lib = bindir / f"{name}{ext}"
        cmd = [cc, *CFLAGS, "-shared", "-fPIC", "-I", str(headers), "-I", str(src), "-o", str(lib),
               str(wrapper), *map(str, ex.sources), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"compiling the FMU failed:\n{' '.join(cmd)}\n{proc.stderr}")
        (root / "modelDescription.xml").write_text(
            _model_description(dm, pvec, outputs, name, guid, description, max_step, stop_time,
                               input_extrapolation))
        tmp_fmu = root / "out.fmu"
        with zipfile.ZipFile(tmp_fmu, "w", zipfile.ZIP_DEFLATED) as z:
            for f in sorted(root.rglob("*")):
                if f.is_file() and f != tmp_fmu:
                    z.write(f, f.relative_to(root).as_posix())
        path.parent.mkdir(parents=True, exist_ok=True)
        os.replace(tmp_fmu, path) if _same_fs(root, path.parent) else path.write_bytes(tmp_fmu.read_bytes())
    return path


def _same_fs(a: Path, b: Path) -> bool:
    try:
        return os.stat(a).st_dev == os.stat(b).st_dev
    except OSError:
        return False


def _model_description(dm: DerivedModel, pvec, outputs: list[int], name: str, guid: str,
                       description: str | None, max_step: float, stop_time: float,
                       input_extrapolation: bool) -> str:
    np_, nx, nu, ny = len(pvec), dm.nx, dm.nu, len(OUTPUT_NAMES)
    sunits = state_units(dm)
    units = sorted({p.unit for p in dm.parameters} | set(sunits) | set(dm.input_units)
                   | set(OUTPUT_UNITS) | {"s", "1"})
    rows: list[str] = []
    index: dict[str, int] = {}

    def var(name_: str, vr: int, causality: str, variability: str, unit: str, desc: str,
            start: float | None, initial: str | None = None) -> None:
        attrs = (f"name={quoteattr(name_)} valueReference=\"{vr}\" causality=\"{causality}\" "
                 f"variability=\"{variability}\"")
        if initial:
            attrs += f" initial=\"{initial}\""
        if desc:
            attrs += f" description={quoteattr(desc)}"
        real = f"unit={quoteattr(unit)}" + (f" start=\"{start!r}\"" if start is not None else "")
        rows.append(f"    <ScalarVariable {attrs}>\n      <Real {real}/>\n    </ScalarVariable>")
        index[name_] = len(rows)

    for i, (pm, v) in enumerate(zip(dm.parameters, pvec)):
        desc = pm.description if not math.isnan(v) else f"{pm.description} (no value: start 0)"
        var(pm.name, i, "parameter", "tunable", pm.unit, desc, 0.0 if math.isnan(v) else float(v))
    for i, (s, u) in enumerate(zip(dm.states, sunits)):
        var(f"{s}_start", np_ + i, "parameter", "fixed", u, f"initial value of {s}", 0.0)
    for i, (s, u) in enumerate(zip(dm.inputs, dm.input_units)):
        var(s, np_ + nx + i, "input", "continuous", u, "", 0.0)
    out_names = []
    for i in outputs:
        var(OUTPUT_NAMES[i], np_ + nx + nu + i, "output", "continuous", OUTPUT_UNITS[i],
            "on the tank assembly, tank-frame components, torques about the tank origin"
            if i < 6 else "", None)
        out_names.append(OUTPUT_NAMES[i])
    for i, (s, u) in enumerate(zip(dm.states, sunits)):
        var(s, np_ + nx + nu + ny + i, "output", "continuous", u, "state", None)
        out_names.append(s)
    var("solver.max_step", np_ + nx + nu + ny + nx, "parameter", "tunable", "s",
        "largest internal RK4 step", float(max_step))
    var("solver.input_extrapolation", np_ + nx + nu + ny + nx + 1, "parameter", "tunable", "1",
        "inputs without a derivative from the master: extrapolated over the step through this "
        "and the previous 1 (linear) or 2 (quadratic) communication points' values, or held (0)",
        float(input_extrapolation))
    unknowns = "\n".join(f"      <Unknown index=\"{index[n]}\"/>" for n in out_names)
    unit_defs = "\n".join(f"    <Unit name={quoteattr(u)}/>" for u in units)
    desc = (description or " + ".join(f"{type(c).__name__}({c.name!r})" for c in dm.model.components)) \
        + "; degrees of freedom: " + "; ".join(degrees_of_freedom(dm.model))
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    variables = "\n".join(rows)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(name)} guid="{guid}"
  description={quoteattr(desc)} generationTool="slosh-analogs (derive.fmu)"
  generationDateAndTime="{now}" variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier={quoteattr(name)} canHandleVariableCommunicationStepSize="true"
    canInterpolateInputs="true" maxOutputDerivativeOrder="0" canNotUseMemoryManagementFunctions="true"/>
  <UnitDefinitions>
{unit_defs}
  </UnitDefinitions>
  <DefaultExperiment startTime="0" stopTime="{float(stop_time)!r}" stepSize="{float(max_step)!r}"/>
  <ModelVariables>
{variables}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{unknowns}
    </Outputs>
    <InitialUnknowns>
{unknowns}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def co_simulate(
    path: str | os.PathLike,
    time: np.ndarray,
    inputs: Mapping[str, np.ndarray],
    outputs: tuple[str, ...] | list[str],
    *,
    start_values: Mapping[str, float] | None = None,
    derivatives: bool = True,
) -> dict[str, np.ndarray]:
    """Run an FMU exported by :func:`export_fmu` as a master that passes input derivatives.

    At each communication point ``time[k]`` the master sets the inputs' values and, with
    ``derivatives``, their slopes to the next point (``fmi2SetRealInputDerivatives``), so
    the FMU sees each input as the straight line between the samples; it then steps to
    ``time[k + 1]`` and reads ``outputs`` (inputs at the end of the step, as the FMU
    extrapolated them). FMPy's ``simulate_fmu`` cannot do this for these FMUs: its
    ``set_input_derivatives=True`` fails unless the model has exactly 9 inputs (FMPy 0.3.32).

    Parameters
    ----------
    path : path
        The ``.fmu`` file.
    time : array (n,)
        Communication points (s), increasing; the first is the start time.
    inputs : mapping
        Samples of every input at ``time``, by input name (SI units).
    outputs : sequence of str
        Names of the variables to read at every communication point.
    start_values : mapping, optional
        Parameters and initial states (``<state>_start``) to set before initialization.
    derivatives : bool, default True
        Pass the slopes; without them the FMU extrapolates or holds the inputs (its
        ``solver.input_extrapolation``).

    Returns
    -------
    dict
        ``"time"`` and each output name: arrays of length ``n``.

    Raises
    ------
    InputError
        For an unknown variable name or a missing input.
    """
    try:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise MissingDependency("co_simulate needs FMPy: `python3 -m pip install '.[fmu]'`") from err
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    names = [v.name for v in md.modelVariables if v.causality == "input"]
    wanted = [*(start_values or {}), *outputs]
    problems = [f"no variable `{n}`" for n in wanted if n not in vr]
    problems += [f"no samples of input `{n}`" for n in names if n not in inputs]
    problems += [f"`{n}` is not an input (inputs: {', '.join(names)})" for n in inputs if n not in names]
    if problems:
        raise InputError(f"{path}: " + "; ".join(problems))
    t = np.asarray(time, float)
    U = np.array([np.broadcast_to(np.asarray(inputs[n], float), t.shape) for n in names])
    uvr, yvr = [vr[n] for n in names], [vr[n] for n in outputs]
    unzipped = extract(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="co_simulate")
    out = np.empty((len(outputs), t.size))
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=float(t[0]))
        slave.enterInitializationMode()
        if start_values:
            slave.setReal([vr[n] for n in start_values], [float(v) for v in start_values.values()])
        slave.setReal(uvr, list(U[:, 0]))
        slave.exitInitializationMode()
        out[:, 0] = slave.getReal(yvr)
        for k in range(t.size - 1):
            h = t[k + 1] - t[k]
            slave.setReal(uvr, list(U[:, k]))
            if derivatives:
                slave.setRealInputDerivatives(uvr, [1] * len(uvr), list((U[:, k + 1] - U[:, k]) / h))
            slave.doStep(float(t[k]), float(h))
            out[:, k + 1] = slave.getReal(yvr)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return {"time": t, **dict(zip(outputs, out))}
