"""Chessboard corner detection: downscaled detection, full-resolution refinement, parallel and cached.

Images up to twice 640x480 in area are detected at full resolution (as a plain OpenCV loop does);
larger ones first on a copy downscaled by an integer factor (INTER_AREA, as ROS camera_calibration
does) and the corners refined at full resolution. The classic detector
(``findChessboardCorners`` with ADAPTIVE_THRESH | NORMALIZE_IMAGE | FAST_CHECK) runs first (on large
images also at full resolution, for steeply tilted boards), the sector-based ``findChessboardCornersSB``
(NORMALIZE_IMAGE) is the fallback, on images larger than 640x480 only when OpenCV's quick check
(``checkChessboard``) finds a board likely. FAST_CHECK and ``checkChessboard`` are only a first pass: they
miss boards plain ``findChessboardCorners`` finds (on real sets 1-8 % of the views), so an image they reject is
tried again at full resolution without them (ADAPTIVE_THRESH | NORMALIZE_IMAGE, as OpenCV's stereo sample)
before it is called board-less; frames without a board cost that extra call. Not on a flat image (a thumbnail
spanning fewer than :data:`FLAT_RANGE_GREY` grey levels: a blank wall, a covered lens, a dark frame): no board
can be told apart there, and NORMALIZE_IMAGE turns its sensor noise into countless quads, on which that call
takes ~2 s per 1280x720 frame (against 0.05-0.15 s on real scenes).
``cornerSubPix`` uses a window fitted to the board: 0.4 x the smallest distance between neighbouring
corners, clamped to 2..11 px (half-size), instead of a fixed 11x11 (half-size) window that would swallow
neighbouring corners of small or distant boards.

Corner arrays are (N, 2) float32 pixel coordinates (OpenCV convention, 0-based pixel centres), row-major
over the pattern's ``(cols, rows)`` inner corners.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["DETECT_AREA_PX", "FLAT_RANGE_GREY", "board_object_points", "detect_board", "is_flat", "refine_window"]

#: Images with more pixels than this are detected on a downscaled copy (as ROS does).
DETECT_AREA_PX = 640 * 480
_CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
#: Without EXHAUSTIVE: that flag finds a few more strongly tilted boards but costs about 0.2 s on every
#: 640x360 image without a board (0.03-0.05 s without it), which dominates long recordings.
_SB_FLAGS = cv2.CALIB_CB_NORMALIZE_IMAGE
#: The retry of views the first pass rejects: plain findChessboardCorners, no FAST_CHECK.
_PLAIN_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
#: An image whose thumbnail (longest side :data:`_THUMB_SIDE_PX`, area-averaged, which averages sensor noise
#: away) spans fewer grey levels than this shows no board. On 12 real sets (866 images with a board, and real
#: scenes without one) the smallest span is 77 levels; a blank synthetic frame with noise spans 2.
FLAT_RANGE_GREY = 12
_THUMB_SIDE_PX = 160
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 0.001)

Corners = NDArray[np.float32]


def refine_window(corners: Corners, pattern: tuple[int, int]) -> int:
    """cornerSubPix half-window (pixels): 0.4 x the smallest neighbour distance in the grid, clamped 2..11.

    The window (``2 * half + 1`` px) then spans 80 % of the smallest corner spacing: it never reaches the
    neighbouring corners nor, for the outer corners, far past the outer squares into the background
    (half the spacing let the board's edge pull corners of OpenCV's left02.jpg by 1-3 px)."""
    cols, rows = pattern
    grid = corners.reshape(rows, cols, 2).astype(np.float64)
    dists = [np.linalg.norm(np.diff(grid, axis=1), axis=2), np.linalg.norm(np.diff(grid, axis=0), axis=2)]
    min_dist = min(float(d.min()) for d in dists if d.size)
    return int(min(11, max(2, math.floor(0.4 * min_dist))))


def _classic(image: NDArray[np.uint8], pattern: tuple[int, int], flags: int = _CLASSIC_FLAGS) -> Corners | None:
    ok, corners = cv2.findChessboardCorners(image, pattern, flags=flags)
    return np.asarray(corners, np.float32).reshape(-1, 2) if ok else None


def _sector_based(image: NDArray[np.uint8], pattern: tuple[int, int]) -> Corners | None:
    ok, corners = cv2.findChessboardCornersSB(image, pattern, flags=_SB_FLAGS)
    return np.asarray(corners, np.float32).reshape(-1, 2) if ok else None


def _board_likely(image: NDArray[np.uint8], pattern: tuple[int, int]) -> bool:
    """OpenCV's quick chessboard check (what FAST_CHECK runs): False means surely no board (a few ms)."""
    return bool(cv2.checkChessboard(image, pattern))


