"""The ground truth of a chessboard frame: corners (s2r's calibration detector), pose by PnP, region and plane.

The board's pose comes from ``cv2.solvePnP`` (IPPE for planar targets, then Levenberg-Marquardt refinement) on the
corners found by :func:`s2r.calib.detect.detect_board`, with the camera's intrinsics and distortion and the known
square size. The board frame has its origin at the first inner corner, x along the pattern's columns, y along
its rows, z into the board; its plane in the camera frame is ``n . P = d`` with ``n`` the board's z axis.
The region of interest is the quadrilateral through the four outermost INNER corners (every pixel in it shows
the board itself, never the background).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import detect_board
from s2r.calib.detect.chessboard import board_object_points
from s2r.quality.metrics import Plane

__all__ = ["BoardView", "find_board", "normalised_rays", "roi_mask", "roi_quad"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BoardView:
    """One detected board: corners (N, 2) px, pose ``T_cam_board`` (4x4, metres), plane, RMS reprojection (px)."""

    corners: NDArray[np.float32]
    T_cam_board: FloatArray
    plane: Plane
    reprojection_px: float


def find_board(grey: NDArray[np.uint8], K: FloatArray, D: FloatArray, pattern: tuple[int, int],
               square_m: float) -> BoardView | None:
    """Detect the board in an 8-bit grey image (H, W) and solve its pose with intrinsics ``K`` (3x3, px) and
    distortion ``D`` (OpenCV order); None when no board is found."""
    corners, _ = detect_board(grey, pattern)
    if corners is None:
        return None
    obj = board_object_points(pattern, square_m)
    img = corners.reshape(-1, 1, 2).astype(np.float64)
    ok, rvec, tvec = cv2.solvePnP(obj, img, K, D, flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        return None
    rvec, tvec = cv2.solvePnPRefineLM(obj, img, K, D, rvec, tvec)
    projected, _ = cv2.projectPoints(obj, rvec, tvec, K, D)
    rms = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - corners) ** 2, axis=1))))
    R = np.asarray(cv2.Rodrigues(rvec)[0], np.float64)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, np.asarray(tvec, np.float64).ravel()
    normal = R[:, 2]
    offset = float(normal @ T[:3, 3])
    if offset < 0:
        normal, offset = -normal, -offset
    return BoardView(corners, T, Plane((float(normal[0]), float(normal[1]), float(normal[2])), offset), rms)


def roi_quad(corners: NDArray[np.float32], pattern: tuple[int, int]) -> NDArray[np.float32]:
    """(4, 2) pixels of the outermost inner corners, in order around the board: the region of interest."""
    cols, rows = pattern
    return np.asarray(corners, np.float32).reshape(-1, 2)[[0, cols - 1, cols * rows - 1, cols * (rows - 1)]]


def roi_mask(corners: NDArray[np.float32], pattern: tuple[int, int], size: tuple[int, int]) -> NDArray[np.bool_]:
    """(H, W) bool mask of the quadrilateral :func:`roi_quad`, for an image ``(W, H)``."""
    quad = roi_quad(corners, pattern)
    mask = np.zeros((size[1], size[0]), np.uint8)
    cv2.fillConvexPoly(mask, np.round(quad * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


def normalised_rays(pixels: FloatArray, K: FloatArray, D: FloatArray) -> FloatArray:
    """(N, 2) undistorted normalised coordinates ``(x, y)`` of (N, 2) pixel positions (OpenCV 0-based)."""
    if not np.any(D):
        return np.column_stack([(pixels[:, 0] - K[0, 2]) / K[0, 0], (pixels[:, 1] - K[1, 2]) / K[1, 1]])
    und = cv2.undistortPoints(pixels.reshape(-1, 1, 2).astype(np.float64), K, D)
    return np.asarray(und, np.float64).reshape(-1, 2)
