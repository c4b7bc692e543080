"""The ``s2r`` command line: parses arguments, calls the library, prints, returns an exit code.

Exit codes: 0 ok, 1 a check failed (a finding), 2 bad input or usage, 3 an internal error (a bug in s2r),
130 interrupted (Ctrl-C). Errors print as one ``error: ...`` line on stderr; ``--debug`` shows the traceback
instead. Warnings from the library (logging) go to stderr. Output piped into a reader that stops early
(``s2r ... | head``) ends the run quietly with exit 0.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Sequence

from s2r._version import __version__
from s2r.cli import (
    calibrate_cmd,
    depth_cmd,
    depth_quality_cmd,
    mujoco_cmd,
    profile_cmd,
    render_cmd,
    sources_cmd,
    validate_cmd,
)
from s2r.errors import S2RError

__all__ = ["build_parser", "main"]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130
_REPORT_HINT = "this is a bug in s2r: rerun with --debug and report the command and the traceback"


def build_parser() -> argparse.ArgumentParser:
    """The full argparse tree of every s2r subcommand."""
    parser = argparse.ArgumentParser(prog="s2r", description="Stereo camera profiles from sim to real.")
    parser.add_argument("--version", action="version", version=f"s2r {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks")
    parser.add_argument("-q", "--quiet", action="store_true", help="hide warnings and progress")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    profile_sub = profile_cmd.register(sub)
    sources_cmd.register(sub, profile_sub)
    mujoco_cmd.register(profile_sub)
    render_cmd.register(sub)
    depth_cmd.register(sub)
    depth_quality_cmd.register(sub)
    calibrate_cmd.register(sub)
    validate_cmd.register(sub)
    return parser


class _WarningFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        return f"{record.levelname.lower()}: {record.getMessage()}"


def _configure_logging(quiet: bool) -> None:
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_WarningFormatter())
    root = logging.getLogger("s2r")
    root.handlers[:] = [handler]
    root.setLevel(logging.ERROR if quiet else logging.WARNING)
    root.propagate = False


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 check failed, 2 bad input, 3 internal error, 130 Ctrl-C).

    This is the one error boundary of the CLI: every exception ends here as one ``error:`` line.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    _configure_logging(args.quiet)
    try:
        code: int = args.func(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the boundary, not at interpreter exit
    except BrokenPipeError:
        return _quiet_broken_pipe()
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except Exception as exc:
        if args.debug:
            raise
        code = _report(exc)
    return code


def _report(exc: Exception) -> int:
    """Print ``exc`` as one ``error:`` line; its exit code (2 for bad input, 3 for a bug in s2r)."""
    from pydantic import ValidationError  # only on the error path: keeps `s2r --help` fast

    try:
        if isinstance(exc, S2RError):
            print(f"error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, ValidationError):  # a value from an input broke a bound of s2r.profile
            first = exc.errors()[0] if exc.errors() else {"loc": (), "msg": str(exc)}
            where = ".".join(str(p) for p in first["loc"]) or exc.title
            print(f"error: {where}: {' '.join(str(first['msg']).split())}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, OSError) and exc.filename is not None:  # a file the user named is unusable
            print(f"error: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        detail = " ".join(str(exc).split())[:200]
        print(f"error: internal error ({type(exc).__name__}: {detail}); {_REPORT_HINT}", file=sys.stderr)
    except BrokenPipeError:
        return _quiet_broken_pipe()
    return EXIT_INTERNAL


def _quiet_broken_pipe() -> int:
    """The reader of our output went away (``| head``): stop without a traceback at interpreter exit."""
    for stream in (sys.stdout, sys.stderr):
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, stream.fileno())
            os.close(devnull)
        except (OSError, ValueError):
            pass
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
