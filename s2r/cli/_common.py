"""Helpers shared by the CLI command modules: JSON output, progress bar, common options."""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO, TypeVar

import numpy as np

if TYPE_CHECKING:
    from s2r.profile import StereoProfile

__all__ = ["ProgressBar", "add_force", "add_jobs", "add_json", "add_profile_positional", "add_recording_inputs",
           "argparse_type", "check_jobs", "check_left_board", "load_profile", "parse_distances", "parse_pattern",
           "positional_is_profile", "print_json", "profile_argument", "to_jsonable"]

T = TypeVar("T")


def parse_pattern(text: str) -> tuple[int, int]:
    """``"9x6"`` -> ``(9, 6)`` chessboard INNER corners (columns x rows); ValueError saying what is wrong."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX*,]\s*(\d+)\s*", text)
    if not match or min(int(match.group(1)), int(match.group(2))) < 2:
        raise ValueError(f"cannot read pattern {text!r}: give INNER corners as COLSxROWS, e.g. 9x6 for a board "
                         "of 10x7 squares")
    return int(match.group(1)), int(match.group(2))


def parse_distances(text: str) -> tuple[float, ...]:
    """``"0.5,1,2"`` -> distances in metres, each finite and positive; ValueError saying what is wrong."""
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise ValueError(f"not a list of numbers: {text!r} (write metres separated by commas, e.g. 0.5,1,2,3)"
                         ) from None
    if not values or not all(math.isfinite(v) and v > 0 for v in values):
        raise ValueError(f"distances must be positive metres, got {text!r} (e.g. 0.5,1,2,3)")
    return values


def load_profile(name_or_path: Any) -> StereoProfile:
    """:func:`s2r.registry.load_profile`, imported on first use: building the parser loads no profile models."""
    from s2r.registry import load_profile as load

    return load(name_or_path)


def add_profile_positional(parser: argparse.ArgumentParser, *, help: str) -> None:
    """The profile as the first positional (``s2r CMD PROFILE ...``, as check, validate and depth-quality take it),
    with ``--profile`` kept as an alias; :func:`profile_argument` reads whichever was given."""
    parser.add_argument("profile", metavar="PROFILE", nargs="?", help=help)
    parser.add_argument("--profile", dest="profile_option", metavar="PROFILE",
                        help="the same as the PROFILE positional (an alias kept for older scripts)")


def profile_argument(args: argparse.Namespace, *, command: str, shift_to: str | None = "recording") -> str:
    """The profile given by :func:`add_profile_positional`'s positional or ``--profile``; ProfileError when
    neither or two different ones were given.

    With ``--profile`` the PROFILE positional is read as :func:`positional_is_profile` says: the same profile again
    (dropped), another profile (refused), or the command's next positional (``shift_to``, e.g. the recording FOLDER:
    ``s2r check --profile P FOLDER``) when that one is free."""
    from s2r.errors import ProfileError

    positional, option = args.profile, args.profile_option
    if positional is None and option is None:
        raise ProfileError("missing the profile", field="PROFILE",
                           hint=f"give it first: s2r {command} PROFILE ... (a name or a YAML path)")
    if positional is not None and option is not None:
        free = shift_to is not None and hasattr(args, shift_to) and getattr(args, shift_to) is None
        if not positional_is_profile(str(positional), str(option), command=command, strict=not free):
            setattr(args, str(shift_to), Path(positional))
        args.profile = None
    return str(positional if option is None else option)


#: Suffixes of profile files (s2r, Kalibr, ROS and OpenCV YAML, OpenCV XML): never an image nor a recording, so such
#: a positional beside ``--profile`` is a second profile, not an input (RealSense's ``.txt`` is left out: a text
#: file given as an image is named as an unreadable image).
PROFILE_SUFFIXES = (".yaml", ".yml", ".xml")


def positional_is_profile(positional: str, option: str, *, command: str, strict: bool = False) -> bool:
    """A positional given beside ``--profile option``: True when it names that same profile (the caller drops it),
    False when it is no profile (an input: an image, a folder, a bag); ProfileError naming both when it names
    another profile (a profile file's suffix, or a profile name that is no path here), or with ``strict`` (the
    command has no other positional to read it as) whenever it is not the same profile.

    The one rule of every command taking both a PROFILE positional and ``--profile`` (check, depth, depth-quality,
    sensor fit/apply): a YAML profile is never read as an image or a recording."""
    from s2r.errors import ProfileError

    if _same_profile(positional, option):
        return True
    if strict or _looks_like_profile(positional):
        raise ProfileError(f"two profiles given: {positional} and --profile {option}", field="PROFILE",
                           hint=f"give one: s2r {command} PROFILE ... or s2r {command} --profile PROFILE ...")
    return False


def _same_profile(a: str, b: str) -> bool:
    """One profile: the same text, or two names or paths of one file."""
    from s2r.errors import S2RError
    from s2r.registry import resolve_profile

    if a == b:
        return True
    try:
        return os.path.samefile(resolve_profile(a), resolve_profile(b))
    except (S2RError, OSError, ValueError):  # an unknown name, a missing file: not one profile
        return False


def _looks_like_profile(text: str) -> bool:
    """A profile file's name (:data:`PROFILE_SUFFIXES`), or a known profile name that is no path here."""
    if Path(text).suffix.lower() in PROFILE_SUFFIXES:
        return True
    if Path(text).exists() or "/" in text or os.sep in text:
        return False
    from s2r.registry import list_profiles

    return text in list_profiles()


