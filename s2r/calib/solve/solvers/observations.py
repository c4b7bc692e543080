"""Board observations of a stereo calibration, per view and per camera, keyed by corner id.

A view may show a different subset of the board's corners in each camera (partial boards such as
ChArUco or AprilGrid); the left and right observations of one view are paired by corner id, never by
position in the arrays. A chessboard view sees every corner, ids ``0 .. cols*rows-1`` row-major.

Frames and units: ``obj`` board frame, metres (z = 0 for a flat board); ``img`` pixels (OpenCV
convention, 0-based pixel centres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoardObservation", "StereoObservation", "chessboard_observation"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class BoardObservation:
    """One camera's view of the board: corner ``ids`` (N,), board points ``obj`` (N, 3) m, pixels ``img`` (N, 2)."""

    ids: IntArray
    obj: FloatArray
    img: FloatArray

    def __post_init__(self) -> None:
        if not (len(self.ids) == len(self.obj) == len(self.img)):
            raise ValueError("ids, obj and img must have the same length")

    def subset(self, keep: NDArray[np.bool_]) -> BoardObservation:
        """The corners where ``keep`` is True."""
        return BoardObservation(self.ids[keep], self.obj[keep], self.img[keep])


@dataclass(frozen=True)
class StereoObservation:
    """One view (one board pose) seen by the left and/or the right camera."""

    name: str
    left: BoardObservation | None
    right: BoardObservation | None

    def common(self) -> tuple[BoardObservation, BoardObservation] | None:
        """Left and right observations restricted to the corners both saw, in the same id order (or None)."""
        if self.left is None or self.right is None:
            return None
        ids, il, ir = np.intersect1d(self.left.ids, self.right.ids, assume_unique=True, return_indices=True)
        if len(ids) == 0:
            return None
        return (BoardObservation(ids, self.left.obj[il], self.left.img[il]),
                BoardObservation(ids, self.right.obj[ir], self.right.img[ir]))


def chessboard_observation(obj: NDArray[np.floating], img: NDArray[np.floating]) -> BoardObservation:
    """A full chessboard view: ids ``0..N-1`` for corners (N, 2) px of board points (N, 3) m."""
    pts = np.asarray(img, np.float64).reshape(-1, 2)
    return BoardObservation(np.arange(len(pts), dtype=np.int64), np.asarray(obj, np.float64).reshape(-1, 3), pts)
