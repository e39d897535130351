"""``slosh diagnose``: what the baseline analog gets wrong, its cause, and the gain."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ._outputs import refuse_existing

__all__ = ["add_parser"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "diagnose", help="find what the baseline analog misses, name the cause, extend the model",
        description="Fit the baseline analog (fixed mass + first-mode pendulum, no hinge spring), "
                    "collect the residual evidence, try candidate extensions (slosh mode, "
                    "quadratic damping, diaphragm stiffness, sensor delay, rig friction) and "
                    "accept those that cut the held-out residual significantly.")
    p.add_argument("cases", nargs="+", help="test case files (TOML)")
    p.add_argument("--json", dest="json_out", required=True, help="write the diagnosis as JSON")
    p.add_argument("--report", default=None, help="write the report folder (plots, Markdown)")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..data import load_case
    from ..diagnosis.report import _json_default, summary, write_report
    from ..diagnosis.search import diagnose

    out = Path(args.json_out)
    refuse_existing([out], args.overwrite)
    d = diagnose([load_case(c) for c in args.cases])
    out.write_text(json.dumps(d.to_dict(), indent=2, default=_json_default))
    if args.report:
        write_report(d, args.report, overwrite=args.overwrite)
    text = summary(d)
    print(text.split("## What the baseline gets wrong")[0].strip())
    return 0
