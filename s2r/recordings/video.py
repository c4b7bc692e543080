"""Stereo frames from videos through OpenCV's ``VideoCapture`` (its FFmpeg backend: H.264, mp4v, MJPG, ...),
streamed one frame at a time, never the whole video in memory.

- :class:`VideoFrames`: one file holding both images, ``sbs`` (left | right side by side, each half the width) or
  ``tb`` (left over right, each half the height);
- :class:`TwoVideoFrames`: two files, paired by frame index; their frame counts must agree.

The size a video declares (``CAP_PROP_FRAME_WIDTH`` / ``CAP_PROP_FRAME_HEIGHT``) is checked against the expected
camera size and the pixel limit before the first frame is decoded, and every decoded frame must have it. Skipped
frames (``every``) are only grabbed, not converted. Frames are named ``frame_000123`` (0-based index in the file).

Stamps: a video holds times from its own start only (its frames' presentation times, ``CAP_PROP_POS_MSEC``; index /
fps when the container gives none), and ROS reads a stamp of 0 as "unset". Each frame is stamped ``start +`` its
time in the video, where ``start`` is the ``start_ns`` given (``--start-stamp``: when the recording began) or else
the file's modification time (a camera or phone writes the file as it records; a copy made without keeping times
moves it). The left video's times pair two videos.

A video that ends before the frame count its container states is refused as truncated; one without a frame is
refused as empty.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import S2RError
from s2r.imageio import native_stderr_silenced
from s2r.recordings.decode import SizeRule, to_uint8
from s2r.recordings.frames import STAMP_FILE_TIME, STAMP_RECORDED, StereoFrame, thinned

__all__ = ["LAYOUTS", "TwoVideoFrames", "VideoFrames"]

#: Single-file layouts: side by side (left | right) and top/bottom (left over right).
LAYOUTS = ("sbs", "tb")
_HINT = "pass a video file OpenCV reads (H.264 / mp4v .mp4, MJPG .avi, ...)"
#: Containers whose frame count FFmpeg reads from an index (exact). Elsewhere (Matroska, WebM, MPEG-TS, ...) OpenCV
#: estimates it from the duration and the frame rate, which an audio track longer than the video inflates: there
#: the count is no evidence of truncation, and two videos are compared by the frames they decode.
_INDEXED_SUFFIXES = frozenset({".mp4", ".m4v", ".mov", ".avi"})


class _Capture:
    """One opened video: its declared width, height, frame count (0 when the container does not say) and fps."""

    def __init__(self, path: Path, *, error: type[S2RError], option: str) -> None:
        self.path, self.error, self.option = Path(path), error, option
        try:
            info = os.stat(self.path)
        except FileNotFoundError:
            raise error("video not found", path=self.path, field=option, hint="check the path") from None
        except OSError as exc:
            raise error(f"cannot read the video: {exc.strerror}", path=self.path, field=option, hint=_HINT) from None
        if not stat.S_ISREG(info.st_mode):
            raise error("not a regular file (a folder, device, FIFO or socket): s2r reads video files only",
                        path=self.path, field=option, hint=_HINT)
        if info.st_size == 0:
            raise error("the video file is empty", path=self.path, field=option, hint=_HINT)
        self.mtime_ns = info.st_mtime_ns
        with native_stderr_silenced():  # FFmpeg's own lines ("moov atom not found"): s2r says it in one line
            self.cap = cv2.VideoCapture(str(self.path), cv2.CAP_FFMPEG)
        if not self.cap.isOpened():
            self.cap.release()
            raise error("cannot open the video (not a video, or truncated before its index)", path=self.path,
                        field=option, hint=_HINT)
        self.width = int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        declared = max(0, int(self.cap.get(cv2.CAP_PROP_FRAME_COUNT)))
        self.count = declared if self.path.suffix.lower() in _INDEXED_SUFFIXES else 0  # 0: unknown (an estimate)
        self.fps = float(self.cap.get(cv2.CAP_PROP_FPS))
        if self.width <= 0 or self.height <= 0:
            self.release()
            raise error("the video declares no frame size (no video stream)", path=self.path, field=option,
                        hint=_HINT)

    def stamp_ns(self, index: int, start_ns: int | None) -> int:
        """The stamp (ns since the Unix epoch) of frame ``index``, the one last grabbed: ``start_ns`` (default the
        file's modification time) plus the frame's presentation time in the video (index / fps when the container
        gives none; 0 when neither is known)."""
        msec = float(self.cap.get(cv2.CAP_PROP_POS_MSEC))
        if np.isfinite(msec) and msec >= 0 and (msec > 0 or index == 0):
            offset = round(msec * 1e6)
        elif self.fps > 0 and np.isfinite(self.fps):
            offset = round(index * 1e9 / self.fps)
        else:
            offset = 0
        return (self.mtime_ns if start_ns is None else start_ns) + offset

    def grab(self, read: int) -> bool:
        """Advance one frame; False at the end. An end before the declared count (less one, as containers round
        it) raises the error naming the truncation; a video without any frame is refused as empty."""
        with native_stderr_silenced():
            if self.cap.grab():
                return True
        if read == 0:
            raise self.error("the video holds no frames", path=self.path, field=self.option, hint=_HINT)
        if self.count and read < self.count - 1:
            raise self.error(f"the video ends after {read} of the {self.count} frames it declares: truncated",
                             path=self.path, field=self.option, hint="copy the whole file again")
        return False

    def retrieve(self, index: int) -> NDArray[Any]:
        """The frame last grabbed (BGR or grey), which must have the declared size."""
        with native_stderr_silenced():
            ok, frame = self.cap.retrieve()
        if not ok or frame is None:
            raise self.error(f"frame {index} cannot be decoded", path=self.path, field=self.option,
                             hint="the video is damaged")
        if frame.shape[:2] != (self.height, self.width):
            raise self.error(f"frame {index} is {frame.shape[1]}x{frame.shape[0]} px but the video declares "
                             f"{self.width}x{self.height}", path=self.path, field=self.option, hint=_HINT)
        return np.asarray(frame)

    def release(self) -> None:
        """Close the capture."""
        self.cap.release()


def _grabbed(cap: _Capture) -> Iterator[int]:
    """Grab the video's frames one at a time (not converted), yielding each one's index."""
    index = 0
    while cap.grab(index):
        yield index
        index += 1


def _halves(frame: NDArray[Any], layout: str) -> tuple[NDArray[Any], NDArray[Any]]:
    if layout == "sbs":
        half = frame.shape[1] // 2
        return frame[:, :half], frame[:, half:]
    half = frame.shape[0] // 2
    return frame[:half], frame[half:]


def _stamp_source(start_ns: int | None) -> str:
    """A video frame's :attr:`StereoFrame.stamp_source`: recorded from ``--start-stamp``, else the file time."""
    return STAMP_FILE_TIME if start_ns is None else STAMP_RECORDED


@dataclass
class VideoFrames:
    """One video holding both images in ``layout`` ('sbs' or 'tb'); ``every``-th frame, at most ``max_frames``;
    ``start_ns``: the stamp of the video's start, ns since the Unix epoch (default the file's modification time)."""

    video: Path
    layout: str = "sbs"
    rule: SizeRule = field(default_factory=SizeRule)
    grey: bool = False
    every: int = 1
    max_frames: int | None = None
    start_ns: int | None = None

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise self.rule.error(f"unknown layout {self.layout!r}", field="--layout",
                                  hint="sbs (left | right side by side) or tb (left over right)")
        self._open().release()

    def _open(self) -> _Capture:
        cap = _Capture(self.video, error=self.rule.error, option="--video")
        sbs = self.layout == "sbs"
        if (cap.width if sbs else cap.height) % 2:
            cap.release()
            raise self.rule.error(f"the video is {cap.width}x{cap.height} px: an odd {'width' if sbs else 'height'}"
                                  f" cannot be split {'side by side' if sbs else 'top/bottom'}", path=self.video,
                                  field="--layout", hint="check --layout (sbs or tb)")
        w, h = (cap.width // 2, cap.height) if sbs else (cap.width, cap.height // 2)
        try:
            for side in ("left", "right"):
                self.rule.check(w, h, side, where=str(self.video), field=f"--video ({self.layout})")
        except BaseException:
            cap.release()
            raise
        return cap

    def describe(self) -> str:
        """The video and its layout."""
        return f"video {self.video} ({self.layout})"

    def frames(self) -> Iterator[StereoFrame]:
        """Decoded frames split into left and right, one at a time."""
        cap = self._open()
        try:
            for index, _ in thinned(_grabbed(cap), self.every, self.max_frames):
                left, right = _halves(cap.retrieve(index), self.layout)
                yield StereoFrame(index=index, name=f"frame_{index:06d}", stamp_ns=cap.stamp_ns(index, self.start_ns),
                                  frame_id="", left=to_uint8(left, grey=self.grey),
                                  right=to_uint8(right, grey=self.grey), source=f"video {self.video} frame {index}",
                                  stamp_source=_stamp_source(self.start_ns))
        finally:
            cap.release()


@dataclass
class TwoVideoFrames:
    """A left and a right video paired by frame index; ``every``-th frame, at most ``max_frames``; ``start_ns`` as
    :class:`VideoFrames` (default the left file's modification time)."""

    left_video: Path
    right_video: Path
    rule: SizeRule = field(default_factory=SizeRule)
    grey: bool = False
    every: int = 1
    max_frames: int | None = None
    start_ns: int | None = None

    def __post_init__(self) -> None:
        for cap in self._open():
            cap.release()

    def _open(self) -> tuple[_Capture, _Capture]:
        left = _Capture(self.left_video, error=self.rule.error, option="--left-video")
        try:
            right = _Capture(self.right_video, error=self.rule.error, option="--right-video")
        except BaseException:
            left.release()
            raise
        try:
            self.rule.check(left.width, left.height, "left", where=str(self.left_video), field="--left-video")
            self.rule.check(right.width, right.height, "right", where=str(self.right_video), field="--right-video")
            if left.count and right.count and left.count != right.count:
                raise self._mismatch(f"the left video has {left.count} frames but the right one {right.count}")
        except BaseException:
            left.release()
            right.release()
            raise
        return left, right

    def _mismatch(self, counts: str) -> S2RError:
        return self.rule.error(f"{counts}: they cannot be paired by frame index",
                               path=f"{self.left_video} + {self.right_video}",
                               field="--left-video/--right-video", hint="pass two recordings of the same frames")

    def describe(self) -> str:
        """The two videos."""
        return f"videos {self.left_video} + {self.right_video}"

    def frames(self) -> Iterator[StereoFrame]:
        """Decoded frame pairs, one at a time; a video ending before the other is refused."""
        left, right = self._open()
        try:
            for index, _ in thinned(self._grabbed_pairs(left, right), self.every, self.max_frames):
                yield StereoFrame(index=index, name=f"frame_{index:06d}", stamp_ns=left.stamp_ns(index, self.start_ns),
                                  frame_id="", left=to_uint8(left.retrieve(index), grey=self.grey),
                                  right=to_uint8(right.retrieve(index), grey=self.grey),
                                  source=f"videos {self.left_video.name} + {self.right_video.name} frame {index}",
                                  stamp_source=_stamp_source(self.start_ns))
        finally:
            left.release()
            right.release()

    def _grabbed_pairs(self, left: _Capture, right: _Capture) -> Iterator[int]:
        """Grab a frame of each video at a time, yielding its index; a video ending before the other is refused."""
        index = 0
        while True:
            more_left, more_right = left.grab(index), right.grab(index)
            if more_left != more_right:
                short, other = ("left", "right") if more_right else ("right", "left")
                raise self._mismatch(f"the {short} video ends after {index} frames but the {other} one has more")
            if not more_left:
                return
            yield index
            index += 1
