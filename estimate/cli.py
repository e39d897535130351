"""The ``slosh`` command line: ``simulate``, ``tank``, ``fit``, ``diagnose``."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from ._outputs import refuse_existing

__all__ = ["main"]


def _add_simulate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "simulate", help="simulate a model for a test case's excitation",
        description="Simulate the analog model for the excitation of CASE.toml and write "
                    "time,force (N) to a CSV file.")
    p.add_argument("case", help="test case file (TOML)")
    p.add_argument("--params", required=True,
                   help="JSON parameter values: a flat map {\"p1.mass\": 1.3, ...} or a fit result")
    p.add_argument("--out", required=True, help="output CSV (time,force)")
    p.add_argument("--model", default=None,
                   help="model specification, e.g. 'fixed,p1,p2' (default: fixed,p1 with hinge "
                        "spring and damper)")
    p.add_argument("--integrator", choices=("rk4", "adaptive"), default="rk4",
                   help="fixed-step RK4 on the sample grid (default) or CVODES")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.set_defaults(run=_run_simulate)


def _run_simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from derive import RK4, Adaptive

    from .case import load_case
    from .experiment import experiment
    from .models import BASELINE, model_from_spec
    from .params_io import read_params

    out = Path(args.out)
    refuse_existing([out], args.overwrite)
    case = load_case(args.case)
    params = read_params(args.params)
    exp = experiment(case, model_from_spec(args.model or BASELINE, case))
    integrator = RK4() if args.integrator == "rk4" else Adaptive()
    sim = exp.simulate(params, integrator=integrator)
    columns = {"time": sim.time, "force": sim.output("force_x")}
    np.savetxt(out, np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="", fmt="%.12g")
    print(f"wrote {out} ({sim.time.size} samples, model {', '.join(exp.model.names)})")
    return 0


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="slosh", description="Fuel-slosh tank tests to mechanical analog models.")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_simulate(sub)
    from . import _cli_fit

    _cli_fit.add_parser(sub)
    from . import _cli_diagnose

    _cli_diagnose.add_parser(sub)
    try:
        from . import _cli_tank
    except ImportError:  # pragma: no cover - the tank module is optional while it is built
        _cli_tank = None
    if _cli_tank is not None:
        _cli_tank.add_parser(sub)
    from . import _cli_export, _cli_montecarlo

    _cli_export.add_parser(sub)
    _cli_montecarlo.add_parser(sub)
    from . import _cli_ntc

    _cli_ntc.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``slosh`` console script; returns the exit status."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    args = _parser().parse_args(argv)
    from analogs import ModelError
    from derive import ParameterError

    from .case import CaseError

    try:
        status = (getattr(args, "run", None) or args.func)(args)
    except (CaseError, ModelError, ParameterError, FileNotFoundError, FileExistsError,
            ValueError, KeyError) as err:
        msg = err.args[0] if isinstance(err, KeyError) and err.args else str(err)
        print(f"slosh {args.command}: error: {msg}", file=sys.stderr)
        return 2
    return int(status or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
