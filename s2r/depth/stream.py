"""Depth on a stream of stereo frames: decode, match and hand over in overlapped stages on threads.

One reader thread pulls frames from the recording (decoding happens there: ``imdecode``, ``VideoCapture.read``),
``workers`` threads rectify and match (OpenCV releases the GIL in remap and the matchers), and the caller's own
thread consumes the results in recording order (a writer encodes PNGs or serialises bag messages there). At most
``2 * workers + 2`` frames are in flight, so a long recording never sits in memory.

    >>> for frame in StereoPipeline("realsense_d435_848x480").stream(recording):
    ...     frame.result.depth      # (H, W) float32 metres, rectified left optical frame, NaN invalid
    ...     frame.stamp_ns, frame.frame_id, frame.name

Frames: every output is in the RECTIFIED left camera's pixel grid and frame. :attr:`DepthFrame.frame_id` is the
left camera's optical frame (the profile's left ``frame_id``, or the input's when the profile has none); the
writers label their outputs with :func:`rectified_frame_id` of it (``cam_optical_frame`` ->
``cam_rect_optical_frame``) and publish that frame on ``/tf_static``, turned from the optical one by the
rectification's R1 (stereo_image_proc labels its outputs with the optical frame itself and leaves R1 out).
"""

from __future__ import annotations

import logging
import re
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from s2r.depth.outputs import limit_depth_range
from s2r.depth.pipeline import DepthResult
from s2r.errors import DepthError
from s2r.recordings.frames import StereoFrame

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline

__all__ = ["STAMP_SYNTHESIZED", "SYNTHETIC_PERIOD_NS", "SYNTHETIC_START_NS", "DepthFrame", "depth_frames", "frame_ids",
           "is_rectified_frame_id", "rectified_frame_id"]

log = logging.getLogger(__name__)

#: Still files carry no time: their stamps are synthesized as ``start + index * period`` (1 s, then 10 Hz), and
#: every output says so (``stamp_source: synthesized``).
SYNTHETIC_START_NS = 1_000_000_000
SYNTHETIC_PERIOD_NS = 100_000_000
STAMP_SYNTHESIZED = "synthesized"


@dataclass(frozen=True)
class DepthFrame:
    """One frame's depth with what names it.

    Attributes:
        index, name, source: the input frame's (see :class:`s2r.recordings.StereoFrame`).
        stamp_ns: the input left image's stamp in nanoseconds, or a synthesized one (``stamp_synthesized``).
        stamp_source: where ``stamp_ns`` comes from: the input frame's ``stamp_source`` (``recorded``, or ``file
            time`` for a video stamped from its file's modification time), or :data:`STAMP_SYNTHESIZED` when the
            input had no time (still files).
        frame_id: the left camera's optical frame (never empty); outputs are labelled with
            :func:`rectified_frame_id` of it.
        result: the depth, in the rectified left camera's grid and frame.
    """

    index: int
    name: str
    source: str
    stamp_ns: int
    stamp_source: str
    frame_id: str
    result: DepthResult

    @property
    def stamp_synthesized(self) -> bool:
        """Whether the input had no time (still files) and ``stamp_ns`` was made up."""
        return self.stamp_source == STAMP_SYNTHESIZED


def frame_ids(profile_left: str, profile_right: str, input_frame_id: str, profile_name: str) -> tuple[str, str]:
    """``(left, right)`` optical frame ids of the outputs: the profile's, else the input's, else one made from the
    profile's name (``NAME_left_optical_frame``, with a warning); the right one defaults to the left's with
    ``left`` replaced by ``right`` (or ``_right`` appended)."""
    left = profile_left or input_frame_id
    if not left:
        left = re.sub(r"[^A-Za-z0-9_]", "_", profile_name).strip("_") + "_left_optical_frame"
        log.warning("neither the profile nor the recording names a frame_id: the left optical frame is %r and the "
                    "depth data are labelled with its rectified frame %r", left, rectified_frame_id(left))
    right = profile_right or (left.replace("left", "right") if "left" in left else f"{left}_right")
    return left, right


