"""``slosh compare``: two or more fit records side by side.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).
"""

from __future__ import annotations

import argparse

from ..outputs import Outputs, json_text

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``compare`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "compare", help="compare fit results: parameters and intervals side by side",
        description="Every parameter and derived quantity of two or more fit records (the "
                    "JSON of `slosh fit --json`) with its 95 %% interval, side by side, and "
                    "each fit's difference from the first in units of their combined standard "
                    "error, sqrt(se_a^2 + se_b^2): a rerun, another fill, another input mode "
                    "or model.")
    p.add_argument("fits", nargs="+", metavar="FIT.json",
                   help="fit records (as written by `slosh fit --json`); the first is the "
                        "reference of the differences")
    p.add_argument("--json", metavar="OUT.json", help="write the comparison as JSON")
    p.add_argument("--plot", metavar="OUT.png",
                   help="plot each quantity's estimates with their 95 %% intervals")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run ``slosh compare``; returns the exit status."""
    from analogs.errors import InputError

    from ..fitting.record import compare_fits, read_fit

    if len(args.fits) < 2:
        raise InputError(f"give at least two fit records to compare, got {len(args.fits)}")
    outputs = Outputs(overwrite=args.overwrite, inputs=args.fits)
    outputs.file("--json", args.json).file("--plot", args.plot).check()
    comparison = compare_fits([read_fit(f) for f in args.fits])
    print(comparison.report())
    with outputs.writing() as paths:
        if args.json:
            paths["--json"].write_text(json_text(comparison.to_dict()))
        if args.plot:
            comparison.plot(paths["--plot"])
    return 0
