"""``slosh fit``: estimate analog parameters from one or more test cases."""

from __future__ import annotations

import argparse

from ..outputs import Outputs
from ._cases import add_decimate, add_strict, load_cases
from ._cases import positive_hz as _positive_hz

__all__ = ["add_parser"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "fit", help="estimate analog parameters from test cases",
        description="Fit the analog model to the measured force of one or more cases (shared "
                    "physical parameters, per-case crank corrections) with IPOPT.")
    p.add_argument("cases", nargs="+", help="test case files (TOML)")
    p.add_argument("--model", default=None,
                   help="model specification: comma-separated `fixed` (fixed mass) and `pN`, "
                        "N from 1 to 6 (pendulum of slosh mode N with hinge spring and damper; "
                        "spherical on the spinning rig), each pendulum with optional modifiers "
                        "`:nospring`, `:quadratic` (adds a quadratic damper), `:diaphragm` "
                        "(adds a diaphragm spring); spinning rig: `rotor` or `rN`; e.g. "
                        "'fixed,p1:nospring,p2:quadratic' (default: fixed,p1)")
    p.add_argument("--transcription", choices=("multiple_shooting", "collocation"),
                   default="multiple_shooting",
                   help="how the equations of motion enter the NLP, whose variables include "
                        "the states at every sample: multiple shooting (continuity after an "
                        "RK4 step per sample interval, default) or direct collocation (Radau "
                        "degree-3 polynomials per sample interval)")
    p.add_argument("--input", choices=("estimated", "filtered"), default=None,
                   help="a measured carriage displacement is estimated with the parameters "
                        "(default) or smoothed and differentiated beforehand (default with "
                        "--cost abs)")
    p.add_argument("--cost", choices=("squared", "abs"), default="squared",
                   help="sum of squared force residuals (default), or 'abs': "
                        "sum((|measured| - |simulated|)^2), sample by sample, blind to the "
                        "force's sign (the classical workflow's cost; filtered input)")
    p.add_argument("--channel-offsets", choices=("none", "offset", "drift"), default="none",
                   help="estimate a zero offset ('offset') or an offset and a linear drift "
                        "('drift') of every measured channel with the parameters, per case "
                        "(a transducer that is not zeroed or drifts); default: none")
    p.add_argument("--json", dest="json_out", default=None, help="write the result as JSON")
    p.add_argument("--plot", default=None, help="write the fit plots (PNG) of the first case")
    p.add_argument("--report", nargs="?", const="-", default=None, metavar="FILE.md",
                   help="print the full text fit report; with a file name, write the report "
                        "as Markdown there instead (with the provenance: versions, date, "
                        "each data file's SHA-256, the options)")
    p.add_argument("--motion-band", type=_positive_hz, default=None, metavar="HZ",
                   help="highest frequency of the carriage motion (Hz): sets the estimated "
                        "carriage spline's knot spacing and the filtered input's displacement "
                        "cutoff; default: the case's [test] motion_band_hz, else read from the "
                        "displacement (a carriage at rest needs none)")
    add_decimate(p)
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_strict(p)
    p.set_defaults(run=run)


#: Parsed options that are not options of the fit (the command's wiring).
_NOT_OPTIONS = ("run", "command")


def _report_file(args: argparse.Namespace) -> str | None:
    """The Markdown report file of ``--report FILE.md`` (None: print, or no report)."""
    from pathlib import Path

    from analogs.errors import InputError

    report = args.report
    if report in (None, "-"):
        return None
    if Path(report).suffix.lower() == ".toml":  # `--report A1.toml`: the case, taken by --report
        raise InputError(f"--report {report}: a case file where the report file was expected; "
                         "give the report a .md name (`--report A1_fit.md`), or put `--report` "
                         "after the case files")
    return report


def run(args: argparse.Namespace) -> int:
    import sys

    from ..data.models import BASELINE, model_from_spec

    report_file = _report_file(args)
    outputs = Outputs(overwrite=args.overwrite, inputs=args.cases)
    outputs.file("--json", args.json_out).file("--plot", args.plot)
    outputs.file("--report", report_file).check()
    cases, notes = load_cases(args.cases, prediction=True, strict=args.strict,
                              motion_band_hz=args.motion_band, shared=True,
                              decimate=args.decimate, slosh_band=True)
    for w in notes:  # before the fit, which starts from [prediction]
        print(f"warning: {w}", file=sys.stderr)
    spec = BASELINE if args.model is None else args.model
    model = model_from_spec(spec, cases[0])
    # the fit's libraries after the inputs are checked: a refused input costs no SciPy import
    from ..fitting.measurement import ChannelOffsets
    from ..fitting.nlp import fit
    from ..fitting.problem import FitProblem
    from ..fitting.record import fit_json, fit_record, report_markdown
    from ..fitting.transcription import Collocation, MultipleShooting

    # the abs cost cannot tell the carriage's sign: it takes the filtered input; else the
    # input mode's default (estimate.fitting.strategies.DEFAULT_INPUT)
    mode = args.input or ("filtered" if args.cost == "abs" else None)
    measurement = (() if args.channel_offsets == "none"
                   else (ChannelOffsets(drift=args.channel_offsets == "drift"),))
    problem = FitProblem.build(cases, model, input=mode, measurement=measurement)
    tr = MultipleShooting() if args.transcription == "multiple_shooting" else Collocation()
    result = fit(problem, transcription=tr, cost=args.cost)
    printed = args.report == "-" or (args.report is None and sys.stdout.isatty())
    if printed:
        print(result.report())
    else:
        print(f"{result.verdict}, "
              f"{result.iterations} iterations, {result.seconds:.2f} s, RMS residual "
              f"{result.rms_residual:.4g} N")
        for i, e in enumerate(result.problem.experiments):
            fig = result.noise_figure(i)
            if fig is not None and len(result.problem.channels(i)) == 1:
                print(f"  {e.case.test.id}: noise figure {fig.describe('N')}; residual "
                      f"{result.residual_over_noise(i):.2f} times the noise")
        for i, (n, v, u) in enumerate(zip(result.names, result.values, result.units)):
            print(f"  {n:30s} {v:.6g} {u} {result.uncertainty_text(i)}")
        for c in result.confounded():
            print(f"  note: {c}")
        for case in cases:  # what loading did to the record ([test] resample_hz)
            for n in case.notes:
                print(f"  note: {n}")
    if not (printed and sys.stdout.isatty()):  # on a terminal the report holds them
        for w in result.warnings:
            print(f"warning: {w}", file=sys.stderr)
    record = None
    if args.json_out or report_file:
        options = {k: v for k, v in vars(args).items() if k not in _NOT_OPTIONS}
        record = fit_record(result, model_spec=args.model, options=options, command="slosh fit",
                            warnings=notes)
    with outputs.writing() as paths:
        if args.json_out:
            paths["--json"].write_text(fit_json(record))
        if report_file:
            paths["--report"].write_text(report_markdown(result, record))
        if args.plot:
            from ..fitting.plots import plot_fit

            plot_fit(result, paths["--plot"])
    return 0 if result.converged else 1
