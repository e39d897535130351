"""The ``slosh`` command line, one module per command: ``fit``, ``simulate``, ``diagnose``,
``tank``, ``export``, ``montecarlo``, ``ntc``, ``campaign``, ``design``."""

from __future__ import annotations

import argparse
import os
import sys

__all__ = ["main"]

_COMMANDS = ("fit", "simulate", "diagnose", "tank", "export", "montecarlo", "ntc", "campaign",
             "design")


def _parser() -> argparse.ArgumentParser:
    import importlib

    parser = argparse.ArgumentParser(
        prog="slosh", description="Fuel-slosh tank tests to mechanical analog models.")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in _COMMANDS:
        importlib.import_module(f"{__name__}.{name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``slosh`` console script; returns the exit status.

    Errors in what the user gave (:class:`analogs.errors.InputError`: case and fit files,
    models, parameter values, options, output paths), file-system errors and missing
    optional libraries are printed as one line (status 2); anything else is a defect and
    shows its traceback. SIGINT and SIGTERM abort the command (:mod:`estimate.interrupts`):
    nothing is written, one line says so, and the status is 130 or 143.
    """
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    args = _parser().parse_args(argv)
    from analogs.errors import InputError, MissingDependency

    from ..interrupts import Interrupted, handled, received

    with handled(f"slosh {args.command}"):
        try:
            status = args.run(args)
        except Interrupted as err:
            return _interrupted(args.command, err, written=False)
        except (InputError, MissingDependency) as err:
            return _fail(args.command, str(err))
        except OSError as err:
            return _fail(args.command, _os_message(err))
        except Exception:
            if received() is None:  # a defect, not an interrupt that some code wrapped
                raise
            return _interrupted(args.command, Interrupted(received()), written=False)
        if received() is not None:  # arrived while the outputs were being renamed
            return _interrupted(args.command, Interrupted(received()), written=True)
    return int(status or 0)


def _interrupted(command: str, err, *, written: bool) -> int:
    what = ("while finishing; the output files it names are complete" if written else
            "nothing was written; existing output files are unchanged")
    print(f"slosh {command}: interrupted by {err.signal_name}: {what}", file=sys.stderr)
    return err.exit_status


def _fail(command: str, message: str) -> int:
    print(f"slosh {command}: error: {message}", file=sys.stderr)
    return 2


def _os_message(err: OSError) -> str:
    """``[Errno 13] Permission denied: 'x'`` as ``x: permission denied``."""
    if err.filename is None or err.strerror is None:
        return str(err)
    return f"{err.filename}: {err.strerror[:1].lower()}{err.strerror[1:]}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
