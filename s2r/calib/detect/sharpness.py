"""Blurred frames of a video, told apart before detection: the variance of the Laplacian.

The sharpness of a grey frame is the variance of its Laplacian (OpenCV's 3x3 aperture, ``ksize=1``: the 4-neighbour
kernel), measured on a copy shrunk (INTER_AREA) to at most :data:`SHARPNESS_WIDTH_PX` wide so the figure does not
depend on the camera's resolution. A frame is *blurred* when, in either camera, it is

- below :data:`MIN_SHARPNESS` (an absolute floor: the OpenCV stereo chessboard set measures 530-780 sharp, 26-42
  under a Gaussian blur of sigma 1.5 px, 5-7 under sigma 3 px), or
- below ``ratio`` (default :data:`BLUR_RATIO`) times the median sharpness of the last :data:`WINDOW` frames kept
  (a hand moving the board smears it: a 15 px motion blur keeps 0.22-0.38 of a still frame's figure on that set,
  while its sharp frames lie within 0.68-1.0 of each other).

Blurred frames are skipped and counted with the figure that condemned them; the first frames (fewer than 5 kept)
are judged by the floor alone.
"""

from __future__ import annotations

import statistics
from collections import deque
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["BLUR_RATIO", "MIN_SHARPNESS", "SHARPNESS_WIDTH_PX", "BlurFilter", "sharpness"]

SHARPNESS_WIDTH_PX = 640
MIN_SHARPNESS = 15.0
BLUR_RATIO = 0.35
WINDOW = 25


def sharpness(grey: NDArray[np.uint8]) -> float:
    """Variance of the Laplacian of an 8-bit grey image (H, W), on a copy at most 640 px wide (module docstring)."""
    width = grey.shape[1]
    if width > SHARPNESS_WIDTH_PX:
        scale = SHARPNESS_WIDTH_PX / width
        small = cv2.resize(grey, (SHARPNESS_WIDTH_PX, max(1, round(grey.shape[0] * scale))),
                           interpolation=cv2.INTER_AREA)
        return float(cv2.Laplacian(small, cv2.CV_64F, ksize=1).var())
    return float(cv2.Laplacian(grey, cv2.CV_64F, ksize=1).var())


@dataclass
class BlurFilter:
    """Judges frames in recording order (module docstring); ``ratio`` 0 keeps the floor only."""

    ratio: float = BLUR_RATIO
    floor: float = MIN_SHARPNESS
    recent: deque[float] = field(default_factory=lambda: deque(maxlen=WINDOW))

    def reason(self, left: NDArray[np.uint8], right: NDArray[np.uint8]) -> str:
        """Why the pair is blurred ('' when it is sharp enough; it then joins the running median)."""
        value = min(sharpness(left), sharpness(right))
        if value < self.floor:
            return f"blurred: variance of the Laplacian {value:.1f} < {self.floor:g}"
        if self.ratio > 0 and len(self.recent) >= 5:
            median = statistics.median(self.recent)
            if value < self.ratio * median:
                return (f"blurred: variance of the Laplacian {value:.1f} < {self.ratio:g} x {median:.1f} (the median "
                        "of the frames before)")
        self.recent.append(value)
        return ""
