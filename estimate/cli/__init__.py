"""The ``slosh`` command line, one module per command: ``fit``, ``simulate``, ``diagnose``,
``tank``, ``export``, ``montecarlo``, ``ntc``, ``campaign``, ``design``, ``compare``."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["main"]

_COMMANDS = ("fit", "simulate", "diagnose", "tank", "export", "montecarlo", "ntc", "campaign",
             "design", "compare")


def _parser() -> argparse.ArgumentParser:
    import importlib

    from ..version import package_version

    parser = argparse.ArgumentParser(
        prog="slosh", description="Fuel-slosh tank tests to mechanical analog models.")
    parser.add_argument("--version", action="version",
                        version=f"slosh-analogs {package_version()}")
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
    nothing is written, one line says so, and the status is 130 or 143; a Ctrl-C while the
    command is still starting (importing its libraries) is one line and 130 too. A signal
    that arrives once the command's outputs are written (renamed into place) does not undo
    them: one line says they are complete and the status is the command's (and the
    ``slosh`` program, called without ``argv``, ignores SIGINT once the command returned).
    """
    import signal

    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _starting_interrupted)
    try:
        status = _main(argv)
    except KeyboardInterrupt:  # before the command's own handlers: its libraries loading
        return _interrupted_while_starting()
    except Exception as exc:
        # a SIGINT inside an extension module's own import (NumPy's core importing
        # `datetime` through PyCapsule_Import) surfaces as an ImportError that may not
        # even name the KeyboardInterrupt: the handler above noted the signal
        if _SIGINT_SEEN or _caused_by_interrupt(exc):
            return _interrupted_while_starting()
        raise
    if argv is None:  # the `slosh` program: done, a Ctrl-C while Python exits changes nothing
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    return status


_SIGINT_SEEN = False


def _starting_interrupted(signum, frame) -> None:
    """Python's own SIGINT behaviour (KeyboardInterrupt), noting that the signal came."""
    global _SIGINT_SEEN
    _SIGINT_SEEN = True
    raise KeyboardInterrupt


def _interrupted_while_starting() -> int:
    print("slosh: interrupted by SIGINT while starting: nothing was written", file=sys.stderr)
    return 130


def _caused_by_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in the cause or context chain of ``exc``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _main(argv: list[str] | None) -> int:
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    args = _parser().parse_args(argv)
    from analogs.errors import InputError, MissingDependency

    from ..interrupts import Interrupted, handled, received
    from ..outputs import committed

    committed.clear()
    with handled(f"slosh {args.command}"), _one_line_warnings():
        try:
            status = args.run(args)
        except Interrupted as err:
            if committed:
                return _after_outputs(args.command, err, 0)
            return _interrupted(args.command, err, written=False)
        except (InputError, MissingDependency) as err:
            return _fail(args.command, str(err))
        except OSError as err:
            return _fail(args.command, _os_message(err))
        except Exception:
            if received() is None:  # a defect, not an interrupt that some code wrapped
                raise
            if committed:
                return _after_outputs(args.command, Interrupted(received()), 0)
            return _interrupted(args.command, Interrupted(received()), written=False)
        if received() is not None:  # arrived while the outputs were being renamed, or after
            return _after_outputs(args.command, Interrupted(received()), int(status or 0))
    return int(status or 0)


def _after_outputs(command: str, err, status: int) -> int:
    from ..outputs import committed

    names = ", ".join(str(p) for p in committed) or "none"
    print(f"slosh {command}: {err.signal_name} arrived after the command had written its "
          f"outputs ({names}); they are complete", file=sys.stderr)
    return status


@contextmanager
def _one_line_warnings() -> Iterator[None]:
    """Warnings of the command on stderr as ``warning: message``, without Python's source
    line; each message once."""
    import warnings

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"warning: {message}", file=sys.stderr if file is None else file)

    with warnings.catch_warnings():
        warnings.simplefilter("default")
        # an interrupt while Python reads a module's bytecode leaves its file to the garbage
        # collector: the interpreter's housekeeping, not the command's, and not the user's
        warnings.simplefilter("ignore", ResourceWarning)
        warnings.showwarning = show
        yield


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
