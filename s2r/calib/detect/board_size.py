"""A wrong ``--pattern`` caught in a second, not after the whole search: the board size the images hold.

Before the full detection, :func:`check_board_size` looks at a few frames (first, middle, last). When the given
chessboard is in one of them, that is the end of it (one classic detection, about 10 ms at 640x480). When it is in
none, it counts the inner corners of the largest chessboard-like grid: OpenCV's sector-based detector with
``CALIB_CB_LARGER`` reports the size of the grid it grows from a 3x3 seed, and that size (or one a row or
column smaller: the grown grid may take in one row of the board's border) is accepted only when the classic
detector then finds exactly that board in that frame. A verified grid of another size is a wrong ``--pattern``
(on OpenCV's 13-pair sample set, 10x7 given on its 9x6 board: named in about 0.5 s of CPU time instead of
the 19 s full search); no grid at all lets the full search go on (the board may be in other frames).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.chessboard import DETECT_AREA_PX, _classic, _downscaled
from s2r.errors import CalibrationError
from s2r.imageio import decode_image_file

__all__ = ["PROBE_FRAMES", "board_size_in", "check_board_size"]

#: Frames looked at before the full search (evenly spread over the recording).
PROBE_FRAMES = 3
#: The smallest grid taken as a board (inner corners per side): smaller ones are too easily a floor's tiles.
_MIN_SIDE = 3


def _probe_frames(files: Sequence[Path], count: int) -> Iterator[NDArray[np.uint8]]:
    """Up to ``count`` readable frames, evenly spread over ``files``, as grey images at detection size, decoded
    one at a time as they are asked for (the board is usually in the first: the others are never read)."""
    if not files:
        return
    picks = sorted({round(i * (len(files) - 1) / max(1, count - 1)) for i in range(count)})
    for i in picks:
        image, _ = decode_image_file(files[i], cv2.IMREAD_GRAYSCALE)
        if image is None or image.ndim != 2:
            continue
        h, w = image.shape
        yield _downscaled(np.asarray(image, np.uint8), math.ceil(math.sqrt(w * h / DETECT_AREA_PX) - 1e-9))


def _grown_sizes(gray: NDArray[np.uint8]) -> set[tuple[int, int]]:
    """Sizes (larger side first) of the grids the sector-based detector grows from a 3x3 seed, and each one a
    row or a column smaller."""
    sizes: set[tuple[int, int]] = set()
    for flags in (cv2.CALIB_CB_LARGER, cv2.CALIB_CB_LARGER | cv2.CALIB_CB_NORMALIZE_IMAGE):
        ok, _, meta = cv2.findChessboardCornersSBWithMeta(gray, (3, 3), flags=flags)
        if ok and meta is not None:
            a, b = sorted(np.asarray(meta).shape[:2], reverse=True)
            sizes |= {(a, b), (a - 1, b), (a, b - 1), (a - 1, b - 1)}
    return {(max(a, b), min(a, b)) for a, b in sizes if min(a, b) >= _MIN_SIDE}


def board_size_in(frames: Sequence[NDArray[np.uint8]]) -> tuple[int, int] | None:
    """Inner corners ``(larger side, smaller side)`` of the largest chessboard the classic detector confirms in
    any of ``frames`` (8-bit grey), or None when none holds one."""
    best: tuple[int, int] | None = None
    tried: set[tuple[int, int]] = set()
    for gray in frames:
        for size in sorted(_grown_sizes(gray), key=lambda s: -s[0] * s[1]):
            if best is not None and size[0] * size[1] <= best[0] * best[1]:
                break
            if size in tried:
                continue
            tried.add(size)
            if _classic(gray, size) is not None:
                best = size
                break
    return best


def check_board_size(files: Sequence[Path], pattern: tuple[int, int], *, frames: int = PROBE_FRAMES) -> None:
    """Raise CalibrationError (field ``--pattern``) naming the board size the images hold when the ``(cols, rows)``
    chessboard is in none of a few of ``files`` and a board of another size is; return otherwise."""
    grey = []
    for g in _probe_frames(files, frames):
        if _classic(g, pattern) is not None:
            return
        grey.append(g)
    found = board_size_in(grey)
    if found is None or sorted(found) == sorted(pattern):
        return
    cols, rows = found if pattern[0] >= pattern[1] else found[::-1]
    raise CalibrationError(f"no {pattern[0]}x{pattern[1]} chessboard found; the images hold a {cols}x{rows} board "
                           f"(inner corners): use --pattern {cols}x{rows}", field="--pattern")