def check_left_board(left: str, pattern: tuple[int, int]) -> None:
    """The board-size check of :func:`s2r.calib.detect.board_size.check_board_size` on a recording's ``--left``
    images (folder or glob): CalibrationError naming the board size that is there when ``pattern`` is not."""
    from s2r.calib.detect.board_size import check_board_size
    from s2r.quality.inputs import IMAGE_SUFFIXES, list_files

    check_board_size(list_files(left, IMAGE_SUFFIXES, option="--left"), pattern)


def argparse_type(parse: Callable[[str], T]) -> Callable[[str], T]:
    """Wrap a parser raising ValueError as an argparse ``type=`` that keeps its message in the usage error."""

    def convert(text: str) -> T:
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return convert


def to_jsonable(value: Any) -> Any:
    """Convert numpy types, tuples, Paths and pydantic models to JSON-ready values (NaN -> None)."""
    if hasattr(value, "model_dump"):
        return to_jsonable(value.model_dump(mode="json"))
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def print_json(data: Any) -> None:
    """Print ``data`` as indented JSON on stdout."""
    print(json.dumps(to_jsonable(data), indent=2))


def add_json(parser: argparse.ArgumentParser) -> None:
    """Add ``--json`` (machine-readable output on stdout)."""
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON on stdout")


def add_recording_inputs(parser: argparse.ArgumentParser) -> None:
    """Add the options a recording is given by (``depth-quality``, ``sensor fit``): the shared recording inputs
    (:func:`s2r.cli._recording.add_recording_arguments`: folders, globs, bags, videos) plus device depth images or
    a bag's depth topic registered to the left images."""
    from s2r.cli._recording import add_recording_arguments

    add_recording_arguments(parser, what="stereo pairs (or --left with --depth / --bag with --depth-topic: device "
                                         "depth)")
    parser.add_argument("--depth", metavar="DIR|GLOB", help="device depth images registered to the left images")
    parser.add_argument("--depth-topic", help="depth topic in --bag (16UC1 mm or 32FC1 m)")


def add_jobs(parser: Any, *, default: int | None, help: str) -> None:
    """Add ``--jobs N`` (dest ``jobs``), the one name of parallelism across commands (calibrate, render,
    validate, depth, fleet check), with ``--workers`` as a hidden alias (depth and fleet check's former name)."""
    parser.add_argument("--jobs", type=_process_count, default=default, metavar="N", help=help)
    parser.add_argument("--workers", type=_process_count, dest="jobs", default=argparse.SUPPRESS,
                        help=argparse.SUPPRESS)


