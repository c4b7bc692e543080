"""Board truth for a drift check, sharing no code with s2r: plain OpenCV on the chessboard corners.

``findChessboardCorners`` + ``cornerSubPix`` in every pair, then ``stereoCalibrate`` with the profile's own
intrinsics fixed (``CALIB_FIX_INTRINSIC``): the relative rotation that best explains the board corners with the
profile's lenses. The drift a check should report for a profile is ``dR = R_board @ R_profile^T`` as a rotation
vector about the right camera's axes (degrees); its sigma is the leave-one-pair-out jackknife.

Run ``python -m tests.drift.board_anchor PROFILE FOLDER`` for the figures.
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def board_corners(folder: Path, pattern: tuple[int, int] = (9, 6)) -> tuple[list[FloatArray], list[FloatArray],
                                                                             tuple[int, int]]:
    """Left and right (N, 1, 2) float32 corners of every ``leftNN``/``rightNN`` pair where both boards are found."""
    left, right, size = [], [], (0, 0)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 1e-3)
    for path in sorted(folder.glob("left[0-9]*.*")):
        other = path.with_name("right" + path.name[4:])
        images = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in (path, other)]
        found = [cv2.findChessboardCorners(im, pattern) for im in images]
        if all(ok for ok, _ in found):
            size = (images[0].shape[1], images[0].shape[0])
            left.append(cv2.cornerSubPix(images[0], found[0][1], (11, 11), (-1, -1), criteria))
            right.append(cv2.cornerSubPix(images[1], found[1][1], (11, 11), (-1, -1), criteria))
    return left, right, size


def _rotation(objects: list[FloatArray], left: list[FloatArray], right: list[FloatArray], K1: FloatArray,
              D1: FloatArray, K2: FloatArray, D2: FloatArray, size: tuple[int, int]) -> FloatArray:
    out = cv2.stereoCalibrate(objects, left, right, K1, D1, K2, D2, size, flags=cv2.CALIB_FIX_INTRINSIC)
    return np.asarray(out[5], np.float64)


def board_drift_deg(K1: FloatArray, D1: FloatArray, K2: FloatArray, D2: FloatArray, R_profile: FloatArray,
                    folder: Path, *, pattern: tuple[int, int] = (9, 6)) -> tuple[FloatArray, FloatArray]:
    """(3,) dR = R_board R_profile^T as (pitch, yaw, roll) degrees about the right camera's axes, and its
    leave-one-pair-out jackknife sigma (degrees)."""
    left, right, size = board_corners(folder, pattern)
    grid = np.zeros((pattern[0] * pattern[1], 3), np.float32)
    grid[:, :2] = np.mgrid[0:pattern[0], 0:pattern[1]].T.reshape(-1, 2)
    objects = [grid] * len(left)

    def drift(keep: list[int]) -> FloatArray:
        R = _rotation([objects[i] for i in keep], [left[i] for i in keep], [right[i] for i in keep],
                      K1, D1, K2, D2, size)
        return np.degrees(cv2.Rodrigues(R @ R_profile.T)[0].reshape(3))

    full = drift(list(range(len(left))))
    loo = np.array([drift([j for j in range(len(left)) if j != i]) for i in range(len(left))])
    n = len(loo)
    sigma = np.sqrt((n - 1) / n * np.sum((loo - loo.mean(axis=0)) ** 2, axis=0))
    return full, sigma


def _profile_matrices(path: Path) -> tuple[FloatArray, ...]:
    import yaml

    data = yaml.safe_load(path.read_text())

    def cam(c: dict) -> tuple[FloatArray, FloatArray]:
        K = np.array([[c["fx_px"], c["skew"], c["cx_px"]], [0, c["fy_px"], c["cy_px"]], [0, 0, 1]], np.float64)
        return K, np.array(c["distortion"]["coefficients"], np.float64)

    K1, D1 = cam(data["left"])
    K2, D2 = cam(data["right"])
    return K1, D1, K2, D2, np.array(data["extrinsics"]["rotation"], np.float64)


if __name__ == "__main__":
    drift_deg, sigma_deg = board_drift_deg(*_profile_matrices(Path(sys.argv[1])), Path(sys.argv[2]))
    for axis, d, s in zip(("pitch", "yaw", "roll"), drift_deg, sigma_deg, strict=True):
        print(f"{axis:<6}{d:+.4f} +/- {s:.4f} deg")
