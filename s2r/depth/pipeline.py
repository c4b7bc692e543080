"""The stereo depth pipeline: rectify with a profile, match with a preset, post-process, convert to depth.

    >>> pipe = StereoPipeline("realsense_d435_848x480", preset="fast")
    >>> result = pipe.compute(left_bgr, right_bgr)
    >>> result.depth            # (H, W) float32 metres along the rectified left optical axis, NaN invalid

The same code runs on any profile: ``StereoPipeline()`` uses the profile named by ``S2R_PROFILE``.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth import postprocess as pp
from s2r.depth.prerectified import given_rectification
from s2r.depth.presets import (
    DEFAULT_POSTPROCESS,
    PRESETS,
    MatcherConfig,
    create_matcher,
    preset_alpha,
    resolve_preset,
)
from s2r.depth.rectify import RectifyMaps, rectify_maps
from s2r.errors import DepthError
from s2r.profile import StereoProfile
from s2r.rectification import StereoRectification, stereo_rectification
from s2r.registry import load_profile

if TYPE_CHECKING:
    from s2r.depth.stream import DepthFrame

__all__ = ["PRESETS", "DepthResult", "StereoPipeline", "check_side_by_side"]

Image = NDArray[np.uint8]


@dataclass(frozen=True)
class DepthResult:
    """One stereo pair's output, everything in the RECTIFIED left camera's pixel grid and frame.

    Attributes:
        rect_left, rect_right: the rectified images the matcher saw ((H, W) grey or (H, W, 3) BGR uint8).
        disparity: (H, W) float32 pixels, ``x_right = x_left - disparity``; NaN where invalid.
        depth: (H, W) float32 metres along the rectified left optical axis; NaN where invalid (never 0).
        valid: (H, W) bool, True exactly where disparity and depth are finite.
        Q: 4x4 reprojection matrix mapping ``(x, y, disparity, 1)`` to homogeneous metres.
    """

    rect_left: Image
    rect_right: Image
    disparity: NDArray[np.float32]
    depth: NDArray[np.float32]
    valid: NDArray[np.bool_]
    Q: NDArray[np.float64]

    def point_cloud(self) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
        """Valid pixels as 3D points: ``(N, 3)`` float32 metres in the rectified left optical frame (x right,
        y down, z forward) and ``(N, 3)`` uint8 RGB colours from the rectified left image."""
        ys, xs = np.nonzero(self.valid)
        pix = np.stack([xs, ys, self.disparity[ys, xs], np.ones_like(xs)], axis=1).astype(np.float64)
        hom = pix @ self.Q.T
        points = (hom[:, :3] / hom[:, 3:4]).astype(np.float32)
        img = self.rect_left
        colours = np.repeat(img[ys, xs][:, None], 3, axis=1) if img.ndim == 2 else img[ys, xs][:, ::-1]
        return points, np.ascontiguousarray(colours, dtype=np.uint8)


@dataclass(frozen=True)
class _Geometry:
    """Everything fixed for one input image size: profile at that size, rectification, maps, matcher."""

    profile: StereoProfile
    rectification: StereoRectification
    maps: RectifyMaps
    config: MatcherConfig


class StereoPipeline:
    """Rectify (fixed-point maps computed once), match (a preset), post-process, and triangulate stereo pairs.

    Args:
        profile: a :class:`StereoProfile`, a profile name or YAML path; None uses ``S2R_PROFILE``.
        preset: one of :data:`PRESETS` (``profile`` uses the profile's own matcher settings).
        alpha: rectification free scaling (0 only valid pixels, 1 every source pixel, -1 OpenCV's own), as
            ``cv2.stereoRectify``; None: the preset's (``seed-sgbm``: -1, as the seed; others 0).
        num_disparities: disparity range in pixels (multiple of 16); None derives it from the profile's
            nearest working depth (``fx' * B / z_min``) or keeps the preset's fixed range.
        postprocess: stage names from :data:`s2r.depth.postprocess.STAGES`; None uses the preset's defaults.
        resize: accept images of another size by rescaling the intrinsics (``Camera.scaled``); otherwise a
            size mismatch is a :class:`DepthError`.
        fov_deg: fisheye (equidistant) profiles: horizontal field of view of the rectified images, degrees;
            None: OpenCV's balance ``alpha``, capped at ``s2r.rectification.DEFAULT_FISHEYE_FOV_DEG``.
        rectified: the pairs are already rectified and ``profile`` is their
            :func:`s2r.depth.prerectified.rectified_profile`: no resampling, the geometry taken as given.

    ``compute`` may be called from several threads at once (each thread gets its own OpenCV matcher).
    """

    def __init__(
        self,
        profile: StereoProfile | str | Path | None = None,
        *,
        preset: str = "profile",
        alpha: float | None = 0.0,
        num_disparities: int | None = None,
        postprocess: Sequence[str] | None = None,
        resize: bool = False,
        fov_deg: float | None = None,
        rectified: bool = False,
    ) -> None:
        if preset not in PRESETS:
            raise DepthError(f"unknown preset {preset!r}", field="preset", hint=f"choose one of {', '.join(PRESETS)}")
        self.profile: StereoProfile = profile if isinstance(profile, StereoProfile) else load_profile(profile)
        self.preset = preset
        self.alpha = preset_alpha(preset, self.profile) if alpha is None else float(alpha)
        self.num_disparities = num_disparities
        self.postprocess: tuple[str, ...] = pp.check_stages(
            DEFAULT_POSTPROCESS[preset] if postprocess is None else postprocess)
        self.resize = resize
        self.fov_deg = fov_deg
        self.rectified = rectified
        self._lock = threading.Lock()
        self._local = threading.local()
        base = self._build(self.profile)
        self._geometries: dict[tuple[int, int], _Geometry] = {self.profile.image_size: base}
        self.rectification: StereoRectification = base.rectification
        self.maps: RectifyMaps = base.maps
        self.config: MatcherConfig = base.config

    def _build(self, profile: StereoProfile) -> _Geometry:
        rect = given_rectification(profile) if self.rectified else stereo_rectification(
            profile, alpha=self.alpha, fov_deg=self.fov_deg)
        check_side_by_side(profile, rect)
        config = resolve_preset(self.preset, profile, fx_px=rect.fx_px, baseline_m=rect.baseline_m,
                                num_disparities=self.num_disparities)
        return _Geometry(profile=profile, rectification=rect, maps=rectify_maps(profile, rect), config=config)

    def __repr__(self) -> str:
        return (f"StereoPipeline({self.profile.name!r}, preset={self.preset!r}, "
                f"num_disparities={self.config.num_disparities}, postprocess={list(self.postprocess)})")

    @property
    def Q(self) -> NDArray[np.float64]:
        """4x4 reprojection matrix of the profile-size rectification."""
        return self.rectification.Q

    def geometry_for(self, size: tuple[int, int]) -> _Geometry:
        """The rectification for images of ``size`` ``(width, height)``; rescaled intrinsics with ``resize``."""
        geo = self._geometries.get(size)
        if geo is not None:
            return geo
        expected = self.profile.image_size
        if not self.resize:
            raise DepthError(
                f"images are {size[0]}x{size[1]} but profile {self.profile.name} is {expected[0]}x{expected[1]}",
                field="image size", hint="pass images of the profile's size, or let s2r rescale "
                "the intrinsics (--resize)")
        sx, sy = size[0] / expected[0], size[1] / expected[1]
        if abs(sx / sy - 1.0) > 0.01:  # another aspect ratio is a crop or another sensor mode, not a rescale
            raise DepthError(
                f"images are {size[0]}x{size[1]} but profile {self.profile.name} is {expected[0]}x{expected[1]}: "
                f"another aspect ratio ({size[0] / size[1]:.3f} vs {expected[0] / expected[1]:.3f}) means the camera "
                "crops, and rescaling the intrinsics would give wrong depth", field="image size",
                hint="use a profile of this image size (calibrate it or import the camera's own calibration)")
        with self._lock:
            geo = self._geometries.setdefault(size, self._build(_scaled_profile(self.profile, size)))
        return geo

    def _matchers(self, config: MatcherConfig) -> Any:
        cache: dict[int, Any] | None = getattr(self._local, "matchers", None)
        if cache is None:
            cache = self._local.matchers = {}
        key = id(config)
        if key not in cache:
            cache[key] = create_matcher(config)
        return cache[key]

    def rectify(self, left: Any, right: Any) -> tuple[Image, Image, _Geometry]:
        """Check and rectify a raw pair (grey or BGR uint8); grey presets convert to grey BEFORE remapping. A colour
        preset (``seed-sgbm``) given a grey pair sees it as ``cv2.imread`` gives a grey file to the seed: three equal
        channels, so its penalties (made for three channels) mean what they mean in the seed."""
        left, right = _as_image(left, "left"), _as_image(right, "right")
        if left.shape[:2] != right.shape[:2]:
            raise DepthError(f"left image is {left.shape[1]}x{left.shape[0]} but right is "
                             f"{right.shape[1]}x{right.shape[0]}", field="right", hint="pass a pair of one size")
        geo = self.geometry_for((left.shape[1], left.shape[0]))
        if geo.config.channels == 1 or left.ndim != right.ndim:
            left, right = _grey(left), _grey(right)
        elif left.ndim == 2:
            left, right = _bgr(left), _bgr(right)
        m = geo.maps
        rl: Image = cv2.remap(left, m.left_map1, m.left_map2, cv2.INTER_LINEAR)  # type: ignore[assignment]
        rr: Image = cv2.remap(right, m.right_map1, m.right_map2, cv2.INTER_LINEAR)  # type: ignore[assignment]
        return rl, rr, geo

    def match(self, rect_left: Image, rect_right: Image, geo: _Geometry) -> NDArray[np.int16]:
        """Fixed-point disparity (int16, px * 16) of a rectified pair after the post-processing stages."""
        # The right image's disparity (for lr-check) runs on a second thread beside the left one: OpenCV
        # releases the GIL and MODE_SGBM uses one core, so the check costs little extra wall time on 2 cores.
        right_job = (_right_pool().submit(self._right_disparity, rect_left, rect_right, geo)
                     if "lr-check" in self.postprocess else None)
        raw: NDArray[np.int16] = self._matchers(geo.config).compute(rect_left, rect_right)
        invalid = (geo.config.min_disparity - 1) * 16
        for stage in self.postprocess:
            if stage == "lr-check" and right_job is not None:
                raw = pp.lr_check(raw, right_job.result(), invalid=invalid,
                                  blind_px=geo.config.min_disparity + geo.config.num_disparities)
            elif stage == "speckle":
                raw = pp.speckle(raw, invalid=invalid, window_px=geo.config.speckle_window_size)
            elif stage == "median":
                raw = pp.median(raw, invalid=invalid)
            elif stage == "close":
                raw = pp.close(raw, invalid=invalid)
            elif stage == "seed-median":
                raw = pp.seed_median(raw)
            elif stage == "seed-close":
                raw = pp.seed_close(raw)
            else:
                raw = pp.fill_background(raw, invalid=invalid)
        return raw

    def _right_disparity(self, rect_left: Image, rect_right: Image, geo: _Geometry) -> NDArray[np.int16]:
        """Fixed-point disparity of the RIGHT image (x_left = x_right + d): the flipped pair matched as usual."""
        flipped = self._matchers(geo.config).compute(cv2.flip(rect_right, 1), cv2.flip(rect_left, 1))
        return np.asarray(cv2.flip(flipped, 1), np.int16)

    def stream(self, recording: Any, *, workers: int = 2, depth_range_m: tuple[float, float] | None = None
               ) -> Iterator[DepthFrame]:
        """Depth of every frame of a recording, in order, decoding, matching and the caller's own work overlapped
        (:func:`s2r.depth.stream.depth_frames`).

        Args:
            recording: a ``FrameSource`` (:func:`s2r.recordings.open_recording`: folders, globs, bags, videos), a
                :class:`s2r.recordings.RecordingSpec`, a folder path (``left/`` + ``right/``, ...), or any iterable
                of :class:`s2r.recordings.StereoFrame`. Images of another size than the profile's are refused
                from their headers, before decoding (unless ``resize``).
            workers: matching threads.
            depth_range_m: ``(near, far)`` metres; depths outside are invalid (default: all kept).

        Yields :class:`s2r.depth.stream.DepthFrame`: ``name``, ``stamp_ns``, ``frame_id`` and ``result``.
        """
        from s2r.depth.stream import depth_frames
        from s2r.recordings import RecordingSpec, open_recording

        size = None if self.resize or self.rectified else self.profile.image_size
        if isinstance(recording, (str, Path)):
            recording = open_recording(folder=Path(recording), expected_size=size, error=DepthError)
        elif isinstance(recording, RecordingSpec):
            recording = open_recording(recording, expected_size=size, error=DepthError)
        frames = recording.frames() if hasattr(recording, "frames") else recording
        return depth_frames(self, frames, workers=workers, depth_range_m=depth_range_m)

    def compute(self, left: Any, right: Any) -> DepthResult:
        """Depth of one raw (unrectified) stereo pair of the profile's size (grey or BGR uint8 arrays)."""
        rl, rr, geo = self.rectify(left, right)
        raw = self.match(rl, rr, geo)
        disparity, depth, valid = to_metric(raw, geo.rectification, min_disparity=geo.config.min_disparity)
        return DepthResult(rect_left=rl, rect_right=rr, disparity=disparity, depth=depth, valid=valid,
                           Q=geo.rectification.Q)


def check_side_by_side(profile: StereoProfile, rect: StereoRectification | None = None,
                       path: str | Path | None = None) -> None:
    """Refuse a rig the row-wise matcher cannot use: OpenCV rectifies a mostly vertical baseline into a
    vertical pair (``P2[1, 3] != 0``, rectified baseline 0), and a right camera left of the left one gives
    negative disparities; either way every pixel would come out invalid (or depth 0) without a word.

    Args:
        profile: the stereo profile.
        rect: its rectification (default: computed with alpha 0).
        path: the profile's file or name, for the error message.
    """
    rect = stereo_rectification(profile) if rect is None else rect
    tx_px, ty_px = float(rect.P2[0, 3]), float(rect.P2[1, 3])
    x, y, z = (float(v) for v in -profile.R.T @ profile.T)
    where = f"the right camera sits at ({x:+.3f}, {y:+.3f}, {z:+.3f}) m in the left optical frame"
    if abs(ty_px) > abs(tx_px):
        raise DepthError(f"vertical stereo rig ({where}): s2r matches along image rows, so it needs a "
                         "side-by-side pair", path=path, field="extrinsics.translation_m",
                         hint="rotate both images 90 degrees and use a profile of the rotated rig")
    if rect.baseline_m <= 0:
        raise DepthError(f"the 'right' camera is to the LEFT of the left one ({where}): disparities would be "
                         "negative", path=path, field="extrinsics.translation_m",
                         hint="swap the left and right images and the profile's cameras")


def _scaled_profile(profile: StereoProfile, size: tuple[int, int]) -> StereoProfile:
    """``profile`` at another image size: intrinsics scaled about pixel edges, a fixed disparity range scaled
    with the width (rounded up to 16)."""
    matcher = profile.matcher
    if matcher.num_disparities is not None:
        nd = int(np.ceil(matcher.num_disparities * size[0] / profile.image_size[0] / 16.0)) * 16
        matcher = matcher.model_copy(update={"num_disparities": max(16, nd)})
    return profile.model_copy(update={"left": profile.left.scaled(*size), "right": profile.right.scaled(*size),
                                      "matcher": matcher})


_POOL: list[ThreadPoolExecutor] = []
_POOL_LOCK = threading.Lock()


def _forget_pool_after_fork() -> None:
    # A forked child inherits the pool object but not its threads: submitting to it would wait forever.
    global _POOL_LOCK
    _POOL.clear()
    _POOL_LOCK = threading.Lock()


os.register_at_fork(after_in_child=_forget_pool_after_fork)


def _right_pool() -> ThreadPoolExecutor:
    with _POOL_LOCK:
        if not _POOL:
            _POOL.append(ThreadPoolExecutor(max_workers=2, thread_name_prefix="s2r-lr-check"))
        return _POOL[0]


def to_metric(
    raw: NDArray[np.int16], rect: StereoRectification, *, min_disparity: int = 0
) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.bool_]]:
    """Fixed-point disparity -> (disparity px, depth m, valid), NaN where no match or disparity <= 0 after
    the principal-point offset (depth would be infinite or negative)."""
    lowest = max(min_disparity * 16, int(np.floor(-16.0 * rect.doffs_px)) + 1)
    valid = raw >= lowest
    disparity = raw.astype(np.float32)
    disparity *= np.float32(1.0 / 16.0)
    disparity[~valid] = np.nan
    depth = np.float32(rect.fx_px * rect.baseline_m) / (disparity + np.float32(rect.doffs_px))
    return disparity, depth, valid


def _as_image(image: Any, name: str) -> Image:
    if not isinstance(image, np.ndarray):
        raise DepthError(f"expected a numpy image, got {type(image).__name__}", field=name,
                         hint="read it with cv2.imread or s2r.depth.outputs.read_image")
    if image.dtype != np.uint8:
        raise DepthError(f"expected 8-bit pixels, got {image.dtype}", field=name,
                         hint="convert to uint8 (e.g. scale 16-bit images by 1/256)")
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 3 and image.shape[2] == 4:
        image = np.asarray(cv2.cvtColor(image, cv2.COLOR_BGRA2BGR), np.uint8)
    if not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3)):
        raise DepthError(f"expected an (H, W) grey or (H, W, 3) BGR image, got shape {image.shape}", field=name,
                         hint="pass a grey or BGR image")
    return np.asarray(image, np.uint8)


def _bgr(image: Image) -> Image:
    return np.asarray(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR), np.uint8)


def _grey(image: Image) -> Image:
    return image if image.ndim == 2 else np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), np.uint8)
