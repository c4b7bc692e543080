"""The ``s2r`` command line: parses arguments, calls the library, prints, returns an exit code.

Exit codes: 0 ok, 1 a check failed, 2 bad input or usage. Errors print as one ``error: ...`` line on
stderr; ``--debug`` shows the traceback instead. Warnings from the library (logging) go to stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

from s2r._version import __version__
from s2r.cli import (
    calibrate_cmd,
    depth_cmd,
    depth_quality_cmd,
    profile_cmd,
    render_cmd,
    sources_cmd,
    validate_cmd,
)
from s2r.errors import S2RError

__all__ = ["build_parser", "main"]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def build_parser() -> argparse.ArgumentParser:
    """The full argparse tree of every s2r subcommand."""
    parser = argparse.ArgumentParser(prog="s2r", description="Stereo camera profiles from sim to real.")
    parser.add_argument("--version", action="version", version=f"s2r {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks")
    parser.add_argument("-q", "--quiet", action="store_true", help="hide warnings and progress")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    profile_sub = profile_cmd.register(sub)
    sources_cmd.register(sub, profile_sub)
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
    """Run the CLI; returns the exit code (0 ok, 1 check failed, 2 bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    _configure_logging(args.quiet)
    try:
        code: int = args.func(args)
    except S2RError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
