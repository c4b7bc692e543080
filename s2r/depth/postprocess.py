"""Named, optional post-processing stages on OpenCV's fixed-point disparity.

Every stage works on the matcher's raw output: int16, disparity * 16, in the rectified LEFT image, with
``invalid = (min_disparity - 1) * 16`` marking pixels without a match (OpenCV's own convention). A stage never
turns an invalid pixel into 0 px or 0 m: it either leaves it invalid or fills it with a neighbour's disparity.

Stages (apply in the order given):

- ``speckle``: ``cv2.filterSpeckles`` removes connected blobs smaller than the matcher's speckle window
  (100 px when the matcher has none) whose disparities stay within 2 px of each other.
- ``lr-check``: left-right consistency. The right image's disparity comes from matching the horizontally
  flipped pair (flip(right) as left, flip(left) as right); a left pixel x with disparity d is kept when the
  right disparity at round(x - d) agrees within 1 px (pixels landing in the right matcher's blind right
  border, ``min_disparity + num_disparities`` wide, cannot be checked and are kept).
- ``median``: the seed's ``cv2.medianBlur`` with a 5x5 window, kept on valid pixels only. The seed blurs
  holes in too; on Middlebury that adds wrong pixels (bad-2.0 up 0.1-0.4 points), so holes stay holes here and
  filling is the separate ``fill`` stage.
- ``close``: the seed's 3x3 morphological close (dilate, then erode), kept on valid pixels only (as median).
- ``seed-median`` / ``seed-close``: the seed's own calls verbatim, ``cv2.medianBlur(raw, 5)`` and
  ``cv2.morphologyEx(raw, MORPH_CLOSE, ones(3, 3))`` on the whole fixed-point image, holes included (they blur
  valid neighbours into holes and the invalid marker into edges). The ``seed-sgbm`` preset's default, so that
  preset reproduces the seed bit for bit; on Middlebury they cost 0.2-0.5 points of bad-2.0 against the raw match.
- ``fill``: row-wise hole filling from the background: an invalid run takes the smaller disparity (the
  farther surface) of the nearest valid pixels to its left and right (occlusions belong to the background).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.names import STAGES
from s2r.errors import DepthError

__all__ = [
    "STAGES",
    "check_stages",
    "close",
    "fill_background",
    "lr_check",
    "median",
    "seed_close",
    "seed_median",
    "speckle",
]

Raw = NDArray[np.int16]

SPECKLE_WINDOW_PX = 100
SPECKLE_RANGE_PX = 2
LR_MAX_DIFF_PX = 1.0
_CLOSE_KERNEL = np.ones((3, 3), np.uint8)


def check_stages(stages: Sequence[str]) -> tuple[str, ...]:
    """``stages`` as a tuple after checking every name; :class:`DepthError` names an unknown one."""
    if isinstance(stages, str):
        stages = [s for s in stages.split(",") if s]
    for name in stages:
        if name not in STAGES:
            raise DepthError(f"unknown post-processing stage {name!r}", field="postprocess",
                             hint=f"choose from {', '.join(STAGES)}")
    return tuple(stages)


def speckle(raw: Raw, *, invalid: int, window_px: int = SPECKLE_WINDOW_PX) -> Raw:
    """Invalidate connected blobs under ``window_px`` pixels (disparity steps within 2 px join a blob)."""
    out = raw.copy()
    cv2.filterSpeckles(out, invalid, window_px or SPECKLE_WINDOW_PX, SPECKLE_RANGE_PX * 16)
    return out


def _on_valid(raw: Raw, filtered: Raw, invalid: int) -> Raw:
    """``filtered`` where ``raw`` was valid and stays valid, ``invalid`` elsewhere (filters never fill holes)."""
    keep = (raw > invalid) & (filtered > invalid)
    return np.where(keep, filtered, np.int16(invalid)).astype(np.int16)


def median(raw: Raw, *, invalid: int) -> Raw:
    """The seed's 5x5 ``cv2.medianBlur``, applied to valid pixels only: holes stay holes (a pixel whose
    window is mostly invalid becomes invalid)."""
    return _on_valid(raw, np.asarray(cv2.medianBlur(raw, 5), dtype=np.int16), invalid)


def close(raw: Raw, *, invalid: int) -> Raw:
    """The seed's 3x3 morphological close (dilate, then erode), applied to valid pixels only: it removes
    one- and two-pixel far outliers inside a surface without inventing disparities in holes."""
    closed = np.asarray(cv2.morphologyEx(raw, cv2.MORPH_CLOSE, _CLOSE_KERNEL), dtype=np.int16)
    return _on_valid(raw, closed, invalid)


def seed_median(raw: Raw) -> Raw:
    """The seed's ``cv2.medianBlur(disparity, 5)`` on the whole fixed-point image (holes included)."""
    return np.asarray(cv2.medianBlur(raw, 5), dtype=np.int16)


