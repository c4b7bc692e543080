"""Frames -> :class:`DepthView`: stereo pairs through the pipeline, device depth files, ROS bag topics."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.pipeline import StereoPipeline
from s2r.errors import DepthError
from s2r.imageio import decode_image_file
from s2r.profile import StereoProfile
from s2r.quality.bags import bag_pairs, decode_depth, decode_image
from s2r.quality.inputs import DEFAULT_DEPTH_SCALE_M, FramePaths, read_depth, read_grey
from s2r.quality.run import DepthView
from s2r.recordings import FrameSource
from s2r.recordings.files import FileFrames

__all__ = ["bag_device_views", "bag_stereo_views", "check_depth_size", "device_fb", "device_views", "frame_views",
           "stereo_fb",
           "stereo_view", "stereo_views", "stereo_visible_m"]


def stereo_fb(pipeline: StereoPipeline) -> float:
    """Rectified focal length (px) times baseline (m) of the pipeline's profile-size rectification."""
    return float(pipeline.rectification.fx_px * pipeline.rectification.baseline_m)


def stereo_visible_m(pipeline: StereoPipeline) -> tuple[float, float]:
    """Depth range (near, far metres) the pipeline's disparity range can see."""
    fb, cfg = stereo_fb(pipeline), pipeline.config
    return fb / max(cfg.min_disparity + cfg.num_disparities - 1, 1), fb / max(cfg.min_disparity, 0.5)


def device_fb(profile: StereoProfile) -> float:
    """Left focal length (px) times baseline (m): the disparity scale of depth in the left camera's grid."""
    return float(profile.left.fx_px * profile.baseline_m)


def _colour(path: Path) -> NDArray[np.uint8]:
    image, reason = decode_image_file(path, cv2.IMREAD_COLOR)
    if image is None:
        raise DepthError(reason, path=path, hint="pass PNG/JPEG images")
    return np.asarray(image, np.uint8)


class _Widening:
    """The pipeline with other disparity ranges (same profile, preset, rectification and post-processing), built
    once per range."""

    def __init__(self, pipeline: StereoPipeline) -> None:
        self.base = pipeline
        self.built: dict[int, StereoPipeline] = {}

    def pipeline(self, num_disparities: int) -> StereoPipeline:
        if num_disparities not in self.built:
            p = self.base
            self.built[num_disparities] = StereoPipeline(
                p.profile, preset=p.preset, alpha=p.alpha, num_disparities=num_disparities,
                postprocess=p.postprocess, resize=p.resize, fov_deg=p.fov_deg, rectified=p.rectified)
        return self.built[num_disparities]


def stereo_view(pipeline: StereoPipeline, name: str, left: NDArray[np.uint8], right: NDArray[np.uint8], *,
                widening: _Widening | None = None) -> DepthView:
    """One raw stereo pair through the pipeline: depth and grey image in the RECTIFIED left camera (no
    distortion, intrinsics ``P1[:3, :3]``); the view can be matched again with a wider disparity range."""
    result = pipeline.compute(left, right)
    geo = pipeline.geometry_for((left.shape[1], left.shape[0]))
    grey = result.rect_left if result.rect_left.ndim == 2 else cv2.cvtColor(result.rect_left, cv2.COLOR_BGR2GRAY)
    K = np.asarray(geo.rectification.P1[:3, :3], np.float64)
    widening = widening or _Widening(pipeline)

    def rematch(num_disparities: int) -> DepthView:
        return stereo_view(widening.pipeline(num_disparities), name, left, right, widening=widening)

    return DepthView(name, np.asarray(grey, np.uint8), result.depth, K, np.zeros(5),
                     disparity_range=(geo.config.min_disparity, geo.config.num_disparities), rematch=rematch)


