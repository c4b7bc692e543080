"""Mutual matching searches backwards only from the ratio-test survivors: the same pairs as a full search."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from s2r.drift.matches import RATIO, _detect, _mutual_matches


def _full_search(desc_l: np.ndarray, desc_r: np.ndarray, norm: int) -> list[tuple[int, int]]:
    """The plain rule: ratio test on every left descriptor, mutual check against a backward search of every right
    descriptor."""
    matcher = cv2.BFMatcher(norm)
    backward = {m.queryIdx: m.trainIdx for m, *_ in matcher.knnMatch(desc_r, desc_l, k=1)}
    return [(m.queryIdx, m.trainIdx) for m, n in (c for c in matcher.knnMatch(desc_l, desc_r, k=2) if len(c) == 2)
            if m.distance < RATIO * n.distance and backward.get(m.trainIdx) == m.queryIdx]


@pytest.mark.parametrize(("kind", "norm"), [("sift", cv2.NORM_L2), ("orb", cv2.NORM_HAMMING)])
def test_mutual_matches_equal_a_full_backward_search(kind: str, norm: int) -> None:
    rng = np.random.default_rng(5)
    texture = cv2.GaussianBlur(rng.integers(0, 256, (360, 480), dtype=np.uint8), (0, 0), 1.5)
    left = cv2.normalize(texture, None, 0, 255, cv2.NORM_MINMAX)
    right = np.roll(left, -12, axis=1)  # a disparity of 12 px
    right = np.clip(right.astype(np.int16) + rng.integers(-6, 7, right.shape), 0, 255).astype(np.uint8)
    _, desc_l = _detect(left, kind, 2000)
    _, desc_r = _detect(right, kind, 2000)
    assert desc_l is not None and desc_r is not None
    pairs = _mutual_matches(desc_l, desc_r, norm)
    assert len(pairs) > 50
    assert pairs == _full_search(desc_l, desc_r, norm)
