"""Textures: a checkerboard with a white quiet zone, and seeded multi-scale random speckle.

Textures are (H, W, 3) uint8 arrays (RGB). PNG files for PyBullet are written with :func:`write_png`.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.render.outputs import STORED_PNG

__all__ = ["checkerboard_texture", "speckle_texture", "write_png"]

#: Grey levels of the checkerboard's dark and light squares (not 0/255, so noise does not clip).
DARK, LIGHT = 20, 235


def checkerboard_texture(
    pattern: tuple[int, int], *, texels_per_square: int, border_squares: float
) -> NDArray[np.uint8]:
    """A chessboard of ``pattern`` inner corners (columns, rows) with a light border.

    The board has ``pattern[0] + 1`` x ``pattern[1] + 1`` squares, the top-left one dark, surrounded by
    ``border_squares`` squares of light margin. Returns (H, W, 3) uint8 RGB, ``texels_per_square`` per square.
    """
    cols, rows = pattern[0] + 1, pattern[1] + 1
    t = texels_per_square
    border = round(border_squares * t)
    j, i = np.meshgrid(np.arange(cols * t) // t, np.arange(rows * t) // t)
    board = np.where((i + j) % 2 == 0, DARK, LIGHT).astype(np.uint8)
    board = np.pad(board, border, constant_values=LIGHT)
    return np.repeat(board[:, :, None], 3, axis=2)


def speckle_texture(size_px: int, *, seed: int, finest_px: float = 1.0) -> NDArray[np.uint8]:
    """A seeded, non-repeating multi-scale speckle texture (size_px x size_px, RGB uint8).

    Octaves of white noise generated at ``size_px / scale`` and upsampled (bicubic) for scales from
    ``finest_px`` texels up to 1/8 of the texture, coarser octaves slightly weaker, so it stays matchable
    whether a texel covers a tenth of a pixel or ten.
    """
    rng = np.random.default_rng(seed)
    total = np.zeros((size_px, size_px), np.float32)
    scale, weight = finest_px, 1.0
    while scale <= size_px / 8:
        n = max(4, round(size_px / scale))
        noise = rng.standard_normal((n, n)).astype(np.float32)
        layer = noise if n == size_px else np.asarray(
            cv2.resize(noise, (size_px, size_px), interpolation=cv2.INTER_CUBIC), dtype=np.float32)
        total += np.float32(weight / (float(layer.std()) + 1e-9)) * layer
        scale, weight = scale * 2.0, weight * 0.8
    total = (total - total.mean()) / (total.std() + 1e-9)
    grey = np.clip(128.0 + 45.0 * total, 10, 245)
    tint = rng.uniform(0.85, 1.15, size=3).astype(np.float32)
    rgb = np.clip(grey[:, :, None] * tint[None, None, :], 0, 255)
    return np.asarray(np.round(rgb), dtype=np.uint8)


def write_png(path: str | Path, rgb: NDArray[np.uint8]) -> str:
    """Write an RGB texture as PNG (OpenCV wants BGR; stored uncompressed, :data:`s2r.render.outputs.STORED_PNG`: a
    temporary file the renderer reads once); returns the absolute path."""
    out = Path(path).resolve()
    bgr = np.ascontiguousarray(rgb[:, :, ::-1])
    if not cv2.imwrite(str(out), bgr, list(STORED_PNG)):
        raise OSError(f"cannot write texture {out}")
    return str(out)
