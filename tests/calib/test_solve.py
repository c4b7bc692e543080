"""Solver conventions: outlier threshold, coverage grid, corner-order fix inside a full solve."""

from __future__ import annotations

import numpy as np
import pytest

from s2r.calib.detect.coverage import coverage_of, coverage_warnings
from s2r.calib.solve.solvers.cvsolve import distortion_flags, outlier_threshold
from s2r.errors import CalibrationError


def test_outlier_threshold_is_robust_and_floored() -> None:
    # median 1.0, MAD 0 -> max(1 + 0, 2 x 1.0, 0.3) = 2.0 px
    assert outlier_threshold(np.array([1.0, 1.0, 1.0, 1.0, 10.0])) == pytest.approx(2.0)
    # median 0.1, MAD 0.01 -> max(0.1 + 5 * 1.4826 * 0.01, 0.2, 0.3) = 0.3 px floor
    assert outlier_threshold(np.array([0.09, 0.1, 0.11, 0.1, 0.1])) == pytest.approx(0.3)
    errs = np.array([0.4, 0.5, 0.6, 0.5, 0.5])  # median 0.5, MAD 0 -> 2 x median = 1.0
    assert outlier_threshold(errs) == pytest.approx(1.0)
    assert outlier_threshold(errs, max_error_px=0.55) == 0.55


def test_coverage_grid_counts_corners_per_cell() -> None:
    # 640x480 split 8x6: cells of 80x80 px; corner (10, 10) -> cell (0, 0); (639, 479) -> (5, 7)
    cov = coverage_of([np.array([[10.0, 10.0], [639.0, 479.0], [85.0, 10.0]], np.float32)], (640, 480))
    assert cov.counts[0, 0] == 1 and cov.counts[5, 7] == 1 and cov.counts[0, 1] == 1
    # covered = the board's footprint (the triangle's area, about 7 % of the image), not 3 of 48 cells
    assert cov.counts.sum() == 3 and cov.fraction == pytest.approx(0.5 * 629 * 75 / (640 * 480), rel=0.25)
    assert cov.footprint is not None and cov.footprint.shape == (60, 80) and cov.footprint.max() == 1
    warnings = coverage_warnings("left", cov)
    assert len(warnings) == 1 and "top-right" in warnings[0] and "add views with the board there" in warnings[0]
    full = coverage_of([(np.mgrid[0:9, 0:6].T.reshape(-1, 2) * [79.8, 95.8]).astype(np.float32)], (640, 480))
    assert full.fraction > 0.98 and coverage_warnings("right", full) == []


def test_unknown_distortion_model_is_refused() -> None:
    with pytest.raises(CalibrationError, match="--distortion"):
        distortion_flags("fisheye")


def test_diverse_selection_keeps_every_region_of_a_large_set() -> None:
    from s2r.calib.solve.views import select_diverse

    rng = np.random.default_rng(1)
    grid = (np.mgrid[0:9, 0:6].T.reshape(-1, 2) * 20.0).astype(np.float32)
    # 190 views crowded in the top-left corner, 10 spread over the rest of a 640x480 image
    crowded = [grid + rng.uniform(0, 40, 2).astype(np.float32) for _ in range(190)]
    spread = [grid + np.array([x, y], np.float32) for x in (200, 300, 440) for y in (150, 300, 370)] + [grid + 250]
    views = crowded + spread
    chosen = select_diverse(views, (9, 6), (640, 480), max_views=30)
    assert len(chosen) == 30 and chosen == sorted(set(chosen))
    assert set(range(190, 200)) <= set(chosen)  # every distinct view survives; the crowd is thinned
    assert select_diverse(views[:12], (9, 6), (640, 480), max_views=30) == list(range(12))