def _process_count(text: str) -> int:
    """``--jobs``'s argparse type: a whole number (its range is :func:`check_jobs`'s)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number of processes, got {text!r} "
                                         "(e.g. --jobs 2)") from None


#: Local worker processes per usable core ``--jobs`` may ask for: each holds images, so more is memory, not speed.
MAX_JOBS_PER_CORE = 4


def check_jobs(jobs: int | None, error: Callable[..., Exception], *, local: bool = True, more: str = "") -> None:
    """Refuse ``--jobs`` below 1 (None is a command's default), or over :data:`MAX_JOBS_PER_CORE` times the cores
    this process may use when the workers are ``local`` processes, with ``error`` (the command's S2RError type):
    one message for every command (``more``: where more workers can run, added to the hint)."""
    if jobs is None:
        return
    if jobs < 1:
        raise error(f"must be at least 1, got {jobs}", field="--jobs/--workers", hint="e.g. --jobs 2")
    from s2r.executor import usable_cores

    cores = usable_cores()
    if local and jobs > MAX_JOBS_PER_CORE * cores:
        raise error(f"{jobs} local worker processes on {cores} usable cores", field="--jobs/--workers",
                    hint=f"at most {MAX_JOBS_PER_CORE * cores} here; each holds images, so more only costs memory"
                    + (f"; {more}" if more else ""))


def add_force(parser: argparse.ArgumentParser) -> None:
    """Add ``--force`` (allow replacing existing outputs)."""
    parser.add_argument("--force", action="store_true", help="replace existing outputs")


#: A stage of at most this many steps (a fleet's robots) logs every step: each is long, and the first one
#: done is news (a fleet showed "0/5" for a minute while its workers started, then nothing until the heartbeat).
EACH_STEP_TOTAL = 20


class ProgressBar:
    """A progress callback for stderr: a redrawn bar on a terminal, plain log lines elsewhere.

    On a terminal it draws ``label [#####-----] done/total``. On anything else (a pipe, a CI log, a file) it
    prints ``progress: label done/total (elapsed s)`` lines: when a stage starts, when it ends, at every step of a
    stage of at most :data:`EACH_STEP_TOTAL` steps, and at least every ``log_every_s`` seconds while one runs (a
    daemon heartbeat thread repeats the last state, so a slow stage between two callbacks still shows it is
    alive). Nothing is logged in the first ``log_every_s``: a quick run
    (or a one-line error, which bad input gives within seconds) stays as short as it was.
    """

    def __init__(self, *, enabled: bool | None = None, terminal: bool | None = None, width: int = 30,
                 log_every_s: float = 10.0, stream: TextIO | None = None) -> None:
        """``enabled=False`` shows nothing (``-q``); ``terminal`` forces the bar (True) or log lines (False)."""
        self.stream = sys.stderr if stream is None else stream
        self.enabled = enabled is not False
        self.terminal = self.stream.isatty() if terminal is None else terminal
        self.width = width
        self.log_every_s = log_every_s
        self._last = 0.0
        self._start = time.monotonic()
        self._state: tuple[int, int, str] | None = None
        self._printed_at = self._start
        self._lock = threading.Lock()
        self._heartbeat: threading.Thread | None = None

    def __call__(self, done: int, total: int, label: str) -> None:
        if not self.enabled or total <= 0:
            return
        if self.terminal:
            self._draw(done, total, label)
        else:
            self._log(done, total, label)

    def _draw(self, done: int, total: int, label: str) -> None:
        now = time.monotonic()
        if done < total and now - self._last < 0.1:
            return
        self._last = now
        filled = int(self.width * done / total)
        bar = "#" * filled + "-" * (self.width - filled)
        end = "\n" if done >= total else ""
        getattr(self.stream, "write_raw", self.stream.write)(f"\r{label:<18} [{bar}] {done}/{total}{end}")
        self.stream.flush()

    def _log(self, done: int, total: int, label: str) -> None:
        with self._lock:
            previous, self._state = self._state, (done, total, label)
            now = time.monotonic()
            stage_changed = previous is None or previous[2] != label
            if now - self._start < self.log_every_s:  # a run that ends within seconds stays silent
                pass
            elif stage_changed or done >= total or now - self._printed_at >= self.log_every_s \
                    or (total <= EACH_STEP_TOTAL and previous is not None and done != previous[0]):
                self._print_state(now)
            if self._heartbeat is None:
                self._heartbeat = threading.Thread(target=self._beat, name="s2r-progress", daemon=True)
                self._heartbeat.start()

    def _print_state(self, now: float) -> None:
        """Print the current state (the caller holds the lock)."""
        if self._state is None:
            return
        done, total, label = self._state
        self.stream.write(f"progress: {label} {done}/{total} ({now - self._start:.0f} s)\n")
        self.stream.flush()
        self._printed_at = now

    def _beat(self) -> None:
        """Repeat the last state every ``log_every_s`` while nothing else printed (ends with the process)."""
        while True:
            time.sleep(self.log_every_s / 4)
            with self._lock:
                now = time.monotonic()
                if self._state is not None and self._state[0] < self._state[1] \
                        and now - self._printed_at >= self.log_every_s:
                    try:
                        self._print_state(now)
                    except (OSError, ValueError):  # the stream closed under us: stop quietly
                        return

