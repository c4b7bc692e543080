"""Where a drift check's ordinary stereo pairs come from: any recording input (:mod:`s2r.recordings`): a folder, two
globs, a bag and two topics, one side-by-side / top-bottom video, or two videos.

The same layouts ``s2r calibrate`` reads. At most ``max_frames`` pairs are used, spread evenly over the recording
(files: only those are decoded; streams: every ``every``-th frame is read and the kept ones thinned as it goes, so
memory stays bounded), and every image's declared size is checked against the profile before it is decoded.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import CheckError
from s2r.profile import StereoProfile
from s2r.recordings import RecordingSpec, open_recording
from s2r.recordings.files import FileFrames

__all__ = ["Sizes", "StereoSource", "profile_sizes", "read_pairs"]

GreyPair = tuple[str, NDArray[np.uint8], NDArray[np.uint8]]
#: Expected (width, height) px of the left and the right images, or None for any size.
Sizes = tuple[tuple[int, int], tuple[int, int]] | None


@dataclass(frozen=True)
class StereoSource:
    """One recording: ``folder``, or ``left_glob`` + ``right_glob``, or ``bag`` + ``left_topic`` + ``right_topic``, or
    ``video`` (+ ``layout``), or ``left_video`` + ``right_video``; ``every``-th frame, ``max_frames`` spread."""

    folder: Path | None = None
    left_glob: str | None = None
    right_glob: str | None = None
    bag: Path | None = None
    left_topic: str | None = None
    right_topic: str | None = None
    max_frames: int = 20
    video: Path | None = None
    layout: str = "sbs"
    left_video: Path | None = None
    right_video: Path | None = None
    every: int = 1
    max_dt_s: float = 0.01

    def spec(self) -> RecordingSpec:
        """The recording as a :class:`~s2r.recordings.RecordingSpec` (all frames: the spread is this module's)."""
        return RecordingSpec(folder=self.folder, left_glob=self.left_glob, right_glob=self.right_glob, bag=self.bag,
                             left_topic=self.left_topic, right_topic=self.right_topic, max_dt_s=self.max_dt_s,
                             video=self.video, layout=self.layout, left_video=self.left_video,
                             right_video=self.right_video, every=self.every)

    def describe(self) -> str:
        """The recording in one phrase, for reports."""
        if self.bag is not None:
            return f"{self.bag} ({self.left_topic}, {self.right_topic})"
        if self.folder is not None:
            return str(self.folder)
        if self.left_glob is not None or self.right_glob is not None:
            return f"{self.left_glob} + {self.right_glob}"
        return self.spec().describe()


def _spread(count: int, limit: int) -> list[int]:
    """``limit`` indices spread evenly over ``count`` items (all of them when there are fewer)."""
    if count <= limit:
        return list(range(count))
    return sorted({round(k * (count - 1) / (limit - 1)) for k in range(limit)})


def _decimated(frames: Iterator[GreyPair], limit: int) -> list[GreyPair]:
    """Every ``step``-th frame, ``step`` doubling whenever more than ``2 * limit`` are held: memory stays
    bounded on a long recording and the kept frames still span all of it."""
    kept: list[GreyPair] = []
    step = 1
    for k, frame in enumerate(frames):
        if k % step:
            continue
        kept.append(frame)
        if len(kept) > 2 * limit:
            kept, step = kept[::2], step * 2
    return kept


def read_pairs(source: StereoSource, *, sizes: Sizes = None) -> Iterator[GreyPair]:
    """``(name, left, right)`` grey (H, W) uint8 pairs of the recording, at most ``max_frames`` of them.

    Args:
        sizes: the profile's ``((w, h) left, (w, h) right)`` px: an image declaring another size is a CheckError
            naming its file (or bag topic and stamp, or video), before it is decoded.
    """
    if source.max_frames < 1:
        raise CheckError(f"must be at least 1, got {source.max_frames}", field="--max-frames", hint="e.g. 20")
    recording = open_recording(source.spec(), expected_size=sizes, grey=True, error=CheckError)
    if isinstance(recording, FileFrames):
        recording.indices = tuple(_spread(len(recording), source.max_frames))
        return ((f.name, f.left, f.right) for f in recording.frames())
    return _spread_stream(recording.frames(), source)


def _spread_stream(frames: Iterator[Any], source: StereoSource) -> Iterator[GreyPair]:
    kept = _decimated(((f.name, f.left, f.right) for f in frames), source.max_frames)
    if not kept:
        raise CheckError("no stereo pairs in the recording", path=source.describe(),
                         hint="check --left-topic and --right-topic (bags) or the video")
    for k in _spread(len(kept), source.max_frames):
        yield kept[k]


def profile_sizes(profile: StereoProfile) -> Sizes:
    """The ``sizes`` of :func:`read_pairs` for ``profile``'s two cameras."""
    return ((profile.left.width_px, profile.left.height_px), (profile.right.width_px, profile.right.height_px))
