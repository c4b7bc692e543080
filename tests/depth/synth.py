"""Synthetic rectified stereo pairs with known disparity: a textured background plane and a nearer box."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class SynthPair:
    """Left/right grey images, the left image's true disparity (NaN where occluded) and the box region."""

    left: NDArray[np.uint8]
    right: NDArray[np.uint8]
    disparity: NDArray[np.float32]
    box: tuple[int, int, int, int]  # x0, x1, y0, y1 of the near box in the left image
    d_background: int
    d_box: int


def speckle_texture(rng: np.random.Generator, height: int, width: int) -> NDArray[np.uint8]:
    """Random speckle, 2x nearest-upsampled and lightly blurred so block matchers lock on."""
    small = rng.integers(0, 256, size=(height // 2 + 1, width // 2 + 1), dtype=np.uint8)
    big = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)[:height, :width]
    return np.asarray(cv2.GaussianBlur(big, (3, 3), 0), np.uint8)


def make_pair(*, width: int = 320, height: int = 240, d_background: int = 12, d_box: int = 30,
              seed: int = 0) -> SynthPair:
    """An ideal rectified pair (x_right = x_left - d): background at ``d_background`` px, a box at ``d_box`` px.

    Left pixel x sees the background texture at column x, the box texture at x inside the box; the right pixel x
    sees the box at x + d_box when that lands in the box, else the background at x + d_background.
    """
    rng = np.random.default_rng(seed)
    pad = d_box + 8
    bg = speckle_texture(rng, height, width + pad)
    fg = speckle_texture(rng, height, width + pad)
    x0, x1, y0, y1 = width // 2, width // 2 + width // 4, height // 4, 3 * height // 4
    cols = np.arange(width)
    rows = np.arange(height)[:, None]
    in_box_rows = (rows >= y0) & (rows < y1)
    left_box = in_box_rows & (cols >= x0) & (cols < x1)
    left = np.where(left_box, fg[:, :width], bg[:, :width])
    right_box = in_box_rows & (cols + d_box >= x0) & (cols + d_box < x1)
    right = np.where(right_box, fg[:, d_box:d_box + width], bg[:, d_background:d_background + width])
    truth = np.where(left_box, d_box, d_background).astype(np.float32)
    occluded = ~left_box & in_box_rows & (cols - d_background + d_box >= x0) & (cols - d_background + d_box < x1)
    truth[occluded] = np.nan
    return SynthPair(left=left.astype(np.uint8), right=right.astype(np.uint8), disparity=truth,
                     box=(x0, x1, y0, y1), d_background=d_background, d_box=d_box)
