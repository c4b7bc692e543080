"""Stereo rectification of a profile (OpenCV's stereoRectify), shared by every stage that needs it.

The depth pipeline, the renderer's ground-truth disparity, calibration's epipolar check and the ROS
camera_info export all rectify through :func:`stereo_rectification`, so they agree to the bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import S2RError
from s2r.profile import StereoProfile

__all__ = ["StereoRectification", "stereo_rectification"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StereoRectification:
    """Rectifying rotations and projections (OpenCV's R1 R2 P1 P2 Q) of a stereo profile.

    ``R1``/``R2`` rotate the left/right optical frames into the common rectified frame; ``P1``/``P2``
    are the 3x4 projections of the rectified cameras (``P2[0, 3] = -fx' * B``); ``Q`` maps
    ``(x, y, disparity, 1)`` in the rectified left image to homogeneous 3D points in metres.
    """

    R1: FloatArray
    R2: FloatArray
    P1: FloatArray
    P2: FloatArray
    Q: FloatArray
    image_size: tuple[int, int]
    roi_left: tuple[int, int, int, int]
    roi_right: tuple[int, int, int, int]

    @property
    def fx_px(self) -> float:
        """Focal length of the rectified cameras, pixels."""
        return float(self.P1[0, 0])

    @property
    def baseline_m(self) -> float:
        """Rectified baseline in metres (``-P2[0, 3] / fx'``)."""
        return float(-self.P2[0, 3] / self.P2[0, 0])

    @property
    def doffs_px(self) -> float:
        """Principal point offset ``cx_right' - cx_left'`` in pixels (0 with CALIB_ZERO_DISPARITY)."""
        return float(self.P2[0, 2] - self.P1[0, 2])

    def depth_from_disparity(self, disparity_px: NDArray[np.floating]) -> NDArray[np.float32]:
        """Depth (metres, along the rectified left axis) of rectified disparities; NaN where d <= 0."""
        d = np.asarray(disparity_px, dtype=np.float32) + np.float32(self.doffs_px)
        with np.errstate(divide="ignore", invalid="ignore"):
            depth = np.float32(self.fx_px * self.baseline_m) / d
        depth[~(d > 0)] = np.nan
        return depth.astype(np.float32)


def stereo_rectification(
    profile: StereoProfile, *, alpha: float = 0.0, image_size: tuple[int, int] | None = None
) -> StereoRectification:
    """Rectify ``profile`` with ``cv2.stereoRectify`` (CALIB_ZERO_DISPARITY).

    Args:
        profile: the stereo profile (OpenCV extrinsics, metres).
        alpha: 0 keeps only valid pixels, 1 keeps every source pixel (black borders), as OpenCV.
        image_size: ``(width, height)`` of the rectified images; default the profile's.
    """
    if not (0.0 <= alpha <= 1.0 or alpha == -1.0):  # NaN fails both
        raise S2RError(f"rectification alpha must be in [0, 1] or -1, got {alpha}", field="alpha")
    size = profile.image_size
    out_size = size if image_size is None else image_size
    roi1: Any
    roi2: Any
    T = profile.T.reshape(3, 1)  # OpenCV 5's stereoRectify wants a 3x1 column, not a flat (3,) vector
    if profile.left.distortion.model == "equidistant":
        # Fisheye lenses need OpenCV's fisheye model; it has no valid-pixel ROI, so report the full image.
        R1, R2, P1, P2, Q = cv2.fisheye.stereoRectify(
            profile.left.K, profile.left.D, profile.right.K, profile.right.D, size, profile.R, T,
            flags=cv2.CALIB_ZERO_DISPARITY, newImageSize=out_size, balance=alpha,
        )
        roi1 = roi2 = (0, 0, int(out_size[0]), int(out_size[1]))
    else:
        R1, R2, P1, P2, Q, roi1, roi2 = cv2.stereoRectify(
            profile.left.K, profile.left.D, profile.right.K, profile.right.D, size, profile.R, T,
            flags=cv2.CALIB_ZERO_DISPARITY, alpha=alpha, newImageSize=out_size,
        )
    return StereoRectification(
        R1=np.asarray(R1, np.float64), R2=np.asarray(R2, np.float64), P1=np.asarray(P1, np.float64),
        P2=np.asarray(P2, np.float64), Q=np.asarray(Q, np.float64), image_size=tuple(out_size),  # type: ignore[arg-type]
        roi_left=tuple(int(v) for v in roi1), roi_right=tuple(int(v) for v in roi2),  # type: ignore[arg-type]
    )
