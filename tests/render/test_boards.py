"""Rendered calibration sets: corners where the profile puts them, poses inside both images, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from s2r.errors import OutputExistsError, RenderError
from s2r.geometry import rotation_angle_rad
from s2r.lens.distortion import project_points
from s2r.profile import SimulationSettings, StereoProfile
from s2r.render import render_board_set
from s2r.render.boards.poses import BoardGeometry, sample_board_poses
from tests.conftest import make_rig
from tests.render._helpers import detect

PATTERN = (9, 6)
#: The conftest ``distorted_rig`` fixture's parameters (fixtures cannot be parametrised over directly).
DISTORTED: dict[str, object] = {"name": "distorted_rig", "distortion": (-0.12, 0.05, 0.0, 0.0, 0.0),
                                "rotation_deg": (0.3, -0.5, 0.2), "cx": 322.0, "cy": 238.5}


def _corner_errors(profile: StereoProfile, out: Path, views: int) -> list[float]:
    """Mean corner error per image; also checks there is no systematic offset (pixel-offset and supersampling
    conventions: a half-pixel slip in either would bias every corner by 0.25-0.5 px)."""
    result = render_board_set(profile, out, views=views, supersample=2, jobs=1)
    board = BoardGeometry(PATTERN, 0.025, 1.0)
    errors, offsets = [], []
    for k, T in enumerate(result.poses):
        X_left = board.corners() @ T[:3, :3].T + T[:3, 3]
        for path, cam, X in ((result.left_paths[k], profile.left, X_left),
                             (result.right_paths[k], profile.right, X_left @ profile.R.T + profile.T)):
            found = detect(path, PATTERN)
            assert found is not None, f"board not detected in {path}"
            diff = found - project_points(cam, X)
            errors.append(float(np.linalg.norm(diff, axis=1).mean()))
            offsets.append(diff.mean(axis=0))
    assert np.all(np.abs(np.mean(offsets, axis=0)) < 0.05), np.mean(offsets, axis=0)
    return errors


def test_corners_match_projection_without_distortion(rig: StereoProfile, tmp_path: Path) -> None:
    errors = _corner_errors(rig, tmp_path / "set", views=6)
    assert np.mean(errors) < 0.2, errors


@pytest.mark.slow
def test_corners_match_projection_with_distortion(distorted_rig: StereoProfile, tmp_path: Path) -> None:
    errors = _corner_errors(distorted_rig, tmp_path / "set", views=6)
    assert np.mean(errors) < 0.2, errors


def test_poses_are_seeded_and_fit_both_images(rig: StereoProfile) -> None:
    board = BoardGeometry(PATTERN, 0.025, 1.0)
    poses = sample_board_poses(rig, board, views=12, seed=3)
    again = sample_board_poses(rig, board, views=12, seed=3)
    other = sample_board_poses(rig, board, views=12, seed=4)
    np.testing.assert_array_equal(np.array(poses), np.array(again))
    assert not np.allclose(np.array(poses), np.array(other))
    tilts, centres = [], []
    for T in poses:
        tilts.append(math.degrees(math.acos(np.clip(T[2, 2], -1, 1))))
        outline = board.outline() @ T[:3, :3].T + T[:3, 3]
        for cam, X in ((rig.left, outline), (rig.right, outline @ rig.R.T + rig.T)):
            uv = project_points(cam, X)
            assert uv.min() >= 0 and uv[:, 0].max() < cam.width_px and uv[:, 1].max() < cam.height_px
        corners = project_points(rig.left, board.corners() @ T[:3, :3].T + T[:3, 3])
        centres.append(corners.mean(axis=0))
        width_frac = np.ptp(project_points(rig.left, outline)[:, 0]) / rig.left.width_px
        assert 0.15 < width_frac < 0.75
    assert max(tilts) > 30 and max(tilts) < 50  # tilts up to about 45 deg
    centres_arr = np.array(centres)
    assert np.ptp(centres_arr[:, 0]) > 0.3 * rig.left.width_px  # covers the image, not just its centre
    assert np.ptp(centres_arr[:, 1]) > 0.3 * rig.left.height_px


def test_truth_file_holds_profile_and_poses(rig: StereoProfile, tmp_path: Path) -> None:
    result = render_board_set(rig, tmp_path / "set", views=2, supersample=1, jobs=1, seed=5)
    assert [p.name for p in result.left_paths] == ["00.png", "01.png"]
    assert all(p.exists() for p in result.left_paths + result.right_paths)
    truth = yaml.safe_load(result.truth_path.read_text())
    assert StereoProfile.model_validate(truth["profile"]) == rig
    assert truth["pattern"] == [9, 6] and truth["square_m"] == 0.025 and truth["seed"] == 5
    np.testing.assert_allclose(np.array(truth["views"][1]["T_left_board"]), result.poses[1])


def test_parallel_render_equals_in_process(rig: StereoProfile, tmp_path: Path) -> None:
    a = render_board_set(rig, tmp_path / "a", views=2, supersample=1, jobs=1, noise_sigma=2.0)
    b = render_board_set(rig, tmp_path / "b", views=2, supersample=1, jobs=2, noise_sigma=2.0)
    for pa, pb in zip(a.left_paths + a.right_paths, b.left_paths + b.right_paths, strict=True):
        assert pa.read_bytes() == pb.read_bytes()


def test_clip_planes_that_cannot_hold_the_board(rig: StereoProfile, tmp_path: Path) -> None:
    near_far = rig.model_copy(update={"simulation": SimulationSettings(clip_near_m=0.05, clip_far_m=0.3)})
    with pytest.raises(RenderError, match=r"simulation\.clip_far_m.*raise clip_far_m") as info:
        render_board_set(near_far, tmp_path / "x", views=2)
    assert "\n" not in str(info.value)
    too_near = rig.model_copy(update={"simulation": SimulationSettings(clip_near_m=2.0, clip_far_m=50.0)})
    with pytest.raises(RenderError, match=r"simulation\.clip_near_m.*lower clip_near_m"):
        render_board_set(too_near, tmp_path / "x", views=2)
    assert not (tmp_path / "x").exists()


def test_pattern_too_large_for_the_view(rig: StereoProfile, tmp_path: Path) -> None:
    with pytest.raises(RenderError, match=r"^pattern: a 60x40 board .* cannot fit the view"):
        render_board_set(rig, tmp_path / "x", views=2, pattern=(60, 40))


def test_output_folder_with_files_is_refused(rig: StereoProfile, tmp_path: Path) -> None:
    out = tmp_path / "set"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    with pytest.raises(OutputExistsError, match="pass --force"):
        render_board_set(rig, out, views=1, supersample=1, jobs=1)
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]
    render_board_set(rig, out, views=3, supersample=1, jobs=1, force=True)
    render_board_set(rig, out, views=1, supersample=1, jobs=1, force=True)
    assert sorted(p.name for p in (out / "left").iterdir()) == ["00.png"]  # no stale views from the bigger set
    assert not (out / "keep.txt").exists()  # --force replaces the output folder whole, never merges


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"views": 0}, "views"), ({"pattern": (1, 6)}, "pattern"), ({"square_m": 0.0}, "square_m"),
    ({"supersample": 0}, "supersample"), ({"noise_sigma": -1.0}, "noise_sigma"), ({"jobs": 0}, "jobs"),
])
def test_bad_options_name_the_field(rig: StereoProfile, tmp_path: Path, kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(RenderError, match=rf"^{field}: "):
        render_board_set(rig, tmp_path / "x", **kwargs)  # type: ignore[arg-type]


@pytest.mark.slow
@pytest.mark.parametrize("distorted", [False, True], ids=["pinhole", "distorted"])
def test_plain_opencv_calibration_recovers_the_profile(tmp_path: Path, distorted: bool) -> None:
    """20 rendered views at 2x: cv2.calibrateCamera per camera + stereoCalibrate(FIX_INTRINSIC) recover fx
    within 0.15 % and the baseline within 0.2 % (the calibration issue's tolerances)."""
    import cv2

    rig = make_rig(**DISTORTED) if distorted else make_rig()
    result = render_board_set(rig, tmp_path / "set", views=20, supersample=2, seed=0)
    obj = BoardGeometry(PATTERN, 0.025, 1.0).corners().astype(np.float32)
    left = [detect(p, PATTERN) for p in result.left_paths]
    right = [detect(p, PATTERN) for p in result.right_paths]
    pairs = [(a, b) for a, b in zip(left, right, strict=True) if a is not None and b is not None]
    assert len(pairs) >= 18
    objs = [obj] * len(pairs)
    size = rig.image_size
    flags = cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST
    calib = []
    for side in (0, 1):
        pts = [p[side].astype(np.float32).reshape(-1, 1, 2) for p in pairs]
        rms, K, D, _, _ = cv2.calibrateCamera(objs, pts, size, None, None, flags=flags)
        assert rms < 0.2
        assert K[0, 0] == pytest.approx(rig.left.fx_px, rel=0.0015)
        assert D[0, 0] == pytest.approx(rig.left.D[0], abs=0.01)
        calib.append((pts, K, D))
    (pl, Kl, Dl), (pr, Kr, Dr) = calib
    rms, *_, R, T, _, _ = cv2.stereoCalibrate(objs, pl, pr, Kl, Dl, Kr, Dr, size, flags=cv2.CALIB_FIX_INTRINSIC)
    assert float(np.linalg.norm(T)) == pytest.approx(rig.baseline_m, rel=0.002)
    assert math.degrees(rotation_angle_rad(R.T @ rig.R)) < 0.15  # cx/cy errors of ~0.5 px tilt R by ~0.05 deg


def _render_in_pool_worker(out: str) -> int:
    profile = make_rig()
    return len(render_board_set(profile, out, views=2, supersample=1, jobs=2).poses)


def test_render_inside_a_pool_worker_falls_back_to_one_process(tmp_path: Path) -> None:
    """A daemonic multiprocessing.Pool worker cannot start processes; rendering falls back to in-process."""
    import multiprocessing

    with multiprocessing.Pool(1) as pool:
        assert pool.apply(_render_in_pool_worker, (str(tmp_path / "set"),)) == 2
