"""ROS's own consumers on s2r's outputs (Debian's ROS 1: image_geometry, camera_calibration_parsers,
stereo_image_proc, rosbag), on a loopback-only roscore. Run with ``make test-ros``.

- camera_info exported by ``convert --to ros`` through camera_calibration_parsers and image_geometry: the
  projections and depths equal s2r's.
- stereo_image_proc on a rendered, rotated, zero-distortion pair (a D435-like unit reports zero coefficients):
  its median depth within 1 % of s2r's, and with the matcher configured alike (the exported
  stereo_image_proc.yaml) its rectified images and disparities bit-identical to s2r's. Without the zero-distortion
  marker ROS passes the raw images through: the same check then fails by far (measured, asserted).
- A ROS 1 bag written by rosbag itself, calibrated by ``s2r calibrate --bag``.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.calib.solve.synth import write_stereo_set
from s2r.cli import main
from s2r.depth.pipeline import StereoPipeline
from s2r.formats.s2r_yaml import dump_profile, load_profile_file
from s2r.profile import MatcherSettings, StereoProfile
from s2r.rectification import stereo_rectification
from tests.conftest import make_rig, shared_data
from tests.ros.conftest import run_helper

pytestmark = pytest.mark.ros



def _rotated_d435_like(**matcher: object) -> StereoProfile:
    """320x240, 69 deg HFOV (fx 231.7), 50 mm baseline, zero distortion, the right camera turned (0.5, -2, 0.3) deg."""
    rig = make_rig(name="d435_like_rotated", width=320, height=240, hfov_rad=1.2, baseline_m=0.05,
                   rotation_deg=(0.5, -2.0, 0.3))
    settings = MatcherSettings.model_validate({**rig.matcher.model_dump(), "num_disparities": 32,
                                               "speckle_range": 16, "min_depth_m": 0.45, **matcher})
    frames = {"left": rig.left.model_copy(update={"frame_id": "d435_left_optical"}),
              "right": rig.right.model_copy(update={"frame_id": "d435_right_optical"})}
    return StereoProfile.model_validate({**rig.model_dump(), "matcher": settings.model_dump(),
                                         **{k: v.model_dump() for k, v in frames.items()}})


def _export(profile: StereoProfile, folder: Path) -> Path:
    src = folder / "profile.yaml"
    dump_profile(profile, src)
    assert main(["profile", "convert", str(src), "--to", "ros", "-o", str(folder / "ros")]) == 0
    return folder / "ros"


def test_camera_info_through_image_geometry(ros_env: dict[str, str], tmp_path: Path) -> None:
    for name, profile in (("rotated", _rotated_d435_like()),
                          ("distorted", make_rig(name="distorted", distortion=(-0.12, 0.05, 0.001, -0.0005, 0.0),
                                                 rotation_deg=(0.3, -0.5, 0.2), cx=322.0, cy=238.5))):
        folder = _export(profile, tmp_path / name)
        rect = stereo_rectification(profile, alpha=0.0)
        points = np.array([[0.1, -0.05, 1.2], [-0.3, 0.2, 2.5], [0.02, 0.01, 0.8], [0.25, 0.15, 4.0]])
        raw_left, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), profile.left.K, profile.left.D)
        rectified = points @ rect.R1.T
        hom = np.c_[rectified, np.ones(len(points))]
        left = (hom @ rect.P1.T)[:, :2] / (hom @ rect.P1.T)[:, 2:]
        right = (hom @ rect.P2.T)[:, :2] / (hom @ rect.P2.T)[:, 2:]
        disparities = [4.0, 12.5, 30.0]
        query = {"points_rect": rectified.tolist(), "raw_left": raw_left.reshape(-1, 2).tolist(),
                 "disparities": disparities}
        out = json.loads(run_helper(ros_env, "geometry", str(folder), stdin=json.dumps(query)))
        np.testing.assert_allclose(out["left"], left, atol=1e-6)
        np.testing.assert_allclose(out["right"], right, atol=1e-6)
        np.testing.assert_allclose(out["rectified_left"], left, atol=1e-4)  # undistortPoints iterates
        np.testing.assert_allclose(out["z"], [rect.fx_px * rect.baseline_m / d for d in disparities], rtol=1e-12)
        assert out["baseline"] == pytest.approx(rect.baseline_m, rel=1e-12)
        assert out["frame_ids"][0] == out["frame_ids"][1] == (profile.left.frame_id or "")


def _grey_pair(profile: StereoProfile, folder: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    scenes = pytest.importorskip("s2r.render.scenes", reason="needs the PyBullet renderer")
    frame = scenes.render_scene(profile, scene="span", distances_m=(1.0,), supersample=1, jobs=1)[0]
    left, right = (cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) for img in (frame.left, frame.right))
    cv2.imwrite(str(folder / "left.png"), left)
    cv2.imwrite(str(folder / "right.png"), right)
    return left, right, frame.depth_rect_m


def _ros_depth(ros_env: dict[str, str], folder: Path, out: Path) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    out.mkdir()
    run_helper(ros_env, "stereo", str(folder), str(folder.parent / "left.png"), str(folder.parent / "right.png"),
               str(out))
    meta = json.loads((out / "disparity.json").read_text())
    disparity = np.load(out / "disparity.npy")
    valid = disparity >= max(meta["min_disparity"], 0) + 0.5  # -1 (min_disparity - 1) marks no match
    depth = np.where(valid, meta["f"] * meta["T"] / np.where(valid, disparity, 1.0), np.nan)
    return disparity, depth, meta


def test_stereo_image_proc_rectifies_a_rotated_zero_distortion_pair(ros_env: dict[str, str], tmp_path: Path) -> None:
    profile = _rotated_d435_like()
    folder = _export(profile, tmp_path)
    left, right, _ = _grey_pair(profile, tmp_path)
    result = StereoPipeline(profile, preset="profile", postprocess=()).compute(left, right)
    s2r_median = float(np.nanmedian(result.depth))
    disparity, depth, meta = _ros_depth(ros_env, folder, tmp_path / "after")
    assert abs(float(np.nanmedian(depth)) / s2r_median - 1) < 0.01
    assert meta["frame_id"] == "d435_left_optical"
    # configured alike (stereo_image_proc.yaml): the same rectified images and the same disparities, bit for bit
    np.testing.assert_array_equal(np.load(tmp_path / "after" / "rect_left.npy"), result.rect_left)
    np.testing.assert_array_equal(np.load(tmp_path / "after" / "rect_right.npy"), result.rect_right)
    np.testing.assert_array_equal(disparity[result.valid], result.disparity[result.valid])
    assert not (disparity[~result.valid] > 0.5).any()
    # the same camera_info without the marker: image_proc passes the raw images through
    stripped = tmp_path / "stripped"
    stripped.mkdir()
    for name in ("left.yaml", "right.yaml", "stereo_image_proc.yaml"):
        text = (folder / name).read_text()
        (stripped / name).write_text(text.replace(", 1.0e-20]", ", 0.0]"))
    assert "1.0e-20" not in (stripped / "left.yaml").read_text().split("# s2r")[0]
    _, before, _ = _ros_depth(ros_env, stripped, tmp_path / "before")
    assert abs(float(np.nanmedian(before)) / s2r_median - 1) > 0.05


def test_stereo_image_proc_on_a_real_middlebury_pair(ros_env: dict[str, str], tmp_path: Path) -> None:
    """Middlebury cones (already rectified: zero distortion, R = I, P = K, so ROS passes it through and s2r's
    identity maps copy it): configured alike, the disparities are bit-identical."""
    folder = shared_data("middlebury", "cones")
    left, right = (cv2.imread(str(folder / name), cv2.IMREAD_GRAYSCALE) for name in ("im2.png", "im6.png"))
    height, width = left.shape
    rig = make_rig(name="cones", width=width, height=height, hfov_rad=1.0, baseline_m=0.16)
    profile = StereoProfile.model_validate({**rig.model_dump(), "matcher": MatcherSettings.model_validate(
        {**rig.matcher.model_dump(), "num_disparities": 64, "speckle_range": 2, "block_size": 5}).model_dump()})
    ros = _export(profile, tmp_path)
    cv2.imwrite(str(tmp_path / "left.png"), left)
    cv2.imwrite(str(tmp_path / "right.png"), right)
    result = StereoPipeline(profile, preset="profile", postprocess=()).compute(left, right)
    disparity, _, _ = _ros_depth(ros_env, ros, tmp_path / "ros_out")
    np.testing.assert_array_equal(np.load(tmp_path / "ros_out" / "rect_left.npy"), left)
    np.testing.assert_array_equal(disparity[result.valid], result.disparity[result.valid])
    assert result.valid.mean() > 0.5 and not (disparity[~result.valid] > 0.5).any()


def test_rosbag_written_bag_calibrates(ros_env: dict[str, str], tmp_path: Path) -> None:
    truth = make_rig(name="truth", distortion=(-0.12, 0.05, 0.0, 0.0, 0.0), rotation_deg=(0.3, -0.5, 0.2),
                     cx=322.0, cy=238.5)
    write_stereo_set(truth, tmp_path / "set", views=12, seed=7)
    bag = tmp_path / "cal.bag"
    count = run_helper(ros_env, "bag", str(bag), str(tmp_path / "set" / "left" / "*.png"),
                       str(tmp_path / "set" / "right" / "*.png"), "/stereo/left/image_raw", "/stereo/right/image_raw")
    assert int(count) == 12
    out = tmp_path / "rig.yaml"
    assert main(["calibrate", "--bag", str(bag), "--left-topic", "/stereo/left/image_raw", "--right-topic",
                 "/stereo/right/image_raw", "--pattern", "9x6", "--square", "0.025", "-o", str(out),
                 "--jobs", "1"]) == 0
    p = load_profile_file(out)
    assert abs(p.left.fx_px - truth.left.fx_px) < 0.01 * truth.left.fx_px
    assert abs(p.baseline_m - truth.baseline_m) < 0.01 * truth.baseline_m
