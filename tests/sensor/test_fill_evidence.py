"""A fill cliff needs evidence (issue 38): a distance bin of fewer than 3 frames is merged with its nearer
neighbour, and a point resting on fewer than 3 frames in all is flagged with its count, in the model and the
notes. Hand-made frames: the figures are hand-computed means."""

from __future__ import annotations

import pytest

from s2r.sensor.fit.depth import DepthFrame
from s2r.sensor.fit.run import fit_model


def _frame(name: str, distance_m: float, fill_pct: float) -> DepthFrame:
    return DepthFrame(name, distance_m, 0.1, fill_pct, None, None, None)


def test_one_tilted_frame_is_no_fill_cliff() -> None:
    near = [_frame(f"n{k}", d, 99.8) for k, d in enumerate((0.62, 0.66, 0.70))]
    tilted = [_frame("tilted", 0.90, 8.0)]  # alone in its 0.75-1.0 m bin
    far = [_frame(f"f{k}", d, 85.0) for k, d in enumerate((1.22, 1.26, 1.30))]
    fit = fit_model([], near + tilted + far, source="hand-made")
    points = fit.model.fill_rate_by_distance
    assert all(p.frames is not None and p.frames >= 3 for p in points)
    assert min(p.fill_rate_pct for p in points) > 60.0  # no 8 % point from one frame
    merged = next(p for p in points if p.frames == 4)
    assert merged.fill_rate_pct == pytest.approx((3 * 99.8 + 8.0) / 4)  # the nearer neighbour: 0.66 m, not 1.26
    assert merged.distance_m == pytest.approx((0.62 + 0.66 + 0.70 + 0.90) / 4)
    assert "merged with their neighbours" in fit.notes["fill_rate_by_distance"]


def test_too_few_frames_in_all_are_flagged_with_their_count() -> None:
    fit = fit_model([], [_frame("a", 1.0, 90.0), _frame("b", 2.5, 70.0)], source="hand-made")
    (point,) = fit.model.fill_rate_by_distance
    assert point.frames == 2 and point.fill_rate_pct == pytest.approx(80.0)
    assert "FEW FRAMES: 1.75 m rests on 2" in fit.notes["fill_rate_by_distance"]
