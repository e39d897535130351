"""``slosh diagnose``: what the baseline analog gets wrong, its cause, and the gain."""

from __future__ import annotations

import argparse

from ..outputs import Outputs, json_text
from ._cases import add_decimate, add_strict, load_cases
from ._cases import positive_hz as _positive_hz

__all__ = ["add_parser"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "diagnose", help="find what the baseline analog misses, name the cause, extend the model")
    # the description names the families' causes: importing them imports the fitting code
    # (SciPy's signal package, about a second), which only `slosh diagnose --help` needs
    plain = p.format_help

    def format_help() -> str:
        if p.description is None:
            from ..diagnosis.families import CAUSES

            p.description = (
                "Fit the baseline analog (fixed mass + first-mode pendulum, no hinge spring), "
                "collect the residual evidence, try the candidate families "
                f"({', '.join(CAUSES)}) and accept those that cut the held-out residual "
                "significantly.")
        return plain()

    p.format_help = format_help
    p.add_argument("cases", nargs="+", help="test case files (TOML)")
    p.add_argument("--json", dest="json_out", required=True, help="write the diagnosis as JSON")
    p.add_argument("--report", default=None, help="write the report folder (plots, Markdown)")
    p.add_argument("--motion-band", type=_positive_hz, default=None, metavar="HZ",
                   help="highest frequency of the carriage motion (Hz): sets the estimated "
                        "carriage spline's knot spacing and the filtered input's displacement "
                        "cutoff; default: the case's [test] motion_band_hz, else read from the "
                        "displacement (a carriage at rest needs none)")
    add_decimate(p)
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_strict(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import sys

    from ..diagnosis.report import REPORT_FILES, summary, write_report
    from ..diagnosis.search import diagnose

    outputs = Outputs(overwrite=args.overwrite, inputs=args.cases)
    outputs.file("--json", args.json_out).folder("--report", args.report, REPORT_FILES).check()
    cases, notes = load_cases(args.cases, prediction=True, strict=args.strict,
                              motion_band_hz=args.motion_band, shared=True,
                              decimate=args.decimate)
    for w in notes:
        print(f"warning: {w}", file=sys.stderr)
    d = diagnose(cases)
    data = d.to_dict()
    data["notes"] = [*notes, *data.get("notes", ())]
    with outputs.writing() as paths:
        paths["--json"].write_text(json_text(data))
        if args.report:
            write_report(d, paths["--report"], overwrite=True)
    text = summary(d)
    print(text.split("## The baseline's residual")[0].strip())
    return 0
