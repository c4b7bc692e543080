"""Repeated frames (a board held still while recording): merged, said so, and the std does not shrink."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.calib import calibrate_stereo, find_stereo_pairs
from s2r.profile import StereoProfile
from tests.calib.conftest import copy_pairs


def _triple(src: Path, dst: Path, pairs: int) -> Path:
    """Every pair three times: an exact copy and a copy with +-1 grey level of noise (near-identical)."""
    rng = np.random.default_rng(3)
    for side in ("left", "right"):
        (dst / side).mkdir(parents=True)
        for i in range(pairs):
            img = cv2.imread(str(src / side / f"{i:02d}.png"), cv2.IMREAD_GRAYSCALE)
            noisy = np.clip(img.astype(np.int16) + rng.integers(-1, 2, img.shape), 0, 255).astype(np.uint8)
            for k, copy in enumerate((img, img, noisy)):
                cv2.imwrite(str(dst / side / f"{3 * i + k:03d}.png"), copy)
    return dst


@pytest.mark.slow
def test_every_view_three_times_keeps_the_std(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path) -> None:
    folder, _ = synthetic_set
    unique = find_stereo_pairs(copy_pairs(folder, tmp_path / "unique", range(12)))
    tripled = find_stereo_pairs(_triple(folder, tmp_path / "tripled", 12))
    one = calibrate_stereo(unique.left, unique.right, pattern=(9, 6), square_m=0.025, jobs=2, compare=False)
    three = calibrate_stereo(tripled.left, tripled.right, pattern=(9, 6), square_m=0.025, jobs=2, compare=False)
    repeats = [d for d in three.dropped if d.reason.startswith("repeat of")]
    assert len(repeats) == 24 and len(three.used_names) == len(one.used_names)
    assert any("repeat an earlier view" in w for w in three.warnings)
    for a, b in ((one.profile.left.std, three.profile.left.std), (one.profile.right.std, three.profile.right.std)):
        assert a is not None and b is not None and a.fx_px and b.fx_px and a.cx_px and b.cx_px
        assert abs(b.fx_px / a.fx_px - 1) < 0.15 and abs(b.cx_px / a.cx_px - 1) < 0.15
    sa, sb = one.profile.extrinsics.baseline_std_m, three.profile.extrinsics.baseline_std_m
    assert sa and sb and abs(sb / sa - 1) < 0.15


def test_a_still_board_with_one_misplaced_corner_is_a_repeat() -> None:
    """The detector misplaces the odd corner of a still frame (8-12 px on a real set with 2 grey levels of
    noise): the median corner distance still calls it a repeat; a board turned by 0.5 deg is a new view."""
    from s2r.calib.solve.views import REPEAT_PX, merge_repeats, repeat_distance

    grid = np.stack(np.meshgrid(np.arange(9.0), np.arange(6.0)), axis=-1).reshape(-1, 2) * 30 + (200, 150)
    rng = np.random.default_rng(8)
    still = grid + rng.normal(0, 0.02, grid.shape)
    still[17] += (9.0, -6.0)  # one corner the detector put 11 px off
    a = np.radians(0.5)
    turned = (grid - grid.mean(0)) @ np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]).T + grid.mean(0)
    assert repeat_distance(grid, still) < REPEAT_PX < repeat_distance(grid, turned)
    keep, repeats = merge_repeats(["a", "b", "c"], [grid, still, turned], [grid + 40, still + 40, turned + 40])
    assert keep == [0, 2] and [d.name for d in repeats] == ["b"] and repeats[0].reason.startswith("repeat of a")
