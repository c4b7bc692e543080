"""Post-processing stages on hand-made fixed-point disparities (int16, px * 16, invalid -16)."""

from __future__ import annotations

import numpy as np
import pytest

from s2r.depth import postprocess as pp
from s2r.errors import DepthError

INV = -16


def test_lr_check_keeps_consistent_and_drops_inconsistent() -> None:
    left = np.full((1, 10), INV, np.int16)
    right = np.full((1, 10), INV, np.int16)
    left[0, 5] = 2 * 16  # x=5, d=2 -> right x=3
    right[0, 3] = 2 * 16 + 8  # 2.5 px: agrees within 1 px
    left[0, 7] = 3 * 16  # -> right x=4 holds 5 px: disagrees
    right[0, 4] = 5 * 16
    left[0, 8] = 1 * 16  # -> right x=7, invalid there: dropped
    left[0, 1] = 4 * 16  # -> x=-3, outside the image: dropped
    out = pp.lr_check(left, right, invalid=INV)
    assert out[0].tolist() == [INV, INV, INV, INV, INV, 32, INV, INV, INV, INV]


def test_lr_check_keeps_pixels_the_right_matcher_cannot_see() -> None:
    left = np.full((1, 10), INV, np.int16)
    right = np.full((1, 10), INV, np.int16)
    left[0, 9] = 16  # lands on right x=8, inside a 3 px blind border (x >= 7)
    assert pp.lr_check(left, right, invalid=INV, blind_px=3)[0, 9] == 16
    assert pp.lr_check(left, right, invalid=INV, blind_px=0)[0, 9] == INV


def test_fill_takes_the_farther_neighbour() -> None:
    raw = np.array([[INV, 80, INV, INV, 32, INV, INV], [INV] * 7], np.int16)
    out = pp.fill_background(raw, invalid=INV)
    assert out[0].tolist() == [80, 80, 32, 32, 32, 32, 32]  # borders take their one neighbour
    assert out[1].tolist() == [INV] * 7  # a row without data stays invalid


def test_median_and_close_never_fill_holes() -> None:
    raw = np.full((9, 9), 20 * 16, np.int16)
    raw[4, 4] = INV  # a one-pixel hole
    raw[2, 2] = 60 * 16  # an outlier
    med = pp.median(raw, invalid=INV)
    assert med[4, 4] == INV and med[2, 2] == 20 * 16
    closed = pp.close(raw, invalid=INV)
    assert closed[4, 4] == INV
    assert closed.dtype == np.int16


def test_speckle_removes_small_blobs() -> None:
    raw = np.full((40, 40), 10 * 16, np.int16)
    raw[5:8, 5:8] = 40 * 16  # 9 px blob far from its surroundings
    out = pp.speckle(raw, invalid=INV, window_px=50)
    assert np.all(out[5:8, 5:8] == INV) and out[20, 20] == 160


def test_check_stages() -> None:
    assert pp.check_stages("lr-check,median") == ("lr-check", "median")
    assert pp.check_stages([]) == ()
    with pytest.raises(DepthError, match=r"postprocess: unknown post-processing stage 'x'.*speckle, lr-check"):
        pp.check_stages(["x"])
