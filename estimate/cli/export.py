"""`slosh export`: a fitted analog as self-contained C, an FMI 2.0 FMU and/or a Python
module of Basilisk slosh effectors.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from analogs import Model
from analogs.errors import InputError
from analogs.vehicle import VehicleFrame, axisymmetric, degrees_of_freedom

from ..outputs import Outputs
from ._cases import add_force, assignments

__all__ = ["add_parser", "run", "export_model"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``export`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "export", help="export a fitted analog as C code, an FMU or Basilisk effectors",
        description="Generate self-contained C (CasADi code generation of rhs, outputs and a "
                    "fixed-step RK4 step; header with state/input/parameter/output order and "
                    "units; fitted values as defaults; Makefile; standalone driver), an "
                    "FMI 2.0 co-simulation FMU and/or a Python module of Basilisk slosh "
                    "effectors from a fit result.")
    p.add_argument("fit", metavar="FIT.json", help="fit result (as written by `slosh fit`) "
                   "or a flat JSON map of parameter values")
    p.add_argument("--out", metavar="DIR", help="folder for the C sources")
    p.add_argument("--fmu", metavar="OUT.fmu", help="write an FMI 2.0 co-simulation FMU")
    p.add_argument("--basilisk", metavar="OUT.py",
                   help="write the analog as Basilisk slosh effectors (sphericalPendulum, "
                        "linearSpringMassDamper; rigid liquid added to the hub): a Python "
                        "module with add_slosh(scObject); needs no Basilisk to write")
    p.add_argument("--tank-position", metavar="X,Y,Z", type=_vector, default=None,
                   help="with --basilisk: the tank origin (tank bottom, on its axis) in the "
                        "spacecraft body frame, m (default 0,0,0)")
    p.add_argument("--tank-axis", metavar="X,Y,Z", type=_vector, default=None,
                   help="with --basilisk: the tank axis in the body frame, pointing from the "
                        "tank bottom to the free surface (default 0,0,1)")
    p.add_argument("--model", default=None,
                   help="model specification, e.g. 'fixed,p1' (default: the fit's model_spec)")
    p.add_argument("--integrator", choices=("rk4",), default="rk4",
                   help="rk4, fixed step (the only integrator that can be generated as C; "
                        "CasADi's adaptive CVODES cannot); --substeps refines it")
    p.add_argument("--substeps", type=int, default=1, help="RK4 substeps per step (default 1)")
    p.add_argument("--interface", choices=("rig", "vehicle"), default="rig",
                   help="rig: lateral rig inputs rig.x, rig.x_dot, rig.x_ddot (default); "
                        "vehicle: tank-frame acceleration, angular velocity and acceleration "
                        "and gravity (analogs.vehicle.VehicleFrame); the lateral fit's "
                        "pendulums become spherical pendulums (same mass, length, height, "
                        "hinge spring and damper), which slosh along tank x and y as in an "
                        "axisymmetric tank")
    p.add_argument("--planar", action="store_true",
                   help="with --interface vehicle: in-plane (x-z) inputs only, planar "
                        "pendulums (no slosh along tank y)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="set a parameter the fit does not give (e.g. p1.hinge_height=0.1, "
                        "needed by torques and by the vehicle interface); repeatable")
    p.add_argument("--name", default="slosh_model", help="C symbol prefix / FMU model identifier")
    p.add_argument("--step", type=float, default=0.01,
                   help="FMU: largest internal RK4 step, s (default 0.01)")
    p.add_argument("--no-build", action="store_true", help="do not compile the C driver")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_force(p)
    p.set_defaults(run=run)


def export_model(spec: str, values: dict[str, float], *, interface: str = "rig",
                 planar: bool = False) -> tuple[Model, dict[str, float]]:
    """The model of ``spec`` for export and the values among ``values`` that it has.

    ``interface="rig"``: a lateral rig with a measured carriage displacement (inputs
    ``rig.x``, ``rig.x_dot``, ``rig.x_ddot``); ``"vehicle"``: the
    :class:`~analogs.vehicle.VehicleFrame` with the analog made three-dimensional for an
    axisymmetric tank (:func:`analogs.vehicle.axisymmetric`: each planar pendulum becomes a
    spherical pendulum, so the slosh responds along tank x and y), or with ``planar`` the
    in-plane (x-z) inputs and the planar analog.

    Raises
    ------
    InputError
        For an unknown interface, or a vehicle analog that cannot be made 3-D.
    """
    from analogs import LateralRig
    from analogs.spec import model_from_spec

    model = model_from_spec(spec, LateralRig(excitation="measured"))
    if interface == "vehicle":
        analog = model.without(model.rig.name)
        if not planar:
            analog = axisymmetric(analog)
        model = (Model((VehicleFrame(planar=planar),)) + analog).validate()
    elif interface != "rig":
        raise InputError(f"interface must be 'rig' or 'vehicle', got {interface!r}")
    names = {p.name for p in model.parameters}
    return model, {k: v for k, v in values.items() if k in names}


def _vector(text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    try:
        if len(parts) != 3:
            raise ValueError
        return tuple(float(x) for x in parts)  # type: ignore[return-value]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three numbers X,Y,Z, got {text!r}") from None


def _print_dof(model: Model) -> None:
    print("  degrees of freedom:")
    for line in degrees_of_freedom(model):
        print(f"    {line}")


def run(args: argparse.Namespace) -> int:
    """Run ``slosh export``; returns the exit status."""
    from derive import derive
    from derive.export_c import c_export_files, export_c, has_c_compiler

    from ..data.models import BASELINE
    from ..fitting.record import fit_notes, fit_spec, read_params

    if not args.out and not args.fmu and not args.basilisk:
        raise InputError("nothing to write: give `--out DIR` for C sources, `--fmu OUT.fmu` "
                         "and/or `--basilisk OUT.py`")
    if (args.tank_position or args.tank_axis) and not args.basilisk:
        raise InputError("`--tank-position` and `--tank-axis` place the tank for `--basilisk`")
    if args.planar and args.interface != "vehicle":
        raise InputError("`--planar` applies to `--interface vehicle` only")
    if args.basilisk and not args.basilisk.endswith(".py"):
        raise InputError(f"--basilisk {args.basilisk}: the Basilisk module's file name must end "
                         "in .py")
    if args.fmu and not has_c_compiler():
        raise InputError(f"--fmu {args.fmu}: an FMU holds a compiled binary and no C compiler was "
                         "found (install gcc, or set CC to one); `--out DIR` writes the C "
                         "sources without one")
    for note in fit_notes(args.fit, force=args.force, what="parameter file"):
        print(f"warning: {note}", file=sys.stderr)
    values = read_params(args.fit) | assignments(args.set)
    spec = args.model or fit_spec(args.fit) or BASELINE
    outputs = Outputs(overwrite=args.overwrite, inputs=[args.fit])
    outputs.folder("--out", args.out, [*c_export_files(args.name).values(), "simulate"])
    outputs.file("--fmu", args.fmu).file("--basilisk", args.basilisk).check()
    model, used = export_model(spec, values, interface=args.interface, planar=args.planar)
    basilisk = None
    if args.basilisk:
        from derive.export_basilisk import basilisk_analog

        basilisk = basilisk_analog(model, values, tank_position=args.tank_position,
                                   tank_axis=args.tank_axis, source=str(args.fit))
    unset = []
    if args.out or args.fmu:
        dm = derive(model)
        pvec = dm.parameter_vector(used)
        unset = [n for n, v in zip(dm.parameter_names, pvec) if math.isnan(v)]
    with outputs.writing() as paths:
        if args.out:
            ex = export_c(dm, paths["--out"], used, substeps=args.substeps, name=args.name,
                          overwrite=True)
            compiler = has_c_compiler()
            if not args.no_build and compiler:
                try:
                    ex.build()
                except RuntimeError as err:
                    raise InputError(f"--out {args.out}: {err}; pass --no-build to write the "
                                     "sources without compiling them") from None
        if args.fmu:
            from derive.fmu import export_fmu

            try:
                export_fmu(dm, paths["--fmu"], used, substeps=args.substeps, max_step=args.step,
                           name=args.name, overwrite=True)
            except RuntimeError as err:  # no compiler, or compiling failed: the compiler's words
                raise InputError(f"--fmu {args.fmu}: {err}") from None
        if basilisk is not None:
            paths["--basilisk"].write_text(basilisk.script(module=Path(args.basilisk).stem))
    if args.out:
        print(f"wrote C export of {spec} ({args.interface} interface) to {args.out}: "
              f"{ex.header.name}, {', '.join(s.name for s in ex.sources)}, {ex.driver.name}, "
              f"{ex.makefile.name}, {ex.parameters_csv.name}")
        _print_dof(model)
        print(f"  states: {', '.join(ex.states)}")
        print(f"  inputs: {', '.join(ex.inputs) or '(none)'}")
        if args.no_build:
            print(f"  sources only (--no-build): build the driver with `make -C {args.out}`")
        elif not compiler:
            print(f"  note: no C compiler found (install gcc, or set CC to one): wrote the "
                  f"sources only, not the driver `{Path(args.out) / 'simulate'}`; build it "
                  f"where a compiler is with `make -C {args.out}`")
        else:
            print(f"  built {Path(args.out) / 'simulate'}")
    if args.fmu:
        print(f"wrote FMU {args.fmu} of {spec} ({args.interface} interface)")
        if not args.out:
            _print_dof(model)
    if basilisk is not None:
        print(f"wrote Basilisk effectors of {spec} to {args.basilisk}: "
              f"{len(basilisk.pendulums)} sphericalPendulum, {len(basilisk.spring_masses)} "
              f"linearSpringMassDamper, {len(basilisk.rigid_masses)} rigid mass(es) for the hub; "
              f"{basilisk.placement}")
        print(f"  use: `import {Path(args.basilisk).stem}` then "
              f"`{Path(args.basilisk).stem}.add_slosh(scObject)` after setting the hub's mass "
              "properties")
        if not args.out and not args.fmu:
            _print_dof(axisymmetric(model.without(model.rig.name)))
    if unset:
        print(f"  note: no value for {', '.join(unset)}: outputs that need them are NaN in C "
              "and left out of the FMU")
    return 0
