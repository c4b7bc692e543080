"""Drop-in names for code written against the seed tutorials, computed from any s2r profile.

``from s2r.compat import camera_configs`` (or ``import s2r.compat.camera_configs as camera_configs``) gives
the module-level names of the seed's ``camera_configs.py`` for the profile named by ``S2R_PROFILE``;
:func:`camera_config_values` computes the same names for an explicit profile.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from s2r.depth.rectify import rectify_maps
from s2r.profile import StereoProfile
from s2r.rectification import opencv_stereo_rectify, stereo_rectification
from s2r.registry import load_profile

__all__ = ["CAMERA_CONFIG_NAMES", "SEED_ALPHA", "camera_config_values", "stereo_rectify"]

#: ``cv2.stereoRectify`` accepting the seed's flat ``T`` (OpenCV 5 refuses a (3,) translation): code written
#: against the tutorial can call ``s2r.compat.stereo_rectify(...)`` with the seed's own arguments.
stereo_rectify = opencv_stereo_rectify

#: The names the seed's camera_configs.py defines, in its order.
CAMERA_CONFIG_NAMES: tuple[str, ...] = (
    "left_camera_matrix", "right_camera_matrix", "left_distortion", "right_distortion", "R", "T", "size",
    "R1", "R2", "P1", "P2", "Q", "left_map1", "left_map2", "right_map1", "right_map2",
)
#: The seed calls ``cv2.stereoRectify`` without ``alpha``: OpenCV's default -1 (its own scaling).
SEED_ALPHA = -1.0


def camera_config_values(profile: StereoProfile | str | Path | None = None) -> dict[str, Any]:
    """The seed's camera_configs names for ``profile`` (None: ``S2R_PROFILE``), as its OpenCV calls make them.

    ``stereoRectify`` with OpenCV's defaults (CALIB_ZERO_DISPARITY, alpha -1; balance 0 for fisheye lenses),
    then ``initUndistortRectifyMap`` as CV_16SC2 fixed-point maps. Camera matrices are 3x3 float64 (pixels),
    distortions (1, n) float64 in OpenCV's order, ``R`` 3x3 and ``T`` (3,) metres with
    ``X_right = R X_left + T``, ``size`` ``(width, height)``.
    """
    prof = profile if isinstance(profile, StereoProfile) else load_profile(profile)
    alpha = 0.0 if prof.left.distortion.model == "equidistant" else SEED_ALPHA
    rect = stereo_rectification(prof, alpha=alpha)
    maps = rectify_maps(prof, rect)
    return {
        "left_camera_matrix": prof.left.K, "right_camera_matrix": prof.right.K,
        "left_distortion": prof.left.D[None, :], "right_distortion": prof.right.D[None, :],
        "R": prof.R, "T": prof.T, "size": prof.image_size,
        "R1": rect.R1, "R2": rect.R2, "P1": rect.P1, "P2": rect.P2, "Q": rect.Q,
        "left_map1": maps.left_map1, "left_map2": maps.left_map2,
        "right_map1": maps.right_map1, "right_map2": maps.right_map2,
        "profile": prof, "valid_roi": (rect.roi_left, rect.roi_right), "baseline_m": np.float64(rect.baseline_m),
    }
