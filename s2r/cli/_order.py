"""One argument order: the profile comes first. A command line that gives a recording (a folder, a bag, a video,
an image) first and a profile later gets a one-line hint instead of an error about the folder not being a profile.

Checked before argparse (whose "unrecognized arguments" would hide the cause) and only when the first
positional is a folder or a recording file, which a profile never is: a right command line pays nothing.
"""

from __future__ import annotations

import argparse
import shlex
from collections.abc import Sequence
from pathlib import Path

__all__ = ["PROFILE_FIRST", "reversed_arguments"]

#: Commands whose first positional is the profile, followed by recordings or files of the recording.
PROFILE_FIRST = frozenset({("validate",), ("depth-quality",), ("sensor", "fit"), ("sensor", "apply"), ("depth",)})
#: Suffixes of recording files (ROS bags, MCAP, ZED SVO, videos) and of single frames.
RECORDING_SUFFIXES = frozenset({".bag", ".mcap", ".db3", ".svo", ".svo2", ".mp4", ".avi", ".mkv", ".mov",
                                ".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".npy"})


def _subcommand(parser: argparse.ArgumentParser, argv: Sequence[str]) -> tuple[tuple[str, ...],
                                                                               argparse.ArgumentParser, list[str]]:
    """``(command words, the parser of that command, the arguments after them)``."""
    words: list[str] = []
    rest = list(argv)
    while rest:
        sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
        if sub is None:
            break
        while rest and rest[0].startswith("-"):  # global options before the command (-q, --debug)
            rest.pop(0)
        if not rest or rest[0] not in sub.choices:
            break
        words.append(rest[0])
        parser = sub.choices[rest.pop(0)]
    return tuple(words), parser, rest


def _positionals(parser: argparse.ArgumentParser, rest: Sequence[str]) -> list[str]:
    """The positional arguments of ``rest``, the values of the parser's options left out."""
    arity = {s: (0 if a.nargs == 0 else 1) for a in parser._actions for s in a.option_strings}
    found: list[str] = []
    skip = 0
    for token in rest:
        if skip:
            skip -= 1
        elif token.startswith("-") and token != "-":
            skip = 0 if "=" in token else arity.get(token, 0)
        else:
            found.append(token)
    return found


def _is_recording(token: str) -> bool:
    path = Path(token)
    return path.is_dir() or (path.is_file() and path.suffix.lower() in RECORDING_SUFFIXES)


def _is_profile(token: str) -> bool:
    from s2r.errors import S2RError
    from s2r.registry import load_profile

    if _is_recording(token):
        return False
    try:
        load_profile(token)
    except (S2RError, OSError, ValueError):
        return False
    return True


def reversed_arguments(parser: argparse.ArgumentParser, argv: Sequence[str]) -> str | None:
    """The one-line hint when ``argv`` gives a PROFILE-first command a recording first and a profile later, else
    None (also for ``-h``)."""
    if "-h" in argv or "--help" in argv:
        return None
    words, command, rest = _subcommand(parser, argv)
    if words not in PROFILE_FIRST:
        return None
    positionals = _positionals(command, rest)
    if len(positionals) < 2 or not _is_recording(positionals[0]):
        return None
    profile = next((p for p in positionals[1:] if _is_profile(p)), None)
    if profile is None:
        return None
    kind = "a folder" if Path(positionals[0]).is_dir() else "a recording"
    return (f"{positionals[0]} is {kind} and {profile} a profile: arguments reversed? the profile comes first: "
            f"s2r {' '.join(words)} {shlex.quote(profile)} ...")
