"""Export a derived model as self-contained C: CasADi-generated ``rhs``, ``outputs`` and
fixed-step RK4 ``step`` functions, a documented header, a standalone driver and a Makefile.

The generated code needs only a C99 compiler and ``<math.h>`` at run time (no CasADi, no
Python). It compiles warning-free with ``gcc -std=c99 -Wall -Wextra -O2``: CasADi's
generated functions take work arguments (``iw``, ``w``, ``mem``) that simple functions do
not use, so :func:`export_c` adds ``(void)`` casts of every parameter to each generated
function definition instead of asking users to pass ``-Wno-unused-parameter``.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from analogs.errors import InputError
from analogs.model import Model
from analogs.vehicle import degrees_of_freedom

from ._c_templates import DRIVER, HEADER, MAKEFILE, WRAPPER
from ._compile import c_compiler
from .derived import OUTPUT_NAMES, OUTPUT_UNITS, DerivedModel
from .simulate import rk4_step

__all__ = ["CExport", "CFLAGS", "c_export_files", "c_functions", "export_c", "has_c_compiler",
           "run_driver", "state_units", "write_input_csv"]

#: Flags the exported code is guaranteed to compile cleanly with.
CFLAGS = ("-std=c99", "-Wall", "-Wextra", "-O2")

def state_units(dm: DerivedModel) -> tuple[str, ...]:
    """Units of the states as the components declare them (:attr:`DerivedModel.state_units`)."""
    return dm.state_units


def c_functions(dm: DerivedModel, *, substeps: int = 1, name: str = "slosh_model"
                ) -> dict[str, ca.Function]:
    """The four CasADi SX functions that are generated as C.

    ``<name>_cg_rhs(x, u, p, t)``, ``<name>_cg_outputs(x, u, p, t)``,
    ``<name>_cg_step(x, u, p, t, h)`` (inputs held over the step) and
    ``<name>_cg_step_stages(x, U, p, t, h)`` (``U`` the inputs at the ``2 substeps + 1``
    stage times, stacked stage by stage, as :func:`derive.simulate` with ``RK4(substeps)``
    uses them).
    """
    nstage = 2 * substeps + 1
    x = ca.SX.sym("x", dm.nx)
    u = ca.SX.sym("u", dm.nu)
    Uv = ca.SX.sym("U", dm.nu * nstage)
    p = ca.SX.sym("p", len(dm.parameter_names))
    t = ca.SX.sym("t")
    h = ca.SX.sym("h")
    step = rk4_step(dm, substeps)
    shape = step.size_in(1)  # (nu, nstage) or (nu * nstage, 1): same column-major data
    zoh = step(x, ca.reshape(ca.repmat(u, 1, nstage), shape), p, t, h)
    staged = step(x, ca.reshape(Uv, shape), p, t, h)
    return {
        "rhs": ca.Function(f"{name}_cg_rhs", [x, u, p, t], [dm.rhs(x, u, p, t)]),
        "outputs": ca.Function(f"{name}_cg_outputs", [x, u, p, t], [dm.outputs(x, u, p, t)]),
        "step": ca.Function(f"{name}_cg_step", [x, u, p, t, h], [zoh]),
        "step_stages": ca.Function(f"{name}_cg_step_stages", [x, Uv, p, t, h], [staged]),
    }


@dataclass(frozen=True)
class CExport:
    """Files of an exported model (all in :attr:`folder`) and its interface order.

    Attributes
    ----------
    folder : Path
        The folder of the export.
    name : str
        The C symbol prefix.
    header, sources, driver, makefile, parameters_csv : Path
        The header, the C sources, the standalone driver, its Makefile and the CSV of the
        parameters' values, units and descriptions.
    states, inputs, parameters, outputs : tuple of str
        The names in the order of the C arrays.
    substeps : int
        RK4 substeps per step of the generated integrator.
    """

    folder: Path
    name: str
    header: Path
    sources: tuple[Path, ...]
    driver: Path
    makefile: Path
    parameters_csv: Path
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    substeps: int

    def build(self, *, cc: str | None = None, extra_flags: tuple[str, ...] = ("-Werror",),
              executable: str = "simulate") -> Path:
        """Compile the standalone driver with ``cc`` (default: ``$CC``, ``cc`` or ``gcc``)
        and :data:`CFLAGS` plus ``extra_flags`` into ``executable`` (a file name in
        :attr:`folder`, default ``"simulate"``); returns the executable's path.

        Raises
        ------
        RuntimeError
            When no C compiler is found, or compiling fails (with the compiler's messages).
        """
        cc = cc or c_compiler()
        if cc is None:
            raise RuntimeError("no C compiler found: set `CC` or install gcc to build the "
                               "exported model")
        exe = self.folder / executable
        cmd = [cc, *CFLAGS, *extra_flags, "-o", str(exe), str(self.driver),
               *map(str, self.sources), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=self.folder)
        if proc.returncode != 0 or proc.stderr.strip():
            if proc.returncode != 0:
                raise RuntimeError(f"compiling {self.name} failed:\n{' '.join(cmd)}\n{proc.stderr}")
            raise RuntimeError(f"compiling {self.name} gave warnings:\n{proc.stderr}")
        return exe


def _c_name(name: str) -> str:
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise InputError(f"name must be a C identifier (letters, digits, underscores), got {name!r}")
    return name


def _quote(items) -> str:
    return ", ".join([f'"{s}"' for s in items] + ["0"])


def _c_double(v: float) -> str:
    if math.isnan(v):
        return "NAN"
    if math.isinf(v):
        return "INFINITY" if v > 0 else "-INFINITY"
    return repr(float(v))


def _table(rows: list[tuple[str, ...]]) -> str:
    if not rows:
        return " *   (none)"
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join(" *   " + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip()
                     for r in rows)


_FUNC_DEF = re.compile(r"^(?!\s)(?![#/])[^;=()]*?\b\w+\s*\(([^()]*)\)\s*\{\s*$")


def _silence_unused_parameters(code: str) -> str:
    """Add ``(void)name;`` for every parameter of every function definition, so that
    generated functions that ignore their work arrays compile without -Wunused-parameter."""
    out = []
    for line in code.splitlines():
        out.append(line)
        m = _FUNC_DEF.match(line)
        if not m or m.group(1).strip() in ("", "void"):
            continue
        names = []
        for param in m.group(1).split(","):
            ident = re.findall(r"\w+", param)
            if ident:
                names.append(ident[-1])
        out.append("  " + " ".join(f"(void){n};" for n in names))
    return "\n".join(out) + "\n"


def c_export_files(name: str = "slosh_model") -> dict[str, str]:
    """The files :func:`export_c` writes for the symbol prefix ``name``, by role."""
    name = _c_name(name)
    return {"header": f"{name}.h", "wrapper": f"{name}.c", "cg_c": f"{name}_casadi.c",
            "cg_h": f"{name}_casadi.h", "driver": "simulate_main.c", "makefile": "Makefile",
            "params": "parameters.csv"}


def export_c(
    model: DerivedModel | Model,
    folder: str | os.PathLike,
    params: Mapping[str, float] | None = None,
    *,
    substeps: int = 1,
    name: str = "slosh_model",
    description: str | None = None,
    overwrite: bool = False,
) -> CExport:
    """Write the model as C sources, header, driver and Makefile into ``folder``.

    Parameters
    ----------
    model : DerivedModel or analogs.Model
        The model (derived first when a ``Model`` is given).
    folder : path
        Output folder; created if needed. Existing files of the export are replaced only
        with ``overwrite=True``.
    params : mapping, optional
        Parameter values compiled in as defaults (e.g. fitted values), over the declared
        defaults; checked against bounds. Parameters nothing needs may stay NaN.
    substeps : int, default 1
        RK4 steps per call of ``<name>_step``.
    name : str, default ``"slosh_model"``
        Prefix of the C symbols and file names (a C identifier).
    description : str, optional
        One line for the header (default: the model's components).

    Returns
    -------
    CExport
        Paths and the interface order; :meth:`CExport.build` compiles the driver.

    Examples
    --------
    >>> from analogs import LateralRig, FixedMass, Pendulum
    >>> from derive.export_c import export_c
    >>> import tempfile
    >>> ex = export_c(LateralRig() + FixedMass("fixed") + Pendulum("p1"), tempfile.mkdtemp(),
    ...               {"rig.dry_mass": 1.2, "fixed.mass": 1.5, "p1.mass": 1.3, "p1.length": 0.057})
    >>> ex.header.name
    'slosh_model.h'
    """
    if isinstance(model, Model):
        from ._derive import derive

        model = derive(model)
    dm = model
    name = _c_name(name)
    if int(substeps) != substeps or substeps < 1:
        raise InputError(f"substeps must be a positive integer, got {substeps!r}")
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    files = {k: folder / f for k, f in c_export_files(name).items()}
    existing = [str(p) for p in files.values() if p.exists()]
    if existing and not overwrite:
        raise FileExistsError(f"{', '.join(existing)} exist; pass overwrite=True (`--overwrite`) "
                              "to replace them")
    pvec = dm.parameter_vector(params)
    fns = c_functions(dm, substeps=substeps, name=name)

    gen = ca.CodeGenerator(f"{name}_casadi.c", {"with_header": True})
    for fn in fns.values():
        gen.add(fn)
    gen.generate(str(folder) + os.sep)
    files["cg_c"].write_text(_silence_unused_parameters(files["cg_c"].read_text()))

    sz = {k: max(1, *(getattr(f, f"sz_{k}")() for f in fns.values()))
          for k in ("arg", "res", "iw", "w")}
    sz["arg"] = max(sz["arg"], 5)
    sunits = state_units(dm)
    params_meta = dm.parameters
    NAME = name.upper()
    fields = dict(
        name=name, NAME=NAME, nx=dm.nx, nu=dm.nu, np=len(pvec), ny=len(OUTPUT_NAMES),
        substeps=substeps, nstages=2 * substeps + 1,
        model=description or " + ".join(f"{type(c).__name__}({c.name!r})"
                                        for c in dm.model.components),
        dof_table="\n".join(f" *   {line}" for line in degrees_of_freedom(dm.model)) or " *   (none)",
        state_table=_table([(f"x[{i}]", s, u) for i, (s, u) in enumerate(zip(dm.states, sunits))]),
        input_table=_table([(f"u[{i}]", s, u) for i, (s, u) in enumerate(zip(dm.inputs, dm.input_units))]),
        param_table=_table([(f"p[{i}]", pm.name, pm.unit, _c_double(v), pm.description)
                            for i, (pm, v) in enumerate(zip(params_meta, pvec))]),
        output_table=_table([(f"y[{i}]", s, u) for i, (s, u) in enumerate(zip(OUTPUT_NAMES, OUTPUT_UNITS))]),
        state_names=_quote(dm.states), state_units=_quote(sunits),
        input_names=_quote(dm.inputs), input_units=_quote(dm.input_units),
        param_names=_quote(dm.parameter_names), param_units=_quote(p.unit for p in params_meta),
        output_names=_quote(OUTPUT_NAMES), output_units=_quote(OUTPUT_UNITS),
        param_values=", ".join([_c_double(v) for v in pvec] + ["0.0"]),
        sz_arg=sz["arg"], sz_res=max(sz["res"], 1), sz_iw=sz["iw"], sz_w=sz["w"],
        input_header="".join(f",{s}" for s in dm.inputs),
    )
    files["header"].write_text(HEADER.substitute(fields))
    files["wrapper"].write_text(WRAPPER.substitute(fields))
    files["driver"].write_text(DRIVER.substitute(fields))
    files["makefile"].write_text(MAKEFILE.substitute(fields))
    lines = ["name,value,unit"] + [f"{pm.name},{_csv_value(v)},{pm.unit}"
                                   for pm, v in zip(params_meta, pvec) if not math.isnan(v)]
    files["params"].write_text("\n".join(lines) + "\n")
    return CExport(
        folder=folder, name=name, header=files["header"],
        sources=(files["wrapper"], files["cg_c"]), driver=files["driver"],
        makefile=files["makefile"], parameters_csv=files["params"],
        states=dm.states, inputs=dm.inputs, parameters=dm.parameter_names,
        outputs=OUTPUT_NAMES, substeps=substeps,
    )


def _csv_value(v: float) -> str:
    return repr(float(v))


def write_input_csv(path: str | os.PathLike, time: np.ndarray, inputs: np.ndarray,
                    names: tuple[str, ...]) -> Path:
    """Write ``time`` (n,) [s] and ``inputs`` (n, nu) as the driver's input CSV at ``path``
    (full precision), the columns headed ``time`` and the input ``names``; returns the path."""
    path = Path(path)
    data = np.column_stack([np.asarray(time, float).ravel(),
                            np.asarray(inputs, float).reshape(len(time), -1)])
    np.savetxt(path, data, delimiter=",", header=",".join(("time", *names)), comments="",
               fmt="%.17g")
    return path


def run_driver(exe: str | os.PathLike, input_csv: str | os.PathLike, output_csv: str | os.PathLike,
               *, params_csv: str | os.PathLike | None = None, stages: bool = False
               ) -> np.ndarray:
    """Run the built driver ``exe`` on ``input_csv`` (:func:`write_input_csv`), writing
    ``output_csv``; ``params_csv`` overrides the parameter values built in, ``stages`` asks
    for the RK4 stage values too. Returns the output CSV as an array (time, states,
    outputs); raises RuntimeError naming the command when the driver fails."""
    cmd = [str(exe)]
    if params_csv is not None:
        cmd += ["--params", str(params_csv)]
    if stages:
        cmd.append("--stages")
    cmd += [str(input_csv), str(output_csv)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr}")
    return np.loadtxt(output_csv, delimiter=",", skiprows=1, ndmin=2)


def has_c_compiler() -> bool:
    """True when a C compiler is available (``$CC``, ``cc`` or ``gcc``)."""
    return c_compiler() is not None or shutil.which("gcc") is not None