def is_flat(gray: NDArray[np.uint8]) -> bool:
    """Whether the 8-bit grey image (H, W) spans fewer than :data:`FLAT_RANGE_GREY` grey levels once
    area-averaged to a thumbnail: nothing in it, least of all a chessboard, stands out from the noise."""
    h, w = gray.shape[:2]
    step = max(1, math.ceil(max(h, w) / _THUMB_SIDE_PX))
    thumb = gray if step == 1 else cv2.resize(gray, (max(1, w // step), max(1, h // step)),
                                              interpolation=cv2.INTER_AREA)
    lo, hi, _, _ = cv2.minMaxLoc(thumb)
    return hi - lo < FLAT_RANGE_GREY


def _downscaled(gray: NDArray[np.uint8], factor: int) -> NDArray[np.uint8]:
    """``gray`` area-averaged by the integer ``factor`` (itself when 1), the rows and columns beyond a whole
    multiple of ``factor`` left out."""
    if factor <= 1:
        return gray
    h, w = gray.shape[:2]
    size = (max(1, w // factor), max(1, h // factor))
    return np.asarray(cv2.resize(gray[:size[1] * factor, :size[0] * factor], size, interpolation=cv2.INTER_AREA),
                      np.uint8)


def _find(gray: NDArray[np.uint8], pattern: tuple[int, int]) -> tuple[Corners | None, str]:
    """Unrefined corners in full-resolution pixels, trying cheap detectors first.

    Up to twice the detection area (e.g. 1280x720): the classic detector at full resolution, as a plain
    OpenCV loop does (on the downscaled copy it is about 4x cheaper but can take seconds on a steeply
    tilted board it then fails to find). Larger images: classic on a copy downscaled by an integer factor
    (INTER_AREA), then classic at full resolution (boards whose squares shrink to a few pixels). Then the
    sector-based detector on the (downscaled) image; for images larger than 640x480 only when OpenCV's quick
    check (``checkChessboard``) says a board is likely, which keeps it (tens of ms) off frames without a
    board. The check misses some boards only the sector-based detector finds (on the 640x480 test set 3 of
    4), so small images, which are cheap, always get the fallback. Last, plain ``findChessboardCorners``
    without FAST_CHECK at full resolution: a board any of the checks above rejected is not lost (skipped on a
    flat image, see :func:`is_flat`).
    """
    h, w = gray.shape[:2]
    factor = math.ceil(math.sqrt(w * h / DETECT_AREA_PX) - 1e-9)
    if factor <= 2:  # detected at full resolution first: the copy is made only if that fails
        found = _classic(gray, pattern)
        if found is not None:
            return found, "classic"
    small = _downscaled(gray, factor)
    if factor > 2:
        found = _classic(small, pattern)
        if found is not None:
            return ((found + 0.5) * factor - 0.5).astype(np.float32), "classic"
        found = _classic(gray, pattern)
        if found is not None:
            return found, "classic-full"
    if factor == 1 or _board_likely(small, pattern):
        found = _sector_based(small, pattern)
        if found is not None:
            return ((found + 0.5) * factor - 0.5).astype(np.float32) if factor > 1 else found, "sb"
    if is_flat(small):
        return None, ""
    found = _classic(gray, pattern, _PLAIN_FLAGS)  # the first pass is no verdict: retry without FAST_CHECK
    return (found, "classic-plain") if found is not None else (None, "")


def detect_board(gray: NDArray[np.uint8], pattern: tuple[int, int]) -> tuple[Corners | None, str]:
    """Find and refine the inner corners of a ``(cols, rows)`` chessboard in an 8-bit grey image (H, W).

    Returns ``(corners (N, 2) float32 pixels or None, detector name)``; refinement is at full resolution.
    """
    found, detector = _find(gray, pattern)
    if found is None:
        return None, ""
    win = refine_window(found, pattern)
    refined = cv2.cornerSubPix(gray, found.reshape(-1, 1, 2).copy(), (win, win), (-1, -1), _SUBPIX_CRITERIA)
    return np.asarray(refined, np.float32).reshape(-1, 2), detector


def board_object_points(pattern: tuple[int, int], square_m: float) -> NDArray[np.float32]:
    """Inner corners of a ``(cols, rows)`` chessboard in the board frame (metres, z = 0), shape (N, 3),
    row-major as :func:`detect_board` returns them: corner k = (k % cols, k // cols) squares."""
    cols, rows = pattern
    grid = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2).astype(np.float32)
    return np.hstack([grid * np.float32(square_m), np.zeros((cols * rows, 1), np.float32)])
