"""Export a derived model as an FMI 2.0 co-simulation FMU.

The FMU wraps the C of :func:`derive.export_c.export_c` in a small FMI 2.0 interface
(``fmi2DoStep`` runs the model's fixed-step RK4); analog parameters are tunable, initial
states are fixed parameters ``<state>_start``, inputs may be interpolated within a step
from first-order input derivatives (``canInterpolateInputs``). The FMI headers ship with
FMPy (extra ``fmu``), which also validates and simulates the result.
"""

from __future__ import annotations

import datetime
import math
import os
import subprocess
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import quoteattr

from analogs.errors import InputError, MissingDependency
from analogs.model import Model

from ._compile import c_compiler
from ._fmu_template import FMI2_WRAPPER
from .derived import OUTPUT_NAMES, OUTPUT_UNITS, DerivedModel
from .export_c import CFLAGS, export_c, state_units

__all__ = ["export_fmu", "fmi_headers"]


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
    name : str
        Model identifier (a C identifier).
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
                                                   max_step=repr(float(max_step))))
        bindir = root / "binaries" / platform
        bindir.mkdir(parents=True)
        lib = bindir / f"{name}{ext}"
        cmd = [cc, *CFLAGS, "-shared", "-fPIC", "-I", str(headers), "-I", str(src), "-o", str(lib),
               str(wrapper), *map(str, ex.sources), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"compiling the FMU failed:\n{' '.join(cmd)}\n{proc.stderr}")
        (root / "modelDescription.xml").write_text(
            _model_description(dm, pvec, outputs, name, guid, description, max_step, stop_time))
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
                       description: str | None, max_step: float, stop_time: float) -> str:
    np_, nx, nu, ny = len(pvec), dm.nx, dm.nu, len(OUTPUT_NAMES)
    sunits = state_units(dm)
    units = sorted({p.unit for p in dm.parameters} | set(sunits) | set(dm.input_units)
                   | set(OUTPUT_UNITS) | {"s"})
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
    unknowns = "\n".join(f"      <Unknown index=\"{index[n]}\"/>" for n in out_names)
    unit_defs = "\n".join(f"    <Unit name={quoteattr(u)}/>" for u in units)
    desc = description or " + ".join(f"{type(c).__name__}({c.name!r})" for c in dm.model.components)
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
