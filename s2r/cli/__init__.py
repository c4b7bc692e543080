"""The ``s2r`` command line: parses arguments, calls the library, prints, returns an exit code.

Exit codes: 0 ok, 1 a check failed (a finding), 2 bad input or usage, 3 an internal error (a bug in s2r),
130 interrupted (Ctrl-C), 143 terminated (SIGTERM, cleaned up like Ctrl-C). Errors print as one ``error: ...``
line on stderr; ``--debug`` shows the traceback instead. Warnings from the library (logging) go to stderr. Output
piped into a reader that stops early (``s2r ... | head``) ends the run quietly with exit 0.
"""

from __future__ import annotations

import argparse
import difflib
import errno
import io
import logging
import os
import re
import sys
from collections.abc import Sequence
from typing import NoReturn, TextIO

from s2r._version import __version__
from s2r.cli import (  # _process first: its process-wide settings (BLAS threads, malloc) precede numpy
    _process,  # noqa: F401
    calibrate_cmd,
    check_cmd,
    depth_cmd,
    depth_quality_cmd,
    mujoco_cmd,
    profile_cmd,
    render_cmd,
    sensor_cmd,
    sources_cmd,
    validate_cmd,
)
from s2r.cli._order import reversed_arguments
from s2r.cli._process import Terminated, sigterm_as_interrupt
from s2r.errors import S2RError, terminal_safe

__all__ = ["build_parser", "entry", "main"]

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130
EXIT_TERMINATED = 143  # SIGTERM (128 + 15), after the same clean-up as Ctrl-C
_WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EFBIG, errno.EROFS, errno.EACCES, errno.EDQUOT, errno.EPERM})
_REPORT_HINT = "this is a bug in s2r: rerun with --debug and report the command and the traceback"


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors a newcomer can act on.

    - an unknown subcommand gets "did you mean" (``calibrte`` -> ``calibrate``);
    - a mistyped option before the subcommand (``s2r --verison``) is named, not reported as a missing COMMAND;
    - optional positionals (``NAME:=VALUE ...``) are not listed as required.
    """

    argv: Sequence[str] = ()

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.format_usage()}{self.prog}: error: {self._explain(message)}\n")

    def _explain(self, message: str) -> str:
        choice = re.match(r"argument (\S+): invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            options = re.findall(r"'([^']*)'", choice.group(3)) or [o.strip() for o in choice.group(3).split(",")]
            close = difflib.get_close_matches(choice.group(2), options, n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            return f"unknown {choice.group(1)} '{choice.group(2)}'{hint} (choose from {', '.join(options)})"
        if message.startswith("the following arguments are required:"):
            unknown = self._unknown_options()
            if unknown:
                return unknown
            optional = {a.metavar or a.dest for a in self._actions if not a.option_strings and a.nargs in ("*", "?")}
            names = [n.strip() for n in message.split(":", 1)[1].split(",")]
            return "the following arguments are required: " + ", ".join(n for n in names if n not in optional)
        if message.startswith("unrecognized arguments:"):
            return self._unrecognized(message)
        return message

    def _unrecognized(self, message: str) -> str:
        """argparse's "unrecognized arguments" with "did you mean" from the options of the command given."""
        parser: argparse.ArgumentParser = self
        for token in type(self).argv:  # walk down to the (sub)command the line names
            chosen = next((a.choices[token] for a in parser._actions
                           if isinstance(a, argparse._SubParsersAction) and token in a.choices), None)
            if chosen is not None:
                parser = chosen
        known = [s for a in parser._actions for s in a.option_strings]
        for token in message.split(":", 1)[1].split():
            close = difflib.get_close_matches(token.split("=", 1)[0], known, n=1, cutoff=0.6) \
                if token.startswith("--") else []
            if close:
                return f"{message} (did you mean {close[0]}?)"
        return message

    def _unknown_options(self) -> str:
        """"unrecognized option --verison (did you mean --version?)" for options this parser does not know."""
        known = [s for a in self._actions for s in a.option_strings]
        for token in type(self).argv:
            if not token.startswith("-") or token == "-":
                continue
            name = token.split("=", 1)[0]
            if name in known:
                continue
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            return f"unrecognized option {name}" + (f" (did you mean {close[0]}?)" if close else "")
        return ""


def build_parser() -> argparse.ArgumentParser:
    """The full argparse tree of every s2r subcommand."""
    parser = _Parser(prog="s2r", description="Stereo camera profiles from sim to real.")
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
    sensor_cmd.register(sub)
    check_cmd.register(sub)
    _accept_global_options_anywhere(parser)
    return parser


