"""Matcher presets: named OpenCV StereoSGBM / StereoBM configurations and their default post-processing.

A preset resolves against a profile into a :class:`MatcherConfig` (plain OpenCV parameter names, disparities in
pixels). Presets with a fixed disparity range from their source (``seed-sgbm`` 112, ``ros-default`` 64) keep it
unless ``num_disparities`` is given; the others derive it from the profile's nearest working depth
(``fx' * B / z_min + 1`` rounded up to 16). Either way a warning is logged when the range cannot see the profile's
stated working range.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import cv2

from s2r.depth.names import PRESETS
from s2r.errors import DepthError
from s2r.profile import MatcherSettings, StereoProfile

__all__ = ["DEFAULT_POSTPROCESS", "PRESETS", "MatcherConfig", "create_matcher", "preset_alpha", "resolve_preset"]

log = logging.getLogger(__name__)

#: Post-processing each preset applies when the caller gives none (names from s2r.depth.postprocess).
DEFAULT_POSTPROCESS: dict[str, tuple[str, ...]] = {
    "profile": ("lr-check", "speckle", "median"),
    # The seed verbatim: medianBlur 5, then a 3x3 morphological close, on the whole disparity image.
    "seed-sgbm": ("seed-median", "seed-close"),
    "fast": ("median",),
    "bm": (),
    "ros-default": (),
}

#: Rectification alpha a preset carries (``s2r depth`` without ``--alpha``; ``StereoPipeline(alpha=None)``): the
#: seed calls ``cv2.stereoRectify`` without alpha, i.e. OpenCV's -1. Others: 0 (only valid pixels).
PRESET_ALPHA: dict[str, float] = {"seed-sgbm": -1.0}


def preset_alpha(preset: str, profile: StereoProfile) -> float:
    """The rectification alpha of ``preset`` for ``profile``: :data:`PRESET_ALPHA`, else 0; 0 for a fisheye
    (equidistant) profile, whose balance has no -1 (as s2r.compat's camera_configs)."""
    if profile.left.distortion.model == "equidistant":
        return 0.0
    return PRESET_ALPHA.get(preset, 0.0)


_SGBM_MODES = {
    "sgbm": cv2.STEREO_SGBM_MODE_SGBM,
    "sgbm_3way": cv2.STEREO_SGBM_MODE_SGBM_3WAY,
    "hh": cv2.STEREO_SGBM_MODE_HH,
    "hh4": cv2.STEREO_SGBM_MODE_HH4,
}


@dataclass(frozen=True)
class MatcherConfig:
    """One matcher's full parameter set (OpenCV names; disparities and block sizes in pixels).

    ``algorithm`` is ``sgbm``/``sgbm_3way``/``hh``/``hh4`` (StereoSGBM modes) or ``bm`` (StereoBM);
    ``grey`` says whether the images are converted to grey before matching (colour SGBM uses 3 channels).
    ``p1``/``p2`` None mean the usual ``8 * cn * block^2`` / ``32 * cn * block^2``; ``pre_filter_cap`` None
    leaves OpenCV's default (StereoSGBM: 0, which SGBM treats as 15 internally), as a call that never sets it.
    """

    algorithm: str
    min_disparity: int
    num_disparities: int
    block_size: int
    grey: bool
    p1: int | None = None
    p2: int | None = None
    disp12_max_diff: int = 1
    uniqueness_ratio: int = 10
    speckle_window_size: int = 100
    speckle_range: int = 32
    pre_filter_cap: int | None = 63
    pre_filter_size: int = 9
    texture_threshold: int = 10

    @property
    def channels(self) -> int:
        """Image channels the matcher sees (1 grey, 3 colour)."""
        return 1 if self.grey or self.algorithm == "bm" else 3

    @property
    def penalties(self) -> tuple[int, int]:
        """SGBM smoothness penalties ``(P1, P2)``."""
        area = self.channels * self.block_size**2
        return (8 * area if self.p1 is None else self.p1, 32 * area if self.p2 is None else self.p2)


def _from_settings(m: MatcherSettings, num_disparities: int) -> MatcherConfig:
    return MatcherConfig(
        algorithm=m.algorithm, min_disparity=m.min_disparity, num_disparities=num_disparities,
        block_size=m.block_size, grey=True, p1=m.p1, p2=m.p2, disp12_max_diff=m.disp12_max_diff,
        uniqueness_ratio=m.uniqueness_ratio, speckle_window_size=m.speckle_window_size,
        speckle_range=m.speckle_range, pre_filter_cap=m.pre_filter_cap, texture_threshold=m.texture_threshold,
    )


def _base_config(preset: str, profile: StereoProfile, derived: int) -> MatcherConfig:
    if preset == "profile":
        nd = profile.matcher.num_disparities or derived
        return _from_settings(profile.matcher, nd)
    if preset == "seed-sgbm":
        # The seed tutorial, verbatim: only the arguments it passes (colour SGBM, numDisparities 112,
        # P1 = 8*3*5^2, P2 = 32*3*5^2, ...); preFilterCap and mode stay at OpenCV's defaults.
        return MatcherConfig(algorithm="sgbm", min_disparity=0, num_disparities=112, block_size=5, grey=False,
                             p1=8 * 3 * 25, p2=32 * 3 * 25, disp12_max_diff=1, uniqueness_ratio=10,
                             speckle_window_size=100, speckle_range=32, pre_filter_cap=None)
    if preset == "fast":
        return MatcherConfig(algorithm="sgbm_3way", min_disparity=0, num_disparities=derived, block_size=5,
                             grey=True, disp12_max_diff=1, uniqueness_ratio=10, speckle_window_size=100,
                             speckle_range=2)
    if preset == "bm":
        # XBot-U: cv2.StereoBM_create(16 * k, 15) with OpenCV's other defaults.
        return MatcherConfig(algorithm="bm", min_disparity=0, num_disparities=derived, block_size=15, grey=True,
                             disp12_max_diff=-1, uniqueness_ratio=15, speckle_window_size=0, speckle_range=0,
                             pre_filter_cap=31, pre_filter_size=9, texture_threshold=10)
    if preset == "ros-default":
        # stereo_image_proc's disparity node defaults (BM).
        return MatcherConfig(algorithm="bm", min_disparity=0, num_disparities=64, block_size=15, grey=True,
                             disp12_max_diff=-1, uniqueness_ratio=15, speckle_window_size=100, speckle_range=4,
                             pre_filter_cap=31, pre_filter_size=9, texture_threshold=10)
    raise DepthError(f"unknown preset {preset!r}", field="preset", hint=f"choose one of {', '.join(PRESETS)}")


def resolve_preset(
    preset: str, profile: StereoProfile, *, fx_px: float, baseline_m: float, num_disparities: int | None = None
) -> MatcherConfig:
    """The :class:`MatcherConfig` of ``preset`` for ``profile`` rectified to focal ``fx_px`` and ``baseline_m``.

    Warns (logging) when the disparity range cannot see down to ``profile.matcher.min_depth_m``; raises
    :class:`DepthError` when it does not fit the image width.
    """
    z_min = profile.matcher.min_depth_m
    # The largest disparity a range reaches is min_disparity + num_disparities - 1: z_min needs fB / z_min of it.
    needed = max(16, math.ceil((fx_px * baseline_m / z_min + 1) / 16.0) * 16)
    width = profile.image_size[0]
    # A derived range never exceeds the image: clamp it (the warning below then says what is lost).
    derived = min(needed, max(16, (width - 1) // 16 * 16))
    config = _base_config(preset, profile, derived)
    if num_disparities is not None:
        if num_disparities <= 0 or num_disparities % 16:
            raise DepthError(f"num_disparities must be a positive multiple of 16, got {num_disparities}",
                             field="num_disparities", hint="use 16, 32, 48, ...")
        config = replace(config, num_disparities=num_disparities)
    # OpenCV's matchers also need half a block beside the range (stereosgbm.cpp: "too small for your window size
    # and max disparity"): a derived range shrinks to fit; a given one is refused below.
    room = width - 1 - config.block_size // 2 - config.min_disparity
    if num_disparities is None and config.num_disparities > room and room >= 16:
        config = replace(config, num_disparities=room // 16 * 16)
    if config.min_disparity + config.num_disparities + config.block_size // 2 >= width:
        raise DepthError(
            f"disparity range {config.min_disparity}+{config.num_disparities} px and the {config.block_size} px "
            f"block do not fit the {width} px image",
            field="num_disparities", hint="pass a smaller num_disparities or raise matcher.min_depth_m")
    nearest = fx_px * baseline_m / max(config.min_disparity + config.num_disparities - 1, 1)
    if nearest > z_min * 1.0001:
        log.warning("preset %s sees no nearer than %.3f m with %d disparities; the profile %s works from %.3f m "
                    "(it needs num_disparities=%d)", preset, nearest, config.num_disparities, profile.name, z_min,
                    max(16, math.ceil((fx_px * baseline_m / z_min + 1 - config.min_disparity) / 16.0) * 16))
    return config


def create_matcher(config: MatcherConfig) -> cv2.StereoBM | cv2.StereoSGBM:
    """A fresh OpenCV matcher for ``config`` (StereoSGBM or StereoBM); one per thread, they are not re-entrant."""
    if config.algorithm == "bm":
        bm = cv2.StereoBM.create(config.num_disparities, config.block_size)
        bm.setMinDisparity(config.min_disparity)
        if config.pre_filter_cap is not None:
            bm.setPreFilterCap(config.pre_filter_cap)
        bm.setPreFilterSize(config.pre_filter_size)
        bm.setTextureThreshold(config.texture_threshold)
        bm.setUniquenessRatio(config.uniqueness_ratio)
        bm.setSpeckleWindowSize(config.speckle_window_size)
        bm.setSpeckleRange(config.speckle_range)
        bm.setDisp12MaxDiff(config.disp12_max_diff)
        return bm
    p1, p2 = config.penalties
    # Only what the config sets: a None preFilterCap and the default mode are left to OpenCV, so a preset that
    # copies a call (seed-sgbm) builds exactly that call's matcher.
    optional: dict[str, int] = {}
    if config.pre_filter_cap is not None:
        optional["preFilterCap"] = config.pre_filter_cap
    if config.algorithm != "sgbm":
        optional["mode"] = _SGBM_MODES[config.algorithm]
    return cv2.StereoSGBM.create(
        minDisparity=config.min_disparity, numDisparities=config.num_disparities, blockSize=config.block_size,
        P1=p1, P2=p2, disp12MaxDiff=config.disp12_max_diff, uniquenessRatio=config.uniqueness_ratio,
        speckleWindowSize=config.speckle_window_size, speckleRange=config.speckle_range, **optional,
    )
