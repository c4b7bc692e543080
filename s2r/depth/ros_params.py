"""stereo_image_proc's disparity parameters for a matcher configuration, inside the ranges ROS accepts.

stereo_image_proc (ROS 1 image_pipeline 1.17, ``cfg/Disparity.cfg`` and ``DisparityNodelet::configCb``) matches
the rectified MONO images with OpenCV's StereoBM or StereoSGBM (``fullDP`` picks MODE_HH; MODE_SGBM_3WAY and
MODE_HH4 are not reachable). Its dynamic_reconfigure ranges bound what a preset can say: ``speckle_range``
0..31, ``disparity_range`` 32..4096 rounded DOWN to a multiple of 16, ``correlation_window_size`` 5..255 and
odd, ``prefilter_cap`` 1..63, ``P1``/``P2`` 0..4000, ``speckle_size`` 0..1000, ``disp12MaxDiff`` 0..128. A value
outside is clamped here, and each clamp is returned as a note (the caller warns): never silently.
"""

from __future__ import annotations

import logging
from typing import Any

import yaml

from s2r.depth.presets import MatcherConfig, resolve_preset
from s2r.profile import StereoProfile
from s2r.rectification import stereo_rectification

__all__ = ["ROS_DISPARITY_FILE", "ROS_DISPARITY_RANGES", "ros_disparity_file", "ros_disparity_params",
           "ros_disparity_yaml"]

log = logging.getLogger(__name__)
#: Name of the parameter file ``convert --to ros`` writes beside left.yaml and right.yaml.
ROS_DISPARITY_FILE = "stereo_image_proc.yaml"

#: stereo_image_proc's parameter ranges (Disparity.cfg), inclusive.
ROS_DISPARITY_RANGES: dict[str, tuple[int, int]] = {
    "prefilter_size": (5, 255), "prefilter_cap": (1, 63), "correlation_window_size": (5, 255),
    "min_disparity": (-2048, 2048), "disparity_range": (32, 4096), "uniqueness_ratio": (0, 100),
    "texture_threshold": (0, 10000), "speckle_size": (0, 1000), "speckle_range": (0, 31), "P1": (0, 4000),
    "P2": (0, 4000), "disp12MaxDiff": (0, 128),
}
#: SGBM treats a preFilterCap below 15 (OpenCV's default 0 included) as 15: ``max(cap, 15) | 1``.
_SGBM_MIN_CAP = 15


def _wanted(config: MatcherConfig) -> tuple[dict[str, Any], list[str]]:
    notes: list[str] = []
    params: dict[str, Any] = {
        "correlation_window_size": config.block_size, "min_disparity": config.min_disparity,
        "disparity_range": config.num_disparities, "uniqueness_ratio": config.uniqueness_ratio,
        "speckle_size": config.speckle_window_size, "speckle_range": config.speckle_range,
    }
    if config.algorithm == "bm":
        params.update(stereo_algorithm=0, prefilter_size=config.pre_filter_size,
                      texture_threshold=config.texture_threshold,
                      prefilter_cap=31 if config.pre_filter_cap is None else config.pre_filter_cap)
        return params, notes
    if config.algorithm in ("sgbm_3way", "hh4"):
        notes.append(f"mode {config.algorithm} is not available in stereo_image_proc (SGBM or full DP only): "
                     "SGBM set, its disparities will differ")
    p1, p2 = config.penalties
    params.update(stereo_algorithm=1, fullDP=config.algorithm == "hh", P1=p1, P2=p2,
                  disp12MaxDiff=config.disp12_max_diff,
                  prefilter_cap=max(_SGBM_MIN_CAP, config.pre_filter_cap or 0))
    if not config.grey:
        notes.append(f"P1 {p1} and P2 {p2} were chosen for colour images; stereo_image_proc matches grey ones")
    return params, notes


def ros_disparity_params(config: MatcherConfig) -> tuple[dict[str, Any], list[str]]:
    """``(params, notes)``: the disparity node's private parameters for ``config`` (ROS names), each clamped into
    :data:`ROS_DISPARITY_RANGES`; ``notes`` names every value changed and every setting ROS cannot express."""
    params, notes = _wanted(config)
    for name, value in list(params.items()):
        if name not in ROS_DISPARITY_RANGES or isinstance(value, bool):
            continue
        low, high = ROS_DISPARITY_RANGES[name]
        fixed = min(max(int(value), low), high)
        if name == "disparity_range":
            fixed = fixed // 16 * 16
        if name == "correlation_window_size" and fixed % 2 == 0:
            fixed += 1
        if fixed != value:
            notes.append(f"{name} {value} is outside stereo_image_proc's range {low}..{high}"
                         + (" (a multiple of 16)" if name == "disparity_range" else "") + f": set to {fixed}")
        params[name] = fixed
    return params, notes


def ros_disparity_yaml(config: MatcherConfig, *, profile_name: str) -> tuple[str, list[str]]:
    """``(text, notes)``: a rosparam file for the disparity node (``rosparam load FILE /NS/disparity``)."""
    params, notes = ros_disparity_params(config)
    header = [f"# stereo_image_proc disparity parameters for s2r profile {profile_name}",
              "# load: rosparam load stereo_image_proc.yaml /<stereo namespace>/<disparity node>"]
    header += [f"# changed: {note}" for note in notes]
    return "\n".join(header) + "\n" + yaml.safe_dump(params, sort_keys=True), notes


def ros_disparity_file(profile: StereoProfile) -> dict[str, str]:
    """``{ROS_DISPARITY_FILE: text}`` for ``profile``'s matcher (its ``profile`` preset, the disparity range
    derived as ``s2r depth`` derives it), each clamp logged as a warning; empty for a vertical pair
    (stereo_image_proc matches along rows only)."""
    if abs(profile.T[1]) > abs(profile.T[0]):
        return {}
    rect = stereo_rectification(profile, alpha=0.0)
    config = resolve_preset("profile", profile, fx_px=float(rect.P1[0, 0]), baseline_m=rect.baseline_m)
    text, notes = ros_disparity_yaml(config, profile_name=profile.name)
    for note in notes:
        log.warning("%s: %s", ROS_DISPARITY_FILE, note)
    return {ROS_DISPARITY_FILE: text}
