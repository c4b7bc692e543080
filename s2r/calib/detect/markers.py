"""Corner detection of file-described targets: ChArUco boards, Kalibr AprilGrids, Kalibr checkerboards.

Every detector returns ``(ids (N,) int32, corners (N, 2) float32 pixels)``: the target's corner ids (see
:mod:`s2r.targets`) and their sub-pixel image positions (OpenCV convention, 0-based pixel centres), so views
where the board is cut by the image edge still count, corner by corner.

- ChArUco: ``cv2.aruco.CharucoDetector`` (markers, then the chessboard corners between them, refined by
  OpenCV; a wider ``cornerSubPix`` window made them worse). Corners that small windows would move by more
  than ``CHARUCO_CHECK_PX`` are dropped: on ray-cast rigs 2-14 % of the corners, RMS error 0.10 -> 0.07 px
  (pinhole) and 0.16 -> 0.09 px (T265-like fisheye), largest error 1.0-1.3 -> 0.35-0.43 px.
- AprilGrid (Kalibr): ``cv2.aruco.ArucoDetector`` with DICT_APRILTAG_36h11 and ``markerBorderBits = 2``
  (Kalibr prints a 2-bit black border). OpenCV's own corner refinement is poor there (the tag outline
  merges with the small black corner squares), so each tag corner, an X junction of the tag and its corner
  square, is refined with ``cornerSubPix`` and a window of about 15 % of the imaged tag size, as Kalibr
  does; a tag whose corners move too far (a bad outline) is dropped whole. ArucoDetector returns each
  Kalibr tag's corners turned by 180 degrees (Kalibr prints the tags turned): bottom-right, bottom-left,
  top-left, top-right in Kalibr's board frame.
- Kalibr checkerboard: the chessboard detector of :mod:`s2r.calib.detect` (whole boards only).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.chessboard import detect_board
from s2r.targets import AnyTarget, AprilGridTarget, CharucoTarget, CheckerboardTarget

__all__ = [
    "MIN_CORNERS",
    "TargetCorners",
    "charuco_board",
    "detect_aprilgrid",
    "detect_charuco",
    "detect_target",
    "usable_corners",
]

Ids = NDArray[np.int32]
Corners = NDArray[np.float32]
TargetCorners = tuple[Ids, Corners]

#: Fewest corners a view must show (and spread over two dimensions of the board) to be used.
MIN_CORNERS = 6
_SUBPIX = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 0.001)
#: ChArUco: a corner is dropped when a 2 or 3 px cornerSubPix window would move it by this much (pixels).
CHARUCO_CHECK_PX = 0.3
#: AprilGrid: the refinement half-window is this share of the imaged tag side (px), clamped.
APRIL_WINDOW_SHARE = 0.15
#: AprilGrid: a tag is dropped when one of its corners moves more than this share of the half-window.
APRIL_MAX_SHIFT = 0.75
#: AprilGrid: ... or when refining again with half the window moves one by more than this (pixels).
APRIL_MAX_DISAGREE_PX = 0.25


def charuco_board(target: CharucoTarget) -> cv2.aruco.CharucoBoard:
    """OpenCV's board for a ChArUco target (``legacyPattern`` for boards drawn by OpenCV <= 4.5)."""
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, target.dictionary))
    board = cv2.aruco.CharucoBoard((target.squaresX, target.squaresY), target.squareLength, target.markerLength,
                                   dictionary)
    board.setLegacyPattern(target.legacyPattern)
    return board


def _side_px(quads: NDArray[np.float32]) -> NDArray[np.float64]:
    """Mean side length (px) of each quadrilateral (M, 4, 2)."""
    q = quads.astype(np.float64)
    return np.asarray(np.linalg.norm(q - np.roll(q, 1, axis=1), axis=2).mean(axis=1), np.float64)


def _subpix(gray: NDArray[np.uint8], pts: NDArray[np.float32], half: int) -> NDArray[np.float32]:
    refined = cv2.cornerSubPix(gray, pts.reshape(-1, 1, 2).astype(np.float32).copy(), (half, half), (-1, -1),
                               _SUBPIX)
    return np.asarray(refined, np.float32).reshape(-1, 2)


def _inside(gray: NDArray[np.uint8], pts: NDArray[np.float32], margin: float) -> NDArray[np.bool_]:
    h, w = gray.shape[:2]
    return np.asarray((pts[:, 0] >= margin) & (pts[:, 0] <= w - 1 - margin) & (pts[:, 1] >= margin)
                      & (pts[:, 1] <= h - 1 - margin), np.bool_)


