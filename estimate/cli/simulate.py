"""``slosh simulate``: the analog's response to a test case's excitation."""

from __future__ import annotations

import argparse
import sys

from analogs.errors import InputError

from ..outputs import Outputs
from ._cases import add_force, add_strict

__all__ = ["add_parser"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "simulate", help="simulate a model for a test case's excitation",
        description="Simulate the analog model for the excitation of CASE.toml and write "
                    "time and every channel the case measures to a CSV file: time,force (N) "
                    "on the lateral rig, time,force_x,...,torque_z (N, N m) on the spinning "
                    "rig. The analog starts as `[test] initial_state` says (a \"free\" start "
                    "is read from a fit result given as --params).")
    p.add_argument("case", help="test case file (TOML)")
    p.add_argument("--params", required=True,
                   help="JSON parameter values: a flat map {\"p1.mass\": 1.3, ...} or a fit result")
    p.add_argument("--out", required=True, help="output CSV (time and the measured channels)")
    p.add_argument("--model", default=None,
                   help="model specification, e.g. 'fixed,p1,p2' (default: the fit's model "
                        "when --params is a fit result, else fixed,p1 with hinge spring and "
                        "damper)")
    p.add_argument("--integrator", choices=("rk4", "adaptive"), default="rk4",
                   help="fixed-step RK4 on the sample grid (default) or CVODES")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    add_force(p)
    add_strict(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from derive import RK4, Adaptive

    from ..data import load_case
    from ..data.experiment import experiment
    from ..data.models import BASELINE, model_from_spec
    from ..fitting.record import fit_notes, fit_spec, fitted_initial_state, read_params

    outputs = Outputs(overwrite=args.overwrite, inputs=[args.case, args.params])
    outputs.file("--out", args.out).check()
    case = load_case(args.case, strict=args.strict)
    for note in fit_notes(args.params, force=args.force, what="parameter file"):
        print(f"warning: {note}", file=sys.stderr)
    params = read_params(args.params)
    x0 = fitted_initial_state(args.params, case) if case.test.initial_state == "free" else None
    spec = args.model or fit_spec(args.params) or BASELINE
    exp = experiment(case, model_from_spec(spec, case))
    for name, value in exp.fixed.items():  # the rig is the case file's, not the fit's
        given = params.pop(name, value)
        if given != value:
            print(f"note: {args.params} gives {name} = {given:.6g}; the case file's "
                  f"{value:.6g} is used", file=sys.stderr)
    integrator = RK4() if args.integrator == "rk4" else Adaptive()
    sim = exp.simulate(params, integrator=integrator, x0=x0)
    # every channel the case measures; the lateral force keeps its historical name
    columns = {"time": sim.time, **({"force": sim.output("force_x")} if exp.channels == ("force_x",)
                                    else {c: sim.output(c) for c in exp.channels})}
    table = np.column_stack(list(columns.values()))
    bad = np.flatnonzero(~np.all(np.isfinite(table), axis=1))
    if bad.size:
        raise InputError(f"the simulation is not finite from t = {sim.time[bad[0]]:.6g} s on "
                         f"({bad.size} of {sim.time.size} rows): check the parameter values in "
                         f"{args.params} and the rig values of {args.case}; {args.out} was not "
                         "written")
    with outputs.writing() as paths:
        np.savetxt(paths["--out"], table, delimiter=",", header=",".join(columns), comments="",
                   fmt="%.12g")
    print(f"wrote {args.out} ({sim.time.size} samples, model {', '.join(exp.model.names)})")
    return 0
