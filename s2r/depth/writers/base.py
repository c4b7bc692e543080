"""The one interface of stream writers, and the loop that feeds one."""

from __future__ import annotations

import abc
import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from s2r.errors import DepthError
from s2r.progress import ProgressCallback, report

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.depth.stream import DepthFrame
    from s2r.rectification import StereoRectification

__all__ = ["TARGETS", "StreamOptions", "StreamWriter", "open_writer", "write_stream"]

log = logging.getLogger(__name__)

#: A rectification turning the left camera by more than this (degrees) is not the identity of rectified input.
RECTIFIED_TURN_DEG = 0.01

#: Output targets of ``s2r depth --to``.
TARGETS: tuple[str, ...] = ("files", "ros2", "ros1")


@dataclass(frozen=True)
class StreamOptions:
    """What a writer writes beside depth.

    Attributes:
        namespace: ROS topic namespace (bags), e.g. ``/stereo``.
        depth_encoding: bags' depth image: ``32FC1`` metres (NaN invalid) or ``16UC1`` millimetres (0 invalid).
        points: bags: PointCloud2 on ``points2``; files: a PLY per frame.
        pcd: files: a binary PCD per frame.
        colour_range_m: files: the fixed (near, far) colour scale of ``color/NAME.png`` (default each frame's).
    """

    namespace: str = "/stereo"
    depth_encoding: str = "32FC1"
    points: bool = False
    pcd: bool = False
    colour_range_m: tuple[float, float] | None = None


class StreamWriter(abc.ABC):
    """Writes depth frames to one target; nothing is visible at ``out`` before :meth:`publish`.

    Use as a context manager: leaving it without publishing discards everything staged.
    """

    def __init__(self, out: Path, pipeline: StereoPipeline, *, force: bool, options: StreamOptions) -> None:
        self.out = Path(out)
        self.pipeline = pipeline
        self.force = force
        self.options = options
        self.frames = 0
        self._rects: dict[tuple[int, int], StereoRectification] = {}
        self._warned_rectified = False

    def __enter__(self) -> StreamWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.discard()

    def rectification(self, frame: DepthFrame) -> StereoRectification:
        """The rectification of ``frame``'s image size (the profile's, or rescaled with ``resize``)."""
        h, w = frame.result.disparity.shape
        if (w, h) not in self._rects:
            self._rects[(w, h)] = self.pipeline.geometry_for((w, h)).rectification
        return self._rects[(w, h)]

    def rect_frame_id(self, frame: DepthFrame) -> str:
        """The frame the outputs of ``frame`` are labelled with (:func:`s2r.depth.stream.rectified_frame_id`); warns
        once when the input's frame is rectified already yet this profile's rectification turns it (R1 not I)."""
        from s2r.depth.stream import is_rectified_frame_id, rectified_frame_id

        if is_rectified_frame_id(frame.frame_id) and not self._warned_rectified:
            R1 = np.asarray(self.rectification(frame).R1, np.float64)
            turn_deg = math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(R1)) - 1.0) / 2.0))))
            if turn_deg > RECTIFIED_TURN_DEG:
                log.warning("%s: the input's frame %s is rectified already, yet profile %s rectifies it again (a "
                            "%.3f deg turn): its depth is labelled %s; give the profile of the rectified cameras",
                            frame.source, frame.frame_id, self.pipeline.profile.name, turn_deg, frame.frame_id)
            self._warned_rectified = True
        return rectified_frame_id(frame.frame_id)

    @abc.abstractmethod
    def write(self, frame: DepthFrame) -> None:
        """Stage one frame (in recording order)."""

    @abc.abstractmethod
    def publish(self) -> list[Path]:
        """Make the output appear whole; the paths published. DepthError when no frame was written."""

    @abc.abstractmethod
    def discard(self) -> None:
        """Remove everything staged and not published (safe to call twice)."""

    def _check_frames(self) -> None:
        if not self.frames:
            raise DepthError("the recording gave no frames; nothing was written", path=self.out,
                             hint="check the recording inputs (--every / --max-frames may have skipped all)")


def open_writer(target: str, out: str | Path, pipeline: StereoPipeline, *, force: bool = False,
                options: StreamOptions | None = None) -> StreamWriter:
    """The writer of ``target`` (one of :data:`TARGETS`) for ``out``; refuses an output it may not replace now,
    before any frame is computed."""
    opts = options or StreamOptions()
    if target == "files":
        from s2r.depth.writers.files import FilesWriter

        return FilesWriter(Path(out), pipeline, force=force, options=opts)
    if target in ("ros1", "ros2"):
        from s2r.depth.writers.rosbag import RosBagWriter

        return RosBagWriter(Path(out), pipeline, force=force, options=opts, ros1=target == "ros1")
    raise DepthError(f"unknown output target {target!r}", field="--to", hint=f"choose one of {', '.join(TARGETS)}")


def write_stream(writer: StreamWriter, frames: Iterable[DepthFrame], *, progress: ProgressCallback | None = None,
                 total: int | None = None) -> int:
    """Feed every frame to ``writer`` (in the caller's thread, overlapping the matching threads); the count."""
    count = 0
    for frame in frames:
        writer.write(frame)
        count += 1
        report(progress, count, total if total is not None else 0, "depth")
    return count

