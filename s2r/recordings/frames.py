"""The frame contract every recording input yields and every stream consumer (depth, calibrate, check) reads, and
the one refusal of an input given for both cameras."""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from s2r.errors import RecordingError

if TYPE_CHECKING:
    from s2r.errors import S2RError

__all__ = ["NAMED_SKIPPED", "STAMP_FILE_TIME", "STAMP_RECORDED", "FrameSource", "StereoFrame", "refuse_same_sides",
           "skipped_fields", "skipped_inputs", "thinned"]

T = TypeVar("T")

#: Where a frame's stamp comes from (:attr:`StereoFrame.stamp_source`; frames.csv's ``stamp_source`` column, with
#: ``synthesized`` for still files, which carry no time).
STAMP_RECORDED = "recorded"
STAMP_FILE_TIME = "file time"


@dataclass(frozen=True)
class StereoFrame:
    """One stereo pair as a recording holds it, decoded.

    Attributes:
        index: position of the frame in the whole recording, 0-based, counted before ``--every`` / ``--max-frames``
            thin it (so outputs can be traced back to the input).
        name: a file-name-safe stem naming the frame: the left image's file stem for files, the left stamp in
            nanoseconds for bags (``1700000000123456789``), ``frame_000123`` for videos.
        stamp_ns: the left image's time in nanoseconds: the header stamp for bags, the video's start plus the
            frame's time in it for videos (:mod:`s2r.recordings.video`),
            None for still files.
        frame_id: the left image's ROS frame_id as recorded ('' when the input has none).
        left: left image, uint8, H x W (grey) or H x W x 3 (BGR).
        right: right image, the same size and channels as ``left``.
        source: a short human description of where the pair came from (file names, ``bag TOPIC @ STAMP``,
            ``video FILE frame N``), for messages and the output index.
        stamp_source: where ``stamp_ns`` comes from: :data:`STAMP_RECORDED` (a bag's header stamp; a video's
            ``--start-stamp`` plus the frame's time in it) or :data:`STAMP_FILE_TIME` (a video's file modification
            time plus the frame's time: a copy may have moved it); meaningless when ``stamp_ns`` is None.
    """

    index: int
    name: str
    stamp_ns: int | None
    frame_id: str
    left: NDArray[np.uint8]
    right: NDArray[np.uint8]
    source: str
    stamp_source: str = STAMP_RECORDED


class FrameSource(Protocol):
    """Anything that streams stereo frames: iterate it once, in recording order."""

    def frames(self) -> Iterator[StereoFrame]:
        """The frames, decoded one at a time (never the whole recording in memory)."""
        ...

    def describe(self) -> str:
        """One line naming the recording for summaries (``folder rec/ (24 pairs)``, ``bag run.bag``)."""
        ...


def skipped_inputs(source: object) -> list[str]:
    """The inputs ``source`` skipped for want of a partner (image files, ``TOPIC @ STAMP ns`` bag messages), as
    its ``skipped`` attribute lists them once it has been read; [] for a source that skips none."""
    return list(getattr(source, "skipped", ()))


#: How many skipped inputs a warning and ``skipped_first`` name.
NAMED_SKIPPED = 5


def skipped_fields(skipped: list[str]) -> dict[str, int | list[str]]:
    """The ``--json`` keys of the inputs skipped for want of a partner, the same in every command (depth, check,
    fleet rows): ``skipped_unpaired`` (how many) and ``skipped_first`` (the first :data:`NAMED_SKIPPED`)."""
    return {"skipped_unpaired": len(skipped), "skipped_first": skipped[:NAMED_SKIPPED]}


def thinned(items: Iterable[T], every: int = 1, max_frames: int | None = None) -> Iterator[tuple[int, T]]:
    """``(index, item)`` of every ``every``-th item (``index`` counted in ``items``, from 0), at most ``max_frames``
    of them (None: all): the ``--every`` / ``--max-frames`` rule of every recording form.

    ``items`` is advanced lazily and never past the last item kept, so a source can yield cheap positions (a
    grabbed video frame, an undecoded bag message) and decode only those this yields."""
    if max_frames is not None and max_frames < 1:
        return
    kept = 0
    for index, item in enumerate(items):
        if index % every:
            continue
        yield index, item
        kept += 1
        if max_frames is not None and kept >= max_frames:
            return


def refuse_same_sides(left: str | Path | None, right: str | Path | None, *, field: str, topics: bool = False,
                      path: str | Path | None = None, error: type[S2RError] = RecordingError) -> None:
    """The one refusal of the same input given for the left and the right camera (two topics, files, folders or
    globs), for every command and input form, before anything is decoded.

    Args:
        left, right: the two inputs as given (None: not given, nothing to compare).
        field: the options (or positionals) named in the error, e.g. ``--left-topic/--right-topic``.
        topics: ``left`` and ``right`` are topic names (compared as given); else paths or globs, the same when
            they name one path (after ``.``/``..`` and symbolic links) or are one glob.
        path: the file holding both (a bag), named in the error.

    Raises:
        ``error``: ``left and right are the same <topic|glob|folder|file> X (give the two cameras' inputs)``.
    """
    if left is None or right is None or not (left == right if topics else _same_path(str(left), str(right))):
        return
    kind = "topic" if topics else "glob" if any(ch in str(left) for ch in "*?[") else \
        "folder" if Path(left).is_dir() else "file"
    raise error(f"left and right are the same {kind} {left}", path=path, field=field,
                hint="give the two cameras' inputs")


def _same_path(left: str, right: str) -> bool:
    """Whether two paths (or globs) name one file or folder: equal once made absolute and normalised, or one file
    on disk (a link, ``..``)."""
    if os.path.normpath(os.path.abspath(left)) == os.path.normpath(os.path.abspath(right)):
        return True
    try:
        return os.path.samefile(left, right)
    except (OSError, ValueError):  # not there (a glob, a missing file): only the names compare
        return False
