"""The board itself: a chessboard's inner corners, outline and centre in the board frame.

The board frame (OpenCV's calibration object frame): origin at the first inner corner, x along the
pattern's columns, y along its rows, z into the board. Inner corner (i, j) sits at ``(i * square_m, j * square_m, 0)``,
metres. Imports numpy only: the pose search (``poses``), the target boards and the scenes share it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoardGeometry"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BoardGeometry:
    """A chessboard of ``pattern`` inner corners (columns, rows), ``square_m`` squares and a light margin."""

    pattern: tuple[int, int]
    square_m: float
    border_squares: float

    @property
    def extent_m(self) -> tuple[float, float, float, float]:
        """``(x0, y0, x1, y1)`` of the whole board (squares plus margin) in the board frame, metres."""
        s, b = self.square_m, self.border_squares
        return (-(1 + b) * s, -(1 + b) * s, (self.pattern[0] + b) * s, (self.pattern[1] + b) * s)

    @property
    def size_m(self) -> tuple[float, float]:
        """Board width and height with the margin, metres."""
        x0, y0, x1, y1 = self.extent_m
        return x1 - x0, y1 - y0

    def corners(self) -> FloatArray:
        """Inner corners ``(cols * rows, 3)`` in OpenCV's order (row by row), board frame, metres (read-only:
        made once per board, as the pose search asks for them thousands of times)."""
        return _corners(self)

    def outline(self, per_edge: int = 8) -> FloatArray:
        """Points ``(4 * per_edge, 3)`` along the board's outer edge, board frame, metres (read-only)."""
        return _outline(self, per_edge)

    def centre(self) -> FloatArray:
        """Centre of the squares area in the board frame, metres (read-only)."""
        return _centre(self)


def _read_only(a: FloatArray) -> FloatArray:
    a.setflags(write=False)
    return a


@functools.lru_cache(maxsize=16)
def _corners(board: BoardGeometry) -> FloatArray:
    cols, rows = board.pattern
    j, i = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return _read_only(np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]).astype(np.float64) * board.square_m)


@functools.lru_cache(maxsize=16)
def _outline(board: BoardGeometry, per_edge: int) -> FloatArray:
    x0, y0, x1, y1 = board.extent_m
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)
    xs = np.concatenate([x0 + (x1 - x0) * t, np.full_like(t, x1), x1 - (x1 - x0) * t, np.full_like(t, x0)])
    ys = np.concatenate([np.full_like(t, y0), y0 + (y1 - y0) * t, np.full_like(t, y1), y1 - (y1 - y0) * t])
    return _read_only(np.column_stack([xs, ys, np.zeros_like(xs)]))


@functools.lru_cache(maxsize=16)
def _centre(board: BoardGeometry) -> FloatArray:
    return _read_only(np.array([(board.pattern[0] - 1) / 2.0, (board.pattern[1] - 1) / 2.0, 0.0]) * board.square_m)
