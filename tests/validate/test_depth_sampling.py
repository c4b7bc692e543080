"""Phase sampling: seeded jitter, span planes covering 1.5x in depth, bootstrap intervals, measured sub-pixel RMS."""

from __future__ import annotations

import numpy as np
import pytest

from s2r.render.layouts import SPAN_RATIO, _field_rays, _span
from s2r.validate.measures.depth_sampling import JITTER, BinSamples, frame_subpixel_rms, jitter_distances
from s2r.validate.settings import FULL, QUICK
from tests.conftest import make_rig


def test_jitter_is_seeded_and_bounded() -> None:
    d = (0.6, 1.0, 2.0, 4.0)
    a, b = jitter_distances(d, seed=0), jitter_distances(d, seed=1)
    assert a == jitter_distances(d, seed=0) and a != b
    shifted = jitter_distances(tuple(1.04 * x for x in d), seed=0)
    np.testing.assert_allclose(shifted, 1.04 * np.array(a))  # a 4 % shift moves every frame by exactly 4 %
    for x, y in zip(d, a, strict=True):
        assert x / (1 + JITTER) <= y <= x * (1 + JITTER)


def test_span_plane_covers_its_depth_ratio() -> None:
    rig = make_rig(name="span_rig", hfov_rad=1.5)
    for k in range(4):
        R = _span(rig, k, seed=2)
        n = R[:, 2]
        rays = _field_rays(rig)
        z = 1.0 / (rays @ n / n[2])  # depth along each border ray of the plane through (0, 0, 1)
        left, right = z[np.argmin(rays[:, 0])], z[np.argmax(rays[:, 0])]
        ratio = max(left, right) / min(left, right)
        assert ratio == pytest.approx(SPAN_RATIO, rel=0.25)
    assert ("span", FULL.distances_m) in FULL.scenes and ("span", QUICK.distances_m) in QUICK.scenes


def test_bootstrap_interval_brackets_the_median() -> None:
    rng = np.random.default_rng(0)
    samples = BinSamples([(1.0, 2.0)], seed=0)
    for _ in range(8):
        truth = rng.uniform(1.0, 2.0, 5000)
        samples.add(truth, rng.normal(0.0, 0.01, 5000))
    lo, hi = samples.interval(0) or (np.nan, np.nan)
    expected = 100 * 0.01 * 0.6745  # median |N(0, 1 %)|
    assert lo < expected < hi and hi - lo < 0.1
    assert samples.frames_in(0) == 8
    assert BinSamples([(1.0, 2.0)], seed=0).interval(0) is None


def test_measured_subpixel_rms_of_a_noisy_plane() -> None:
    rng = np.random.default_rng(1)
    K = np.array([[400.0, 0, 159.5], [0, 400.0, 119.5], [0, 0, 1]])
    ys, xs = np.mgrid[0:240, 0:320]
    x, y = (xs - 159.5) / 400.0, (ys - 119.5) / 400.0
    z = 2.0 / (1.0 - 0.2 * x - 0.05 * y)  # a slanted plane near 2 m
    fb = 400.0 * 0.05
    disparity = fb / z + rng.normal(0.0, 0.12, z.shape)  # 0.12 px matching noise
    got = frame_subpixel_rms(fb / disparity, K, fb)
    assert got == pytest.approx(0.12, rel=0.1)
