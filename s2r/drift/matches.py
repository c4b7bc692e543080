"""Feature matches of ordinary stereo pairs, in the profile's rectified image coordinates.

Features are found in the RAW images (SIFT from OpenCV's main module; ORB, FAST corners with binary descriptors,
as the second detector whose matches widen sigma) and only their coordinates are rectified
(``cv2.undistortPoints`` with the profile's R1/P1 and R2/P2), so no image is resampled. Images over
:data:`MAX_FEATURE_PIXELS` are downscaled for the detectors (memory and time bounded; keypoints are scaled back to
full-resolution pixels). A match survives Lowe's ratio test, a mutual best-match check, a horizontal disparity
range (points in front of the rig, give or take the shift a yaw drift of up to 2 degrees adds to far points) and a
vertical gate wide enough for about 2 degrees of drift. The raw coordinates of every mutual match are kept, so
that another profile (a corrected one, or the cameras exchanged) can be gated again without detecting again.

Frames and units: pixels of the rectified left / right images (OpenCV's 0-based convention), disparity
``d = x_left - x_right + doffs`` (pixels, positive in front of the rig); raw pixels of the images as read.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.profile import Camera, StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["DETECTORS", "MAX_FEATURE_PIXELS", "FrameMatches", "RawMatches", "gate_matches", "match_frame",
           "raw_matches"]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: Lowe's ratio test: best / second-best descriptor distance.
RATIO = 0.8
#: Vertical gate, and the negative-disparity margin, as a fraction of the rectified focal length (0.035 rad: about
#: 2 degrees of pitch or roll across the image, or of yaw).
VERTICAL_GATE = 0.035
#: Images larger than this (pixels; 1280 x 1024) are downscaled for feature detection: SIFT doubles the image and
#: keeps about 11 float planes per octave (about 230 bytes per pixel: 15 GB for 8192^2, 0.3 GB here), and the
#: rotation is still measured to a fraction of a full-size pixel.
MAX_FEATURE_PIXELS = 1_310_720
DETECTORS = ("sift", "orb")


@dataclass(frozen=True)
class RawMatches:
    """Every mutual match of one pair in raw pixels: (N, 2) left and right, and what the detector found.

    ``keypoints`` is the smaller of the two images' keypoint counts; ``sharpness`` the variance of the left
    image's Laplacian (grey levels squared, at the detection scale; low for blurred or textureless images);
    ``identical`` that both images are the same textured pixels; ``size`` the images' (width, height) px.
    """

    left: FloatArray
    right: FloatArray
    keypoints: int
    sharpness: float
    identical: bool
    size: tuple[int, int]


@dataclass(frozen=True)
class FrameMatches:
    """The gated matches of one stereo pair: (N, 2) rectified left and right pixels, and what was found.

    ``behind`` counts the matches the gates dropped only because their disparity is negative (points behind the
    rig: many of them, and few kept, mean the cameras are swapped); ``raw`` holds the SIFT matches before the
    gates and ``second`` the second detector's (ORB), both in raw pixels.
    """

    name: str
    left: FloatArray
    right: FloatArray
    keypoints: int
    sharpness: float
    behind: int = 0
    identical: bool = False
    raw: RawMatches | None = None
    second: RawMatches | None = None

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


def _mutual_matches(desc_l: NDArray[Any], desc_r: NDArray[Any], norm: int) -> list[tuple[int, int]]:
    """Index pairs (left, right) that pass the ratio test and are each other's best match.

    The backward search (right -> left) runs only for the right descriptors some left one passed the ratio test
    with: brute force handles each query row alone, so their best matches are those of a search over every
    right descriptor, at a fraction of its cost (the mutual check needs no others).
    """
    matcher = cv2.BFMatcher(norm)
    forward = [c for c in matcher.knnMatch(desc_l, desc_r, k=2) if len(c) == 2]
    candidates = [(best.queryIdx, best.trainIdx) for best, second in forward
                  if best.distance < RATIO * second.distance]
    if not candidates:
        return []
    wanted = np.unique(np.fromiter((j for _, j in candidates), np.int64, len(candidates)))
    backward = {int(wanted[m.queryIdx]): m.trainIdx
                for m, *_ in matcher.knnMatch(np.ascontiguousarray(desc_r[wanted]), desc_l, k=1) if m is not None}
    return [(i, j) for i, j in candidates if backward.get(j) == i]


def _detect(image: NDArray[np.uint8], kind: str, max_features: int
            ) -> tuple[list[cv2.KeyPoint], NDArray[np.generic] | None]:
    """Keypoints and descriptors: SIFT's, or ORB's (FAST corners with binary descriptors: another localisation of
    the same scene, whose matches are the "other detector" estimate of sigma)."""
    if kind == "sift":
        sift = cv2.SIFT_create(nfeatures=max_features)  # type: ignore[attr-defined]
        return sift.detectAndCompute(image, None)  # type: ignore[no-any-return]
    if kind != "orb":
        raise ValueError(f"unknown detector {kind!r}; one of {DETECTORS}")
    orb = cv2.ORB_create(nfeatures=max_features, scaleFactor=1.2, nlevels=4)  # type: ignore[attr-defined]
    return orb.detectAndCompute(image, None)  # type: ignore[no-any-return]


def detection_scale(size: tuple[int, int]) -> float:
    """The factor (<= 1) images of ``size`` (width, height) px are resized by before detection."""
    pixels = size[0] * size[1]
    return 1.0 if pixels <= MAX_FEATURE_PIXELS else math.sqrt(MAX_FEATURE_PIXELS / pixels)


def _scaled(image: NDArray[np.uint8], scale: float) -> NDArray[np.uint8]:
    if scale >= 1.0:
        return image
    size = (max(1, round(image.shape[1] * scale)), max(1, round(image.shape[0] * scale)))
    return np.asarray(cv2.resize(image, size, interpolation=cv2.INTER_AREA), np.uint8)


def raw_matches(left: NDArray[np.uint8], right: NDArray[np.uint8], *, detector: str = "sift",
                max_features: int = 4000) -> RawMatches:
    """Mutual matches of one raw grey pair (H, W) uint8, in full-resolution raw pixels."""
    size = (int(left.shape[1]), int(left.shape[0]))
    scale = detection_scale(size)
    identical = left.shape == right.shape and cv2.norm(left, right, cv2.NORM_INF) == 0  # no full-size temporary
    small_l, small_r = _scaled(left, scale), _scaled(right, scale)
    kp_l, desc_l = _detect(small_l, detector, max_features)
    kp_r, desc_r = _detect(small_r, detector, max_features)
    sharpness = float(cv2.Laplacian(small_l, cv2.CV_32F).var())
    keypoints = min(len(kp_l), len(kp_r))
    empty = np.zeros((0, 2))
    if desc_l is None or desc_r is None or keypoints < 2 or identical:
        return RawMatches(empty, empty, keypoints, sharpness, identical and keypoints > 0, size)
    pairs = _mutual_matches(desc_l, desc_r, cv2.NORM_L2 if detector == "sift" else cv2.NORM_HAMMING)
    raw_l = np.array([kp_l[i].pt for i, _ in pairs], np.float64).reshape(-1, 2)
    raw_r = np.array([kp_r[j].pt for _, j in pairs], np.float64).reshape(-1, 2)
    if scale < 1.0:  # pixel centres: x_full = (x_small + 0.5) / scale - 0.5
        raw_l, raw_r = (raw_l + 0.5) / scale - 0.5, (raw_r + 0.5) / scale - 0.5
    return RawMatches(raw_l, raw_r, keypoints, sharpness, False, size)


def gate_matches(profile: StereoProfile, rect: StereoRectification, raw: RawMatches
                 ) -> tuple[FloatArray, FloatArray, int]:
    """Raw matches rectified with ``profile`` and gated: (N, 2) left, (N, 2) right rectified px, and the count
    dropped only for lying behind the rig."""
    rect_l = _rectify_points(profile.left, raw.left, rect.R1, rect.P1)
    rect_r = _rectify_points(profile.right, raw.right, rect.R2, rect.P2)
    if len(rect_l) == 0:
        return rect_l, rect_r, 0
    disparity = rect_l[:, 0] - rect_r[:, 0] + rect.doffs_px
    gate = VERTICAL_GATE * rect.fx_px
    rows_agree = (np.abs(rect_r[:, 1] - rect_l[:, 1]) < gate) & np.isfinite(rect_l).all(axis=1) \
        & np.isfinite(rect_r).all(axis=1)
    keep = (disparity > -gate) & (disparity < 0.5 * rect.image_size[0]) & rows_agree  # -gate: a yaw drift
    behind = int(np.count_nonzero(rows_agree & (disparity <= -gate) & (disparity > -0.5 * rect.image_size[0])))
    return rect_l[keep], rect_r[keep], behind


def match_frame(profile: StereoProfile, rect: StereoRectification, left: NDArray[np.uint8],
                right: NDArray[np.uint8], *, name: str, max_features: int = 4000, second: bool = True
                ) -> FrameMatches:
    """Matches of one raw grey pair (H, W) uint8 in ``rect``'s rectified coordinates (pixels); with ``second``
    the ORB matches are kept too (raw pixels) for the spread between detectors."""
    raw = raw_matches(left, right, detector="sift", max_features=max_features)
    other = raw_matches(left, right, detector="orb") if second and len(raw.left) else None
    rect_l, rect_r, behind = gate_matches(profile, rect, raw)
    return FrameMatches(name, rect_l, rect_r, raw.keypoints, raw.sharpness, behind=behind,
                        identical=raw.identical, raw=raw, second=other)
