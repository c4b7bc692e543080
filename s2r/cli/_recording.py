"""The recording inputs of every command that reads stereo frames, defined once (:mod:`s2r.recordings.spec`).

``add_recording_arguments(parser)`` adds the argument group; ``recording_from_args(args)`` opens what was given as a
:class:`~s2r.recordings.FrameSource` (``spec_from_args`` returns the description without opening it).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from s2r.errors import S2RError
    from s2r.recordings import FrameSource, RecordingSpec

__all__ = ["RECORDING_FORMS", "add_recording_arguments", "recording_from_args", "spec_from_args"]

#: The forms in one line, for command descriptions and errors.
RECORDING_FORMS = ("FOLDER, --left GLOB --right GLOB, --bag BAG --left-topic T --right-topic T, "
                   "--video FILE --layout sbs|tb, or --left-video L --right-video R")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _start_stamp(text: str) -> int:
    """``--start-stamp``: seconds since the Unix epoch (``1714564800.25``) or an ISO 8601 time with its zone
    (``2024-05-01T12:00:00Z``, ``...+02:00``), as ns since the epoch."""
    from datetime import datetime
    from decimal import Decimal, InvalidOperation

    try:
        seconds = Decimal(text)
    except InvalidOperation:
        seconds = None
    if seconds is None:
        try:
            when = datetime.fromisoformat(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not seconds since the Unix epoch nor an ISO 8601 time: {text!r} "
                                             "(e.g. 2024-05-01T12:00:00Z)") from None
        if when.tzinfo is None:
            raise argparse.ArgumentTypeError(f"{text!r} has no time zone: add Z (UTC) or an offset such as +02:00")
        return round(when.timestamp() * 1e6) * 1000
    if not seconds.is_finite() or not 0 < seconds < 2**63 // 10**9:
        raise argparse.ArgumentTypeError(f"must be positive seconds since the Unix epoch, got {text!r}")
    return int(seconds * 10**9)


def add_recording_arguments(parser: argparse.ArgumentParser, *, positional: str | None = "recording",
                            max_frames_default: int | None = None, max_frames_help: str | None = None,
                            what: str = "stereo pairs") -> None:
    """Add the recording inputs to ``parser`` (one argument group; see :data:`RECORDING_FORMS`).

    Args:
        positional: dest of the optional positional FOLDER (None: no positional, the command has its own).
        max_frames_default / max_frames_help: ``--max-frames``' default and help when the command gives it another
            meaning (``check`` spreads its pairs over the recording).
        what: what the recording holds, for the help texts.
    """
    group = parser.add_argument_group("recording", f"{what} from one of: {RECORDING_FORMS}")
    if positional is not None:
        group.add_argument(positional, nargs="?", type=Path, metavar="FOLDER",
                           help="folder with left/ and right/ (or cam0/ cam1/, image_0/ image_1/) subfolders, or with "
                                "leftNN/rightNN image files")
    group.add_argument("--left", metavar="GLOB|DIR", help="left images: a quoted glob or a folder (with --right)")
    group.add_argument("--right", metavar="GLOB|DIR", help="right images: a quoted glob or a folder")
    group.add_argument("--bag", type=Path, metavar="BAG",
                       help="ROS 1 .bag, or ROS 2 bag folder / .db3 / .mcap (with --left-topic, --right-topic)")
    group.add_argument("--left-topic", metavar="TOPIC", help="--bag: left Image or CompressedImage topic")
    group.add_argument("--right-topic", metavar="TOPIC", help="--bag: right Image or CompressedImage topic")
    group.add_argument("--max-dt", type=float, default=0.01, metavar="S",
                       help="--bag: pairing tolerance of the header stamps, seconds (default 0.01)")
    group.add_argument("--video", type=Path, metavar="FILE", help="one video holding both images (with --layout)")
    group.add_argument("--layout", choices=("sbs", "tb"), default="sbs",
                       help="--video: sbs = left | right side by side (default), tb = left over right")
    group.add_argument("--left-video", type=Path, metavar="FILE", help="left camera video (with --right-video)")
    group.add_argument("--right-video", type=Path, metavar="FILE",
                       help="right camera video, paired with --left-video by frame index")
    group.add_argument("--start-stamp", type=_start_stamp, metavar="TIME",
                       help="--video / --left-video: when the video began, seconds since the Unix epoch or ISO 8601 "
                       "with a zone (2024-05-01T12:00:00Z); frames are stamped TIME + their time in the video "
                       "(default: the video file's modification time)")
    group.add_argument("--every", type=_positive_int, default=1, metavar="N",
                       help="use every N-th frame or pair of the recording (default 1)")
    group.add_argument("--max-frames", type=_positive_int, default=max_frames_default, metavar="N",
                       help=max_frames_help or "stop after N frames (default: all)")


def spec_from_args(args: argparse.Namespace, *, positional: str | None = "recording", max_frames: bool = True
                   ) -> RecordingSpec:
    """The :class:`~s2r.recordings.RecordingSpec` the arguments describe (not checked, nothing opened).

    ``positional``: the dest of the command's FOLDER argument (None: it has none). ``max_frames=False`` leaves
    ``--max-frames`` to the command (``check`` spreads its pairs instead).
    """
    from s2r.recordings import RecordingSpec

    def get(name: str | None) -> Any:
        return None if name is None else getattr(args, name, None)

    return RecordingSpec(folder=get(positional), left_glob=get("left"), right_glob=get("right"), bag=get("bag"),
                         left_topic=get("left_topic"), right_topic=get("right_topic"),
                         max_dt_s=get("max_dt") if get("max_dt") is not None else 0.01,
                         video=get("video"), layout=get("layout") or "sbs", left_video=get("left_video"),
                         right_video=get("right_video"), every=get("every") or 1,
                         max_frames=get("max_frames") if max_frames else None, start_ns=get("start_stamp"))


def recording_from_args(args: argparse.Namespace, *, expected_size: Any = None, grey: bool = False,
                        error: type[S2RError] | None = None, positional: str = "recording") -> FrameSource:
    """Open the recording the arguments name (:func:`s2r.recordings.open_recording`).

    Args:
        expected_size: (width, height) px of both cameras, or ((w, h) left, (w, h) right): images declaring another
            size are refused before decoding.
        grey: 8-bit grey frames (else as recorded, 8-bit grey or BGR).
        error: the command's error class (default :class:`s2r.errors.RecordingError`).
        positional: the dest of the command's FOLDER argument.
    """
    from s2r.errors import RecordingError
    from s2r.recordings import open_recording

    return open_recording(spec_from_args(args, positional=positional), expected_size=expected_size, grey=grey,
                          error=error or RecordingError)