def detect_charuco(gray: NDArray[np.uint8], target: CharucoTarget) -> TargetCorners | None:
    """ChArUco corners of one 8-bit grey image (H, W): ids and refined pixels, or None."""
    detector = cv2.aruco.CharucoDetector(charuco_board(target))
    corners, ids, _marker_corners, _marker_ids = detector.detectBoard(gray)
    if ids is None or corners is None or len(ids) == 0:
        return None
    pts = np.asarray(corners, np.float32).reshape(-1, 2)
    ids_a = np.asarray(ids, np.int32).reshape(-1)
    # OpenCV refines the corners itself, with a window kept inside the white gap between square corner and
    # marker (moving them with a wider cornerSubPix window pulls them towards the markers: 0.2 px, measured).
    # Its positions are kept; a corner that small windows (2 and 3 px) would move by more than
    # CHARUCO_CHECK_PX is not a clean X junction there (blur, a steep or strongly distorted square) and is dropped.
    keep = np.ones(len(pts), dtype=bool)
    for half in (2, 3):
        keep &= np.linalg.norm(_subpix(gray, pts, half) - pts, axis=1) < CHARUCO_CHECK_PX
    return ids_a[keep], pts[keep]


#: ArucoDetector corner k of a Kalibr tag -> column of AprilGridTarget.tag_corner_ids (BL, BR, TR, TL).
_APRIL_CORNER_ORDER = (1, 0, 3, 2)


def _aruco_april() -> cv2.aruco.ArucoDetector:
    params = cv2.aruco.DetectorParameters()
    params.markerBorderBits = 2
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_NONE
    return cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)


def detect_aprilgrid(gray: NDArray[np.uint8], target: AprilGridTarget) -> TargetCorners | None:
    """Kalibr AprilGrid tag corners of one 8-bit grey image (H, W): Kalibr corner ids and refined pixels."""
    quads, tag_ids, _rejected = _aruco_april().detectMarkers(gray)
    if tag_ids is None or len(tag_ids) == 0:
        return None
    tag_ids = np.asarray(tag_ids, np.int64).reshape(-1)
    quads_a = np.asarray(quads, np.float32).reshape(-1, 4, 2)
    ok = (tag_ids >= target.codeOffset) & (tag_ids < target.codeOffset + target.tag_count)
    tag_ids, quads_a = tag_ids[ok], quads_a[ok]
    if len(tag_ids) == 0:
        return None
    ids_out, pts_out = [], []
    ids_all = target.tag_corner_ids(tag_ids)[:, list(_APRIL_CORNER_ORDER)]
    for quad, cids, side in zip(quads_a, ids_all, _side_px(quads_a), strict=True):
        half = int(min(15, max(2, round(APRIL_WINDOW_SHARE * side * min(1.0, target.tagSpacing / 0.3)))))
        if not _inside(gray, quad, half + 2).all():
            continue
        refined = _subpix(gray, quad, half)
        if float(np.max(np.linalg.norm(refined - quad, axis=1))) > max(1.5, APRIL_MAX_SHIFT * half):
            continue
        # an X junction refines to the same point with a smaller window; a corner pulled by the tag's
        # outline or a neighbour (small, steep tags) does not
        check = _subpix(gray, refined, max(2, half // 2))
        if float(np.max(np.linalg.norm(check - refined, axis=1))) > APRIL_MAX_DISAGREE_PX:
            continue
        ids_out.append(cids)
        pts_out.append(refined)
    if not ids_out:
        return None
    return _merge(np.concatenate(ids_out).astype(np.int32), np.concatenate(pts_out).astype(np.float32))


def _merge(ids: Ids, pts: Corners) -> TargetCorners:
    """One entry per corner id (ids are unique per tag corner in an AprilGrid; kept sorted)."""
    order = np.argsort(ids, kind="stable")
    ids, pts = ids[order], pts[order]
    first = np.concatenate([[True], np.diff(ids) != 0])
    return ids[first], pts[first]


def usable_corners(ids: Ids, object_points: NDArray[np.float64]) -> bool:
    """True when a view has at least :data:`MIN_CORNERS` corners spread over the board in two directions
    (collinear corners cannot fix a board pose)."""
    if len(ids) < MIN_CORNERS:
        return False
    pts = object_points[:, :2] - object_points[:, :2].mean(axis=0)
    sv = np.linalg.svd(pts, compute_uv=False)
    return bool(sv[-1] > 0.05 * sv[0])


def detect_target(gray: NDArray[np.uint8], target: AnyTarget) -> tuple[TargetCorners | None, str]:
    """Detect ``target`` in an 8-bit grey image (H, W): ``((ids, corners) or None, detector name)``.

    Views with too few corners (or corners on one line) count as not found."""
    found: TargetCorners | None
    if isinstance(target, CheckerboardTarget):
        corners, name = detect_board(gray, target.pattern)
        found = None if corners is None else (np.arange(len(corners), dtype=np.int32), corners)
    elif isinstance(target, CharucoTarget):
        found, name = detect_charuco(gray, target), "charuco"
    else:
        found, name = detect_aprilgrid(gray, target), "aprilgrid"
    if found is None or not usable_corners(found[0], target.points_of(found[0])):
        return None, name
    return found, name
