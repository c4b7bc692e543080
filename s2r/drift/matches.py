"""Feature matches of ordinary stereo pairs, in the profile's rectified image coordinates.

Features are found in the RAW images (SIFT, from OpenCV's main module) and only their coordinates are
rectified (``cv2.undistortPoints`` with the profile's R1/P1 and R2/P2), so no image is resampled. A match
survives Lowe's ratio test, a mutual best-match check, a horizontal disparity range (points in front of the
rig, give or take the shift a yaw drift of up to 2 degrees adds to far points) and a vertical gate wide enough
for about 2 degrees of drift.

Frames and units: pixels of the rectified left / right images (OpenCV's 0-based convention), disparity
``d = x_left - x_right + doffs`` (pixels, positive in front of the rig).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.profile import Camera, StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["FrameMatches", "match_frame"]

FloatArray = NDArray[np.float64]

#: Lowe's ratio test: best / second-best descriptor distance.
RATIO = 0.8
#: Vertical gate, and the negative-disparity margin, as a fraction of the rectified focal length (0.035 rad: about
#: 2 degrees of pitch or roll across the image, or of yaw).
VERTICAL_GATE = 0.035


@dataclass(frozen=True)
class FrameMatches:
    """The matches of one stereo pair: (N, 2) rectified left and right pixels, and what was found.

    ``keypoints`` is the smaller of the two images' keypoint counts; ``sharpness`` the variance of the left
    image's Laplacian (grey levels squared; low for blurred or textureless images); ``behind`` the matches the
    gates dropped only because their disparity is negative (points behind the rig: many of them, and few kept,
    mean the left and right images are swapped); ``identical`` that both images are the same textured pixels.
    """

    name: str
    left: FloatArray
    right: FloatArray
    keypoints: int
    sharpness: float
    behind: int = 0
    identical: bool = False

    @property
    def count(self) -> int:
        """Number of matches."""
        return len(self.left)


def _rectify_points(cam: Camera, pts: FloatArray, R: FloatArray, P: FloatArray) -> FloatArray:
    """(N, 2) raw pixels -> rectified pixels of the camera ``cam`` (rectifying rotation R, projection P)."""
    if len(pts) == 0:
        return np.zeros((0, 2))
    src = pts.reshape(-1, 1, 2).astype(np.float64)
    if cam.distortion.model == "equidistant":
        out = cv2.fisheye.undistortPoints(src, cam.K, cam.D, R=R, P=P[:, :3])
    else:
        out = cv2.undistortPoints(src, cam.K, cam.D, R=R, P=P[:, :3])
    return np.asarray(out, np.float64).reshape(-1, 2)


def _mutual_matches(desc_l: NDArray[np.float32], desc_r: NDArray[np.float32]) -> list[tuple[int, int]]:
    """Index pairs (left, right) that pass the ratio test and are each other's best match."""
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    forward = matcher.knnMatch(desc_l, desc_r, k=2)
    backward = {m.queryIdx: m.trainIdx for m, *_ in matcher.knnMatch(desc_r, desc_l, k=1) if m is not None}
    pairs = []
    for candidates in forward:
        if len(candidates) < 2:
            continue
        best, second = candidates
        if best.distance < RATIO * second.distance and backward.get(best.trainIdx) == best.queryIdx:
            pairs.append((best.queryIdx, best.trainIdx))
    return pairs


def match_frame(profile: StereoProfile, rect: StereoRectification, left: NDArray[np.uint8],
                right: NDArray[np.uint8], *, name: str, max_features: int = 4000) -> FrameMatches:
    """Matches of one raw grey pair (H, W) uint8 in ``rect``'s rectified coordinates (pixels)."""
    sift = cv2.SIFT_create(nfeatures=max_features)  # type: ignore[attr-defined]
    kp_l, desc_l = sift.detectAndCompute(left, None)
    kp_r, desc_r = sift.detectAndCompute(right, None)
    sharpness = float(cv2.Laplacian(left, cv2.CV_64F).var())
    keypoints = min(len(kp_l), len(kp_r))
    empty = np.zeros((0, 2))
    identical = keypoints > 0 and left.shape == right.shape and bool(np.array_equal(left, right))  # not blank
    if desc_l is None or desc_r is None or keypoints < 2 or identical:
        return FrameMatches(name, empty, empty, keypoints, sharpness, identical=identical)
    pairs = _mutual_matches(desc_l, desc_r)
    raw_l = np.array([kp_l[i].pt for i, _ in pairs], np.float64).reshape(-1, 2)
    raw_r = np.array([kp_r[j].pt for _, j in pairs], np.float64).reshape(-1, 2)
    rect_l = _rectify_points(profile.left, raw_l, rect.R1, rect.P1)
    rect_r = _rectify_points(profile.right, raw_r, rect.R2, rect.P2)
    disparity = rect_l[:, 0] - rect_r[:, 0] + rect.doffs_px
    gate = VERTICAL_GATE * rect.fx_px
    rows_agree = (np.abs(rect_r[:, 1] - rect_l[:, 1]) < gate) & np.isfinite(rect_l).all(axis=1) \
        & np.isfinite(rect_r).all(axis=1)
    keep = (disparity > -gate) & (disparity < 0.5 * rect.image_size[0]) & rows_agree  # -gate: a yaw drift
    behind = int(np.count_nonzero(rows_agree & (disparity <= -gate) & (disparity > -0.5 * rect.image_size[0])))
    return FrameMatches(name, rect_l[keep], rect_r[keep], keypoints, sharpness, behind=behind)
