"""Matching a recording's stereo pairs for a drift check: the profile the check works with (a vertical rig turned on
its side), each pair's size checked against it, and the pairs matched in input order in one process or in
``--jobs`` worker processes (:func:`s2r.cvpool.opencv_pool`), with the same matches either way.
"""

from __future__ import annotations

import contextlib
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor

import numpy as np
from numpy.typing import NDArray

from s2r.cvpool import opencv_pool_or_none
from s2r.drift.matches import MAX_FEATURE_PIXELS, FrameMatches, match_frame
from s2r.drift.turned import Turn, side_by_side_turn
from s2r.errors import CheckError
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.rectification import StereoRectification, stereo_rectification

__all__ = ["check_image_sizes", "match_pairs", "working_profile"]


def check_image_sizes(profile: StereoProfile, name: str, left: NDArray[np.uint8], right: NDArray[np.uint8]) -> None:
    """CheckError naming frame ``name`` when an image is not the size its camera has in ``profile``."""
    for side, cam, image in (("left", profile.left, left), ("right", profile.right, right)):
        if image.shape[:2] != (cam.height_px, cam.width_px):
            raise CheckError(f"{side} image is {image.shape[1]}x{image.shape[0]} px but the profile "
                             f"{profile.name!r} has {cam.width_px}x{cam.height_px}", path=name, field="image size",
                             hint="check the recording with the profile of the camera that took it")


def working_profile(profile: StereoProfile) -> tuple[StereoProfile, StereoRectification, Turn | None]:
    """The profile the check works with (a vertical rig turned on its side), its rectification and the turn."""
    rect = stereo_rectification(profile)
    if abs(rect.P2[1, 3]) <= abs(rect.P2[0, 3]):
        _check_baseline(profile, rect)
        return profile, rect, None
    turn = side_by_side_turn(profile)  # OpenCV rectified it top-bottom: check it turned side by side
    turned = stereo_rectification(turn.profile)
    _check_baseline(profile, turned)
    return turn.profile, turned, turn


def _check_baseline(profile: StereoProfile, rect: StereoRectification) -> None:
    """CheckError (one line, exit 2) when the rectified rig has no usable baseline: a diagonal one (as far
    across as up, which neither a side-by-side nor a vertical rectification holds) or a right camera on the
    left of the profile's own left one."""
    if np.isfinite(rect.baseline_m) and rect.baseline_m > 1e-9 * max(profile.baseline_m, 1e-12):
        return
    x, y, z = (float(v) for v in -profile.R.T @ profile.T.reshape(3))
    raise CheckError(f"the right camera sits at ({x:+.3f}, {y:+.3f}, {z:+.3f}) m in the left optical frame: no "
                     "side-by-side or vertical rectification holds this baseline", path=profile.name,
                     field="extrinsics.translation_m",
                     hint="check the profile's T: a diagonal baseline is a calibration mistake; recalibrate "
                     "with s2r calibrate")


_Task = tuple[StereoProfile, StereoRectification, str, NDArray[np.uint8], NDArray[np.uint8]]


def _match_task(task: _Task) -> FrameMatches:
    """One pair's matches (a worker function: one picklable argument)."""
    return match_frame(task[0], task[1], task[3], task[4], name=task[2])


def _matching_pool(profile: StereoProfile, jobs: int, stack: contextlib.ExitStack) -> ProcessPoolExecutor | None:
    """The pool of :func:`match_pairs` (its workers forked now, before a reader or progress thread exists), or None
    to match in this process: one job, images over :data:`MAX_FEATURE_PIXELS` (read ahead for the workers and
    queued to them, 8192^2 pairs would break the 1 GB the single process keeps to), or no way to start workers."""
    if jobs <= 1 or profile.left.width_px * profile.left.height_px > MAX_FEATURE_PIXELS:
        return None
    return opencv_pool_or_none(jobs, stack, "matching")


def match_pairs(profile: StereoProfile, pairs: Iterable[tuple[str, NDArray[np.uint8], NDArray[np.uint8]]], *,
                progress: ProgressCallback | None = None, total: int | None = None, jobs: int = 1
                ) -> list[FrameMatches]:
    """Matched frames of raw grey pairs ``(name, left, right)`` for ``profile`` (turned for a vertical rig), in
    input order. With ``jobs`` > 1 the pairs are matched in that many worker processes (OpenCV single-threaded,
    :func:`s2r.cvpool.opencv_pool`), at most ``2 * jobs`` pairs in flight, so a long recording is never all in
    memory; the matches are the same as in one process.
    """
    working, rect, turn = working_profile(profile)

    def tasks() -> Iterator[_Task]:
        for name, left, right in pairs:
            check_image_sizes(profile, name, left, right)
            if turn is not None:
                left, right = turn.image(left), turn.image(right)
            yield working, rect, name, left, right

    frames: list[FrameMatches] = []

    def done(frame: FrameMatches) -> None:
        frames.append(frame)
        report(progress, len(frames), total or len(frames), "matching features")

    with contextlib.ExitStack() as stack:
        pool = _matching_pool(profile, jobs, stack)
        if pool is None:
            for task in tasks():
                done(_match_task(task))
        else:
            pending: deque[Future[FrameMatches]] = deque()
            for task in tasks():
                pending.append(pool.submit(_match_task, task))
                while len(pending) >= 2 * jobs:
                    done(pending.popleft().result())
            while pending:
                done(pending.popleft().result())
    if frames and total is not None and len(frames) < total:  # fewer pairs than --max-frames: the stage is over
        report(progress, len(frames), len(frames), "matching features")
    return frames