def _accept_global_options_anywhere(parser: argparse.ArgumentParser) -> None:
    """``s2r calibrate ... -q`` works as ``s2r -q calibrate ...``: every subcommand also takes -q and --debug
    (default SUPPRESS, so a subcommand without them keeps the value given before it)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in set(action.choices.values()):
                child.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                                   help="hide warnings and progress")
                child.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                                   help="show full tracebacks")
                _accept_global_options_anywhere(child)


class _WarningFormatter(logging.Formatter):
    """``level: message`` on one line: every control character of the message (a file name's ESC, BEL, CR or
    newline) escaped."""

    def format(self, record: logging.LogRecord) -> str:
        return f"{record.levelname.lower()}: {terminal_safe(record.getMessage())}"


class _TerminalSafeStream(io.TextIOBase):
    """stdout / stderr of the CLI: control characters other than newline and tab are escaped on the way out, so
    no name printed anywhere can send ESC, OSC, BEL or CR to the terminal. The progress bar alone draws its
    ``\\r`` through :meth:`write_raw`."""

    def __init__(self, stream: TextIO) -> None:
        super().__init__()
        self.stream = stream

    def write(self, text: str) -> int:
        """Write ``text`` with its control characters (but newlines and tabs) escaped; returns ``len(text)``."""
        self.stream.write(terminal_safe(text, keep="\n\t"))
        return len(text)

    def write_raw(self, text: str) -> int:
        """Write ``text`` as it is (s2r's own fixed progress line)."""
        return self.stream.write(text)

    def flush(self) -> None:
        """Flush the wrapped stream."""
        self.stream.flush()

    def isatty(self) -> bool:
        """Whether the wrapped stream is a terminal."""
        return self.stream.isatty()

    def fileno(self) -> int:
        """The wrapped stream's descriptor."""
        return self.stream.fileno()

    @property
    def encoding(self) -> str:  # type: ignore[override]
        """The wrapped stream's encoding."""
        return getattr(self.stream, "encoding", None) or "utf-8"


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
    _Parser.argv = list(sys.argv[1:] if argv is None else argv)
    streams = sys.stdout, sys.stderr
    logger = logging.getLogger("s2r")
    logging_state = logger.handlers[:], logger.level, logger.propagate
    sys.stdout, sys.stderr = _TerminalSafeStream(sys.stdout), _TerminalSafeStream(sys.stderr)
    try:
        hint = reversed_arguments(parser, _Parser.argv)
        if hint is not None:  # before argparse, whose "unrecognized arguments" would hide the cause
            print(f"error: {hint}", file=sys.stderr)
            return EXIT_BAD_INPUT
        args = parser.parse_args(argv)
        _configure_logging(args.quiet)
        with sigterm_as_interrupt():
            return _run(args)
    finally:  # an in-process caller (a script, a test) gets its streams and s2r's logger back as they were
        sys.stdout, sys.stderr = streams
        logger.handlers[:], logger.level, logger.propagate = logging_state


def entry() -> NoReturn:
    """The ``s2r`` console script: :func:`main`, then exit without the interpreter's teardown.

    Every output is already published (atomic, closed) and every worker pool shut down when :func:`main`
    returns, so the teardown (finalising numpy, OpenCV, pydantic and their modules: ~0.1 s of a 1 s
    calibration) only delays the shell. Standard streams and logging are flushed first; a reader that closed
    the pipe early still gets the quiet exit 0 of :func:`main`.
    """
    code = main()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except BrokenPipeError:
        code = _quiet_broken_pipe()
    logging.shutdown()
    os._exit(code)


#: Argument destinations that name what a command writes (-o/--output/--out, --report, sensor fit's --profile-out):
#: every other path argument is an input, which no output may be or replace (fileio.protecting_inputs).
_OUTPUT_DESTS = frozenset({"output", "out", "report", "profile_out"})


def _run(args: argparse.Namespace) -> int:
    from s2r.fileio import protecting_inputs, removing_new_folders_on_failure

    given = [v for dest, value in vars(args).items() if dest not in _OUTPUT_DESTS
             for v in (value if isinstance(value, list) else [value])]
    paths = [v for v in given if isinstance(v, (str, os.PathLike))]
    try:  # no output is an input: neither written over nor its folder replaced by --force
        with protecting_inputs(paths), removing_new_folders_on_failure():  # a refused run leaves no empty folder
            code: int = args.func(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the boundary, not at interpreter exit
    except BrokenPipeError:
        return _quiet_broken_pipe()
    except KeyboardInterrupt as exc:
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    except Exception as exc:
        if args.debug:
            raise
        code = _report(exc)
    return code


def _report(exc: Exception) -> int:
    """Print ``exc`` as one ``error:`` line; its exit code (2 for bad input, 3 for a bug in s2r)."""
    from concurrent.futures.process import BrokenProcessPool

    from pydantic import ValidationError  # only on the error path: keeps `s2r --help` fast

    try:
        if isinstance(exc, S2RError):
            print(f"error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, ValidationError):  # a value from an input broke a bound of s2r.profile
            first = exc.errors()[0] if exc.errors() else {"loc": (), "msg": str(exc)}
            where = ".".join(str(p) for p in first["loc"]) or exc.title
            print(terminal_safe(f"error: {where}: {' '.join(str(first['msg']).split())}"), file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, BrokenProcessPool):  # a worker killed from outside, not a fault of s2r's
            print("error: a worker process ended abruptly (killed by another program or the out-of-memory killer); "
                  "nothing was written (run again, or with --jobs 1 to use one process)", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, OSError) and exc.filename is not None:  # a file the user named is unusable
            print(f"error: {terminal_safe(exc.filename)}: {terminal_safe(exc.strerror or exc)}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, OSError) and exc.errno in _WRITE_ERRNOS:  # a full or read-only disk, not a bug
            print(f"error: cannot write: {terminal_safe(exc.strerror or exc)} (free space or choose a writable "
                  "location)", file=sys.stderr)
            return EXIT_BAD_INPUT
        detail = terminal_safe(" ".join(str(exc).split())[:200])
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