def seed_close(raw: Raw) -> Raw:
    """The seed's ``cv2.morphologyEx(disparity, cv2.MORPH_CLOSE, ones((3, 3)))`` on the whole image."""
    return np.asarray(cv2.morphologyEx(raw, cv2.MORPH_CLOSE, _CLOSE_KERNEL), dtype=np.int16)


def lr_check(
    raw_left: Raw, raw_right: Raw, *, invalid: int, blind_px: int = 0, max_diff_px: float = LR_MAX_DIFF_PX
) -> Raw:
    """Keep left disparities the right image's disparity confirms within ``max_diff_px`` (vectorised).

    Args:
        raw_left: fixed-point disparity of the left image, (H, W) int16.
        raw_right: fixed-point disparity of the right image (x_left = x_right + d), (H, W) int16.
        invalid: the fixed-point marker of unmatched pixels.
        blind_px: width of the right image's right border the flipped match cannot cover
            (min_disparity + num_disparities); left pixels landing there are kept unchecked.
    """
    w = raw_left.shape[1]
    d_left = raw_left.astype(np.float32) * np.float32(1 / 16)
    x_right = np.rint(np.arange(w, dtype=np.float32)[None, :] - d_left).astype(np.intp)
    inside = (x_right >= 0) & (raw_left > invalid)
    blind = x_right >= w - blind_px  # the right matcher cannot see there: keep the left value unchecked
    np.clip(x_right, 0, w - 1, out=x_right)
    matched = np.take_along_axis(raw_right, x_right, axis=1)
    agree = (matched > invalid) & (np.abs(raw_left - matched.astype(np.int32)) <= max_diff_px * 16)
    return np.where(inside & (agree | blind), raw_left, np.int16(invalid)).astype(np.int16)


def fill_background(raw: Raw, *, invalid: int) -> Raw:
    """Fill invalid runs row by row with the smaller (farther) of the nearest valid disparities either side.

    A run touching the image border takes its one valid neighbour; a row without any valid pixel stays invalid.
    """
    w = raw.shape[1]
    valid = raw > invalid
    cols = np.arange(w, dtype=np.intp)[None, :]
    left_idx = np.maximum.accumulate(np.where(valid, cols, -1), axis=1)
    right_idx = np.minimum.accumulate(np.where(valid, cols, w)[:, ::-1], axis=1)[:, ::-1]
    big = np.int32(np.iinfo(np.int16).max)
    left_val = np.where(left_idx >= 0, np.take_along_axis(raw, np.clip(left_idx, 0, w - 1), axis=1), big)
    right_val = np.where(right_idx < w, np.take_along_axis(raw, np.clip(right_idx, 0, w - 1), axis=1), big)
    fill = np.minimum(left_val, right_val)
    fill = np.where(fill == big, invalid, fill)
    return np.where(valid, raw, fill).astype(np.int16)
