"""`slosh montecarlo`: simulate a fitted analog for parameter draws from its covariance.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from analogs.errors import InputError

from ..outputs import Outputs, json_text
from ._cases import add_force, add_strict

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``montecarlo`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "montecarlo", help="Monte Carlo of a fitted analog over its parameter uncertainty",
        description="Draw parameters from the fit's covariance (truncated to the bounds), "
                    "simulate the case's excitation for every draw on a Dask cluster (embedded "
                    "local cluster by default) and write percentile envelopes of the force and "
                    "summaries of derived quantities (JSON + plot).")
    p.add_argument("fit", metavar="FIT.json", help="fit result written by `slosh fit`")
    p.add_argument("case", metavar="CASE.toml", help="test case whose excitation drives the model")
    p.add_argument("--samples", type=int, required=True, help="number of draws")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help="Dask scheduler of an existing cluster, e.g. tcp://host:8786 "
                            "(default: an embedded local cluster)")
    where.add_argument("--local", action="store_true", help="run in this process, no Dask")
    p.add_argument("--workers", type=int, default=None,
                   help="workers of the embedded local cluster (default: CPU count)")
    p.add_argument("--batch-size", type=int, default=256, help="draws per task (default 256)")
    p.add_argument("--model", default=None, help="model specification (default: the fit's)")
    p.add_argument("--out", metavar="DIR", default="montecarlo",
                   help="output folder for montecarlo.json and envelope.png (default ./montecarlo)")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_force(p)
    add_strict(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run ``slosh montecarlo``; returns the exit status."""
    from ..analysis.montecarlo import monte_carlo, read_fit
    from ..data import load_case
    from ..data.experiment import experiment
    from ..data.models import model_from_spec
    from ..executor import executor_for
    from ..fitting.record import fit_notes

    if args.samples < 1:
        raise InputError(f"--samples must be at least 1, got {args.samples}")
    out = Path(args.out)
    files = {"montecarlo.json": out / "montecarlo.json", "envelope.png": out / "envelope.png"}
    outputs = Outputs(overwrite=args.overwrite, inputs=[args.fit, args.case])
    for name, path in files.items():
        outputs.file(f"--out {name}", path, new_folder=True)
    outputs.check()
    for note in fit_notes(args.fit, force=args.force):
        print(f"warning: {note}", file=sys.stderr)
    fit = read_fit(args.fit)
    held = [n for n in fit.estimated if n not in fit.draw_names]
    if held:
        print(f"warning: {args.fit}: {', '.join(f'`{n}`' for n in held)} ended on a bound "
              "and the record says nothing of how far the data allow it off the bound (a "
              "record of an older version, or an estimate the data do not determine): the "
              "draws hold it at its value, so the envelope can be narrower than the fit's "
              "95 % intervals", file=sys.stderr)
    for label, _ in fit.to_modes:
        print(f"note: {args.fit}: half the draws are moved to the refit with {label} (a "
              "pendulum far heavier than its tank mode: the record may not hold it), as the "
              "fit's intervals reach", file=sys.stderr)
    case = load_case(args.case, strict=args.strict)
    exp = experiment(case, model_from_spec(args.model or fit.model_spec, case))
    with executor_for(args.scheduler, local=args.local, n_workers=args.workers) as ex:
        res = monte_carlo(exp.derived, case.time, exp.excitation, fit, args.samples,
                          fixed=exp.fixed, seed=args.seed, executor=ex,
                          batch_size=args.batch_size)
    data = {"fit": str(args.fit), "case": str(args.case), **res.to_json()}
    with outputs.writing() as paths:
        paths["--out montecarlo.json"].write_text(json_text(data, indent=1))
        res.plot(paths["--out envelope.png"], measured=_measured(exp, res))
    print(res.report())
    print(f"wrote {files['montecarlo.json']} and {files['envelope.png']}")
    return 0


def _measured(exp, res):
    """The case's measurement of the plotted output, low-passed as the fit saw it (the
    10 Hz force filter), or None when the case does not measure it."""
    from ..data.signals import lowpass
    from ..fitting.strategies import FILTERED_FORCE_CUTOFF_HZ

    raw = exp.case.channels.get(next(iter(res.outputs)))
    if raw is None:
        return None
    return lowpass(exp.case.time, raw, cutoff_hz=FILTERED_FORCE_CUTOFF_HZ)
