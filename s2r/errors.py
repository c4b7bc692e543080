"""The s2r error tree: one root, one subclass per stage.

Every error renders as ONE line that names the file and/or field at fault and what to do about it,
because the CLI prints ``str(error)`` as ``error: ...`` and exits 2 (no traceback unless ``--debug``).
"""

from __future__ import annotations

import re
from pathlib import Path

__all__ = [
    "CalibrationError",
    "CheckError",
    "DepthError",
    "FormatError",
    "OutputExistsError",
    "ProfileError",
    "RecordingError",
    "RenderError",
    "S2RError",
    "SourceError",
    "ValidateError",
    "terminal_safe",
]

#: C0 controls (ESC, BEL, CR, LF, ...), DEL, C1 controls (CSI, OSC as single code points), the line and
#: paragraph separators and the bidirectional overrides/isolates (which reorder what a terminal shows).
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def terminal_safe(text: object, *, keep: str = "") -> str:
    """``str(text)`` with every control character written as its Python escape (ESC as ``\\x1b``, a newline as
    ``\\n``), so a file name can neither recolour nor retitle a terminal, nor forge a line of output.

    ``keep`` lists control characters to pass through unchanged (``"\\n"`` for text that is several lines on
    purpose). The one rule for every name s2r prints: error lines, log lines and the CLI's output streams.
    """
    return _UNSAFE.sub(lambda m: m.group() if m.group() in keep else ascii(m.group())[1:-1], str(text))


class S2RError(Exception):
    """Root of every error s2r raises on purpose (bad input, refused writes, impossible requests).

    Args:
        message: what is wrong, without the location.
        path: the file at fault, if any.
        field: the dotted field path or XML element at fault, if any.
        hint: what the user should do about it.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | Path | None = None,
        field: str | None = None,
        hint: str | None = None,
    ) -> None:
        self.message = message
        self.path = None if path is None else terminal_safe(path)
        self.field = field
        self.hint = hint
        super().__init__(self.one_line())

    def one_line(self) -> str:
        """The error as ``path: field: message (hint)`` on a single line."""
        text = " ".join(self.message.split())
        if self.hint:
            text = f"{text} ({' '.join(self.hint.split())})"
        parts = [terminal_safe(p) for p in (self.path, self.field) if p]
        return terminal_safe(": ".join([*parts, text]))


class ProfileError(S2RError):
    """A profile is invalid, unknown or unreadable."""


class FormatError(S2RError):
    """An outside file format (ROS, OpenCV, Kalibr, RealSense, ...) could not be read or written."""


class SourceError(S2RError):
    """A robot description (URDF, xacro, SDF) could not be turned into a profile."""


class CalibrationError(S2RError):
    """Calibration inputs are unusable or the solve failed."""


class RenderError(S2RError):
    """A PyBullet render request cannot be satisfied."""


class DepthError(S2RError):
    """The depth pipeline got inputs it cannot process."""


class ValidateError(S2RError):
    """A validation request is malformed (tolerances, distances, report folder)."""


class RecordingError(S2RError):
    """A recording (image folder, globs, bag, video) cannot be read as stereo frames."""


class CheckError(S2RError):
    """A target-less drift check (``s2r check``, ``s2r fleet check``) got unusable inputs."""


class OutputExistsError(S2RError):
    """An output already exists and ``force`` was not given: nothing was overwritten."""
