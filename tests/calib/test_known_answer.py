"""Known answers: synthesise a rig with known parameters, calibrate, and check they come back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.calib import calibrate_stereo, find_stereo_pairs
from s2r.profile import StereoProfile
from tests.calib.conftest import distorted_truth


def test_synthetic_rig_recovered_within_tolerances(synthetic_set: tuple[Path, StereoProfile]) -> None:
    folder, truth = synthetic_set
    pairs = find_stereo_pairs(folder)
    result = calibrate_stereo(pairs.left, pairs.right, names=pairs.names, jobs=2)
    p = result.profile
    for cam, true in ((p.left, truth.left), (p.right, truth.right)):
        assert cam.std is not None
        for key, tol in (("fx_px", 0.0015 * true.fx_px), ("fy_px", 0.0015 * true.fy_px), ("cx_px", 0.7),
                         ("cy_px", 0.7)):
            got, want, sd = getattr(cam, key), getattr(true, key), getattr(cam.std, key)
            assert abs(got - want) <= tol, (key, got, want)
            assert sd is not None and sd > 0 and abs(got - want) <= 3 * sd, (key, got, want, sd)
    assert abs(p.baseline_m - truth.baseline_m) <= 0.002 * truth.baseline_m
    b_std = p.extrinsics.baseline_std_m
    assert b_std is not None and abs(p.baseline_m - truth.baseline_m) <= 3 * b_std
    assert np.allclose(p.R, truth.R, atol=2e-3)
    assert p.provenance.origin == "real"
    q = p.provenance.calibration
    assert q is not None and q.views_used >= 20 and q.rms_stereo_px is not None and q.rms_stereo_px < 0.3
    assert q.epipolar_rms_px is not None and q.epipolar_rms_px < 0.3


@pytest.mark.slow
def test_pybullet_rendered_boards_recover_the_rig(tmp_path: Path) -> None:
    """The renderer's physically rendered boards (PyBullet TinyRenderer, 2x supersampled, distortion)."""
    boards = pytest.importorskip("s2r.render.boards.sets")
    truth = distorted_truth()
    rendered = boards.render_board_set(truth, tmp_path / "boards", views=20, seed=0, supersample=2,
                                       noise_sigma=1.0, jobs=2)
    result = calibrate_stereo(rendered.left_paths, rendered.right_paths, jobs=2)
    p = result.profile
    for cam, true in ((p.left, truth.left), (p.right, truth.right)):
        assert cam.std is not None
        for key, tol in (("fx_px", 0.0015 * true.fx_px), ("fy_px", 0.0015 * true.fy_px), ("cx_px", 0.7),
                         ("cy_px", 0.7)):
            got, want, sd = getattr(cam, key), getattr(true, key), getattr(cam.std, key)
            assert abs(got - want) <= min(tol, 3 * sd), (key, got, want, sd)
    b_std = p.extrinsics.baseline_std_m
    assert b_std is not None
    assert abs(p.baseline_m - truth.baseline_m) <= min(0.002 * truth.baseline_m, 3 * b_std)


def test_progress_is_reported_per_image(small_set: Path) -> None:
    calls: list[tuple[int, int, str]] = []
    pairs = find_stereo_pairs(small_set)
    calibrate_stereo(pairs.left, pairs.right, jobs=1, progress=lambda d, t, label: calls.append((d, t, label)))
    detecting = [c for c in calls if c[2] == "detecting corners"]
    assert [c[0] for c in detecting] == list(range(1, 17)) and {c[1] for c in detecting} == {16}
    assert calls[-1] == (1, 1, "solving")
