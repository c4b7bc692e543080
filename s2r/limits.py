"""Size bounds shared across layers, in a module that loads nothing (the profile's validators, the image reader
and the CLI's argument checks use the same numbers without importing the models that carry them)."""

from __future__ import annotations

__all__ = ["MAX_IMAGE_PX", "MAX_SQUARE_M", "MIN_IMAGE_PX"]

#: Image side bounds, pixels. 16384 is above the largest sensors used for stereo (about 14000 px) and keeps the
#: float32 rectification maps under 2 GiB; below 16 px no block matcher (5..21 px blocks) has room to work.
MIN_IMAGE_PX, MAX_IMAGE_PX = 16, 16384

#: Largest chessboard square (m) accepted from ``--square`` and by the board renderer: printed boards have
#: squares of millimetres to ~0.2 m; beyond 2 m the value is millimetres or a typo, and 1e308 overflows the
#: float32 board model.
MAX_SQUARE_M = 2.0