def frame_views(pipeline: StereoPipeline, recording: FrameSource) -> Iterator[DepthView]:
    """A recording's stereo frames through the pipeline (see :func:`stereo_view`), one at a time, named by the frame.
    Grey still images go in as BGR (3 equal channels), as they always were read from files here."""
    colour = isinstance(recording, FileFrames)
    for frame in recording.frames():
        left, right = frame.left, frame.right
        if colour and left.ndim == 2:
            left = np.asarray(cv2.cvtColor(left, cv2.COLOR_GRAY2BGR), np.uint8)
            right = np.asarray(cv2.cvtColor(right, cv2.COLOR_GRAY2BGR), np.uint8)
        name = recording.pairs.left[frame.index].name if isinstance(recording, FileFrames) else frame.name
        yield stereo_view(pipeline, name, left, right)


def stereo_views(pipeline: StereoPipeline, frames: Sequence[FramePaths]) -> Iterator[DepthView]:
    """Stereo pairs on disk through the pipeline (see :func:`stereo_view`), read one at a time."""
    widening = _Widening(pipeline)
    for frame in frames:
        assert frame.right is not None
        yield stereo_view(pipeline, frame.left.name, _colour(frame.left), _colour(frame.right), widening=widening)


def device_views(profile: StereoProfile, frames: Sequence[FramePaths], *,
                 depth_scale_m: float = DEFAULT_DEPTH_SCALE_M) -> Iterator[DepthView]:
    """Device depth files registered to the left images, in the left camera (profile intrinsics, distortion).

    A frame's left path may be None-like (flat wall without images): then only the depth is read."""
    K, D = profile.left.K, profile.left.D
    for frame in frames:
        assert frame.depth is not None
        grey = read_grey(frame.left) if frame.left != frame.depth else None
        depth = check_depth_size(read_depth(frame.depth, scale_m=depth_scale_m), profile, name=str(frame.depth))
        if grey is not None and grey.shape != depth.shape:
            raise DepthError(f"left image is {grey.shape[1]}x{grey.shape[0]}, its depth image "
                             f"{depth.shape[1]}x{depth.shape[0]}", path=frame.left,
                             hint="pass depth registered to the left image (same size)")
        yield DepthView(frame.left.name if grey is not None else frame.depth.name, grey, depth, K, D)


def bag_stereo_views(pipeline: StereoPipeline, bag: Path, left_topic: str, right_topic: str, *,
                     max_dt_s: float) -> Iterator[DepthView]:
    """Stereo pairs from a bag's left and right image topics through the pipeline (see :func:`stereo_view`)."""
    widening = _Widening(pipeline)
    for name, (lm, lt), (rm, rt) in bag_pairs(bag, left_topic, right_topic, other_flag="--right-topic",
                                              max_dt_s=max_dt_s):
        yield stereo_view(pipeline, name, decode_image(lm, lt), decode_image(rm, rt), widening=widening)


def bag_device_views(profile: StereoProfile, bag: Path, left_topic: str, depth_topic: str, *, max_dt_s: float,
                     depth_scale_m: float = DEFAULT_DEPTH_SCALE_M) -> Iterator[DepthView]:
    """Left image and device depth topics of a bag, in the left camera (profile intrinsics, distortion)."""
    for name, (lm, lt), (dm, dt) in bag_pairs(bag, left_topic, depth_topic, other_flag="--depth-topic",
                                              max_dt_s=max_dt_s):
        image = decode_image(lm, lt)
        grey = image if image.ndim == 2 else np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), np.uint8)
        depth = check_depth_size(decode_depth(dm, dt, scale_m=depth_scale_m, name=name), profile, name=name)
        yield DepthView(name, grey, depth, profile.left.K, profile.left.D)


def check_depth_size(depth: NDArray[np.float32], profile: StereoProfile, *, name: str) -> NDArray[np.float32]:
    """``depth`` when it is (H, W) of the profile's left image; DepthError naming ``name`` and both sizes."""
    width, height = profile.left.width_px, profile.left.height_px
    if depth.shape != (height, width):
        shape = "x".join(str(v) for v in depth.shape[::-1])
        raise DepthError(f"depth image is {shape}, the profile {profile.name} expects {width}x{height}", path=name,
                         hint="pass depth registered to the left image at the profile's resolution")
    return depth