def rectified_frame_id(optical: str) -> str:
    """The frame of the rectified left camera beside the optical frame ``optical``, named after REP 103's
    ``_optical`` suffix: ``cam_optical_frame`` -> ``cam_rect_optical_frame``, ``cam_optical`` ->
    ``cam_rect_optical``, any other ``cam`` -> ``cam_rect``. Its axes are the optical frame's turned by the
    rectification's R1 (``X_rect = R1 X_optical``), the same origin.

    A frame already named rectified (:func:`is_rectified_frame_id`: ``cam_rect_optical_frame``, what s2r labels its
    own outputs with) is returned as it is, never ``cam_rect_rect_optical_frame``: such input is rectified already,
    so its profile is the rectified cameras' (R1 = I) and the data stay in that frame (the writers then publish no
    transform of the frame into itself, and warn when R1 does turn). Only frame ids carry the suffix: output topics
    are fixed names under ``--namespace`` (``left/image_rect``, never made from the input's topics) and output files
    are named after the input frames as they are."""
    if is_rectified_frame_id(optical):
        return optical
    for suffix in ("_optical_frame", "_optical"):
        if optical.endswith(suffix):
            return optical[: -len(suffix)] + "_rect" + suffix
    return optical + "_rect"


def is_rectified_frame_id(frame_id: str) -> bool:
    """Whether ``frame_id`` names a rectified frame: ``_rect`` last, or before REP 103's ``_optical_frame`` /
    ``_optical`` suffix (``cam_rect``, ``cam_rect_optical``, ``cam_rect_optical_frame``)."""
    for suffix in ("_optical_frame", "_optical"):
        if frame_id.endswith(suffix):
            return frame_id[: -len(suffix)].endswith("_rect")
    return frame_id.endswith("_rect")


def _stamp(frame: StereoFrame, previous: int | None) -> tuple[int, str]:
    """The frame's stamp (ns) and where it comes from (``synthesized`` for still files); recorded stamps must not
    run backwards."""
    if frame.stamp_ns is None:
        return SYNTHETIC_START_NS + frame.index * SYNTHETIC_PERIOD_NS, STAMP_SYNTHESIZED
    if previous is not None and frame.stamp_ns < previous:
        log.warning("%s: stamp %d runs backwards (previous %d); kept as recorded", frame.source, frame.stamp_ns,
                    previous)
    return int(frame.stamp_ns), frame.stamp_source


def _compute(pipeline: StereoPipeline, read: Future[StereoFrame | None],
             depth_range_m: tuple[float, float] | None) -> tuple[StereoFrame, DepthResult] | None:
    frame = read.result()
    if frame is None:
        return None
    try:
        result = pipeline.compute(frame.left, frame.right)
    except DepthError as exc:  # e.g. one frame of another size: say which frame
        if exc.path is not None:
            raise
        raise DepthError(exc.message, path=frame.source, field=exc.field, hint=exc.hint) from None
    if depth_range_m is not None:
        result, _ = limit_depth_range(result, *depth_range_m)
    return frame, result


def depth_frames(pipeline: StereoPipeline, frames: Iterable[StereoFrame], *, workers: int = 2,
                 depth_range_m: tuple[float, float] | None = None) -> Iterator[DepthFrame]:
    """Depth of every frame of ``frames``, in order, computed ``workers`` frames at a time.

    Args:
        pipeline: the profile's pipeline (its ``compute`` is thread-safe).
        frames: any iterable of :class:`StereoFrame` (a ``FrameSource``'s ``frames()``); iterated on one reader
            thread, so its decoding overlaps the matching.
        workers: matching threads (>= 1).
        depth_range_m: ``(near, far)`` metres; depths outside are invalid (see ``limit_depth_range``).

    Errors (unreadable frame, size mismatch) propagate from the frame that failed, in order; stopping the
    iteration early cancels the frames not yet started.
    """
    if workers < 1:
        raise DepthError(f"must be at least 1, got {workers}", field="workers", hint="e.g. 2")
    source: Iterator[StereoFrame] = iter(frames)
    reader = ThreadPoolExecutor(1, thread_name_prefix="s2r-decode")
    computer = ThreadPoolExecutor(workers, thread_name_prefix="s2r-depth")
    pending: deque[Future[Any]] = deque()
    previous: int | None = None
    ids: dict[str, str] = {}  # input frame_id -> output frame_id (warned about once)
    try:
        while True:
            while len(pending) < 2 * workers + 2:  # reads past the end return None, and so do their computes
                read = reader.submit(next, source, None)
                pending.append(computer.submit(_compute, pipeline, read, depth_range_m))
            done = pending.popleft().result()
            if done is None:
                return
            frame, result = done
            stamp, stamp_source = _stamp(frame, previous)
            previous = stamp
            if frame.frame_id not in ids:
                ids[frame.frame_id] = frame_ids(pipeline.profile.left.frame_id, "", frame.frame_id,
                                                pipeline.profile.name)[0]
            yield DepthFrame(index=frame.index, name=frame.name, source=frame.source, stamp_ns=stamp,
                             stamp_source=stamp_source, frame_id=ids[frame.frame_id], result=result)
    finally:
        for pool in (reader, computer):
            pool.shutdown(wait=True, cancel_futures=True)
