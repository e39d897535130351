"""``slosh design``: recommend the next test, the drive that best pins down what the data
cannot yet separate."""

from __future__ import annotations

import argparse
import re
import sys

from analogs.errors import InputError

from ..outputs import Outputs, json_text
from ._cases import add_force, add_strict

__all__ = ["add_parser", "parse_duration"]


def parse_duration(text: str) -> float:
    """``"60"``, ``"60s"``, ``"1.5min"`` -> seconds."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(s|min)?\s*", text)
    if not m or not float(m.group(1)) > 0:
        raise InputError(f"--budget: expected a positive duration such as `60s` or `2min`, "
                         f"found {text!r}")
    return float(m.group(1)) * (60.0 if m.group(2) == "min" else 1.0)


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "design", help="recommend the next test: the drive that best pins down the analog",
        description="Search the drives the rig can run (steady sine, stepped sine, amplitude "
                    "steps, linear chirp; on the spinning rig spin rate, coning frequency and "
                    "cone angle) within `[rig.limits]` of the case file, and recommend the one "
                    "that narrows the intervals of the target parameters most, with the "
                    "records already fitted counted in (or that best tells two competing "
                    "models of a diagnosis apart).")
    p.add_argument("fit", help="the fit of the records run so far (JSON of `slosh fit`)")
    p.add_argument("case", help="case file of the rig, with [rig.limits] (TOML)")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--target", default=None,
                      help="comma-separated parameters to pin down, e.g. p1.mass,fixed.mass "
                           "(default: those the fit leaves confounded)")
    what.add_argument("--discriminate", default=None, metavar="DIAG.json",
                      help="a diagnosis (JSON of `slosh diagnose`): find the drive that best "
                           "tells its baseline and final models apart")
    p.add_argument("--budget", default=None,
                   help="rig time of the next record, e.g. 60s or 2min (default: "
                        "[rig.limits] duration)")
    p.add_argument("--criterion", choices=("D", "A"), default="D",
                   help="D-optimal (smallest joint confidence region of the targets, default) "
                        "or A-optimal (smallest sum of their relative variances)")
    p.add_argument("--max-swing", type=float, default=None,
                   help="largest predicted pendulum swing of the drive [rad] (default 0.35)")
    p.add_argument("--goal", type=float, default=None,
                   help="95 %% half-width a target must reach, as a fraction of its value "
                        "(default 0.05): the report says why a target misses it")
    p.add_argument("--families", default=None,
                   help="lateral drive families to search, comma-separated: sine, stepped, "
                        "steps, chirp (default: all)")
    p.add_argument("--json", dest="json_out", required=True, help="write the design as JSON")
    p.add_argument("--drive", default=None,
                   help="write the recommended drive as CSV at the rig's rate (default: the "
                        "JSON's name with `_drive.csv`)")
    p.add_argument("--plot", default=None, help="write the design plot (PNG)")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_force(p)
    add_strict(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ..data import load_case
    from ..design import GOAL, MAX_SWING, DesignProblem, design, discrimination
    from ..fitting.record import fit_notes

    drive_out = args.drive or str(Path(args.json_out).with_name(
        Path(args.json_out).stem + "_drive.csv"))
    inputs = [args.fit, args.case] + ([args.discriminate] if args.discriminate else [])
    outputs = Outputs(overwrite=args.overwrite, inputs=inputs)
    outputs.file("--json", args.json_out).file("--drive", drive_out).file("--plot", args.plot)
    outputs.check()
    for note in fit_notes(args.fit, force=args.force):
        print(f"warning: {note}", file=sys.stderr)
    case = load_case(args.case, strict=args.strict)
    duration = parse_duration(args.budget) if args.budget else None
    max_swing = MAX_SWING if args.max_swing is None else args.max_swing
    families = tuple(f.strip() for f in args.families.split(",") if f.strip()) \
        if args.families else None
    if args.discriminate:
        result = discrimination(args.discriminate, case, fit=args.fit, duration=duration,
                                max_swing=max_swing, families=families)
    else:
        targets = [t.strip() for t in args.target.split(",") if t.strip()] if args.target else None
        problem = DesignProblem.build(args.fit, case, targets=targets, criterion=args.criterion,
                                      duration=duration, max_swing=max_swing,
                                      goal=GOAL if args.goal is None else args.goal)
        result = design(problem, families=families)
    print(result.summary())
    for w in result.warnings():
        print(f"warning: {w}")
    with outputs.writing() as paths:
        paths["--json"].write_text(json_text(result.to_dict(
            drive_file=str(Path(drive_out).resolve()))))
        result.write_drive(paths["--drive"])
        if args.plot:
            result.plot(paths["--plot"])
    return 0
