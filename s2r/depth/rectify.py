"""Rectification maps of a profile: OpenCV's initUndistortRectifyMap, as fixed-point CV_16SC2 maps.

The rectifying rotations and projections come from :func:`s2r.rectification.stereo_rectification`, the same
call the renderer uses for its ground-truth disparity. Fisheye (``equidistant``) profiles use ``cv2.fisheye``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.profile import Camera, StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["RectifyMaps", "camera_maps", "rectify_maps"]


@dataclass(frozen=True)
class RectifyMaps:
    """Fixed-point remap tables for both cameras (``map1`` (H, W, 2) int16, ``map2`` (H, W) uint16).

    ``cv2.remap(image, map1, map2, cv2.INTER_LINEAR)`` turns a raw image into the rectified one.
    """

    left_map1: NDArray[np.int16]
    left_map2: NDArray[np.uint16]
    right_map1: NDArray[np.int16]
    right_map2: NDArray[np.uint16]


def camera_maps(
    camera: Camera, R: NDArray[np.float64], P: NDArray[np.float64], size: tuple[int, int]
) -> tuple[NDArray[np.int16], NDArray[np.uint16]]:
    """Fixed-point maps rectifying one camera, straight from ``initUndistortRectifyMap(..., CV_16SC2)``.

    That is the seed's call; it is the same format ``convertMaps`` makes from float maps (integer part in
    ``map1``, 1/32 px interpolation index in ``map2``), without building the float maps first, and it agrees with
    the seed's maps to the bit (float-then-convert rounds about 0.1 % of the fractional indices differently).

    Args:
        camera: the raw camera (K in pixels, distortion).
        R: 3x3 rectifying rotation (OpenCV's R1 or R2).
        P: 3x4 rectified projection (P1 or P2), pixels.
        size: ``(width, height)`` of the rectified image.
    """
    if camera.distortion.model == "equidistant":
        map1, map2 = cv2.fisheye.initUndistortRectifyMap(camera.K, camera.D, R, P[:, :3], size, cv2.CV_16SC2)
    else:
        map1, map2 = cv2.initUndistortRectifyMap(camera.K, camera.D, R, P, size, cv2.CV_16SC2)
    return np.asarray(map1, np.int16), np.asarray(map2, np.uint16)


def rectify_maps(profile: StereoProfile, rectification: StereoRectification) -> RectifyMaps:
    """Both cameras' fixed-point maps for ``rectification`` of ``profile``."""
    size = rectification.image_size
    lm1, lm2 = camera_maps(profile.left, rectification.R1, rectification.P1, size)
    rm1, rm2 = camera_maps(profile.right, rectification.R2, rectification.P2, size)
    return RectifyMaps(left_map1=lm1, left_map2=lm2, right_map1=rm1, right_map2=rm2)
