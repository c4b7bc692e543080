"""Stereo rectification of a profile (OpenCV's stereoRectify), shared by every stage that needs it.

The depth pipeline, the renderer's ground-truth disparity, calibration's epipolar check and the ROS
camera_info export all rectify through :func:`stereo_rectification`, so they agree to the bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import S2RError
from s2r.profile import StereoProfile

__all__ = ["DEFAULT_FISHEYE_FOV_DEG", "StereoRectification", "opencv_stereo_rectify", "stereo_rectification"]

FloatArray = NDArray[np.float64]

#: Horizontal field of view (degrees) of a fisheye pair's rectified images when OpenCV's balance would give a
#: wider one: a rectified (pinhole) image of a near-180-degree lens spends almost all its pixels on the rim.
DEFAULT_FISHEYE_FOV_DEG = 90.0


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


def _fisheye_field(P1: FloatArray, P2: FloatArray, out_size: tuple[int, int], fov_deg: float | None
                   ) -> tuple[FloatArray, FloatArray, FloatArray] | None:
    """P1, P2, Q of rectified cameras with ``fov_deg`` horizontal field (principal point at the image centre), or
    None to keep OpenCV's (``fov_deg`` None and OpenCV's field at most :data:`DEFAULT_FISHEYE_FOV_DEG`)."""
    width, height = out_size
    f_cv = float(P1[0, 0])
    if fov_deg is None:
        if 2.0 * math.degrees(math.atan(0.5 * width / f_cv)) <= DEFAULT_FISHEYE_FOV_DEG:
            return None
        fov_deg = DEFAULT_FISHEYE_FOV_DEG
    f = 0.5 * width / math.tan(math.radians(fov_deg) / 2.0)
    cx, cy = 0.5 * (width - 1), 0.5 * (height - 1)
    tx = float(P2[0, 3]) / float(P2[0, 0])  # -baseline (m)
    new1 = np.array([[f, 0.0, cx, 0.0], [0.0, f, cy, 0.0], [0.0, 0.0, 1.0, 0.0]])
    new2 = new1.copy()
    new2[0, 3] = f * tx
    Q = np.array([[1.0, 0.0, 0.0, -cx], [0.0, 1.0, 0.0, -cy], [0.0, 0.0, 0.0, f], [0.0, 0.0, -1.0 / tx, 0.0]])
    return new1, new2, Q


def stereo_rectification(
    profile: StereoProfile, *, alpha: float = 0.0, image_size: tuple[int, int] | None = None,
    fov_deg: float | None = None,
) -> StereoRectification:
    """Rectify ``profile`` with ``cv2.stereoRectify`` (CALIB_ZERO_DISPARITY); fisheye (equidistant) pairs with
    ``cv2.fisheye.stereoRectify`` (``alpha`` is its balance).

    Args:
        profile: the stereo profile (OpenCV extrinsics, metres).
        alpha: 0 keeps only valid pixels, 1 keeps every source pixel (black borders), as OpenCV.
        image_size: ``(width, height)`` of the rectified images; default the profile's.
        fov_deg: fisheye pairs only: horizontal field of view (degrees, 10-170) of the rectified images, with
            OpenCV's rotations R1 R2 and the principal point at the image centre. Default: OpenCV's balance
            result, capped at :data:`DEFAULT_FISHEYE_FOV_DEG`.
    """
    if not (0.0 <= alpha <= 1.0 or alpha == -1.0):  # NaN fails both
        raise S2RError(f"rectification alpha must be in [0, 1] or -1, got {alpha}", field="alpha")
    if fov_deg is not None and not 10.0 <= fov_deg <= 170.0:
        raise S2RError(f"rectified field of view must be 10-170 degrees, got {fov_deg}", field="fov_deg",
                       hint="e.g. 90")
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
        chosen = _fisheye_field(np.asarray(P1, np.float64), np.asarray(P2, np.float64),
                                (int(out_size[0]), int(out_size[1])), fov_deg)
        if chosen is not None:
            P1, P2, Q = chosen
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


def opencv_stereo_rectify(camera_matrix1: Any, dist_coeffs1: Any, camera_matrix2: Any, dist_coeffs2: Any,
                          image_size: Any, R: Any, T: Any, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
    """``cv2.stereoRectify`` as code written for OpenCV 4 calls it, with a flat translation accepted.

    The seed tutorial's camera_configs.py passes ``T = np.array([tx, ty, tz])`` (shape (3,)); OpenCV 5 refuses
    it (``gemm: a_size.width == len``) where OpenCV 4 took it. ``T`` (metres or any unit, 3 numbers) is passed as
    the (3, 1) column OpenCV wants; every other argument, and the return value, is ``cv2.stereoRectify``'s.
    """
    column = np.asarray(T, dtype=np.float64).reshape(3, 1)
    return tuple(cv2.stereoRectify(camera_matrix1, dist_coeffs1, camera_matrix2, dist_coeffs2, image_size, R, column,
                                   *args, **kwargs))
