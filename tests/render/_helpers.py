"""Helpers for the render tests: detect chessboard corners the plain OpenCV way; a T265-like fisheye rig."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.profile import Camera, Distortion, Extrinsics, Provenance, SimulationSettings, StereoProfile

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


def t265_rig(name: str = "t265_like") -> StereoProfile:
    """A T265-like fisheye pair: two 848x800 equidistant cameras (fx ~ 286 px, about 163 deg across the image
    circle), 64 mm baseline, slightly rotated right camera; too wide for one pinhole render."""
    left = Camera(width_px=848, height_px=800, fx_px=286.2, fy_px=286.9, cx_px=425.3, cy_px=398.1,
                  distortion=Distortion(model="equidistant", coefficients=(-0.0074, 0.043, -0.041, 0.0076)))
    right = Camera(width_px=848, height_px=800, fx_px=285.1, fy_px=285.6, cx_px=421.6, cy_px=403.7,
                   distortion=Distortion(model="equidistant", coefficients=(-0.0061, 0.041, -0.039, 0.0072)))
    R = Rotation.from_rotvec(np.radians([0.3, 0.5, -0.2])).as_matrix()
    T = -R @ np.array([0.064, -0.0004, 0.0003])
    return StereoProfile(
        name=name, left=left, right=right,
        extrinsics=Extrinsics(rotation=tuple(map(tuple, R.tolist())), translation_m=tuple(T.tolist())),
        simulation=SimulationSettings(clip_near_m=0.05, clip_far_m=50.0),
        provenance=Provenance(origin="sim", method="tests.render._helpers.t265_rig", convention="exact"),  # type: ignore[arg-type]
    )
