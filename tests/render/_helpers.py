"""Helpers for the render tests: detect chessboard corners the plain OpenCV way."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

SUBPIX = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)


def detect(path: Path, pattern: tuple[int, int]) -> NDArray[np.float64] | None:
    """Corners (N, 2) found by findChessboardCorners + cornerSubPix, ordered so the first is top-left-most."""
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, corners = cv2.findChessboardCorners(img, pattern, flags=flags)
    if not ok:
        return None
    corners = cv2.cornerSubPix(img, corners, (5, 5), (-1, -1), SUBPIX).reshape(-1, 2).astype(np.float64)
    diagonal = corners[-1] - corners[0]
    if diagonal[0] + diagonal[1] < 0:  # OpenCV may start at either end; the sampled boards roll < 10 deg
        corners = corners[::-1].copy()
    return corners
