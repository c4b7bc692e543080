"""camera_info that ROS's own nodes use as intended (checked without ROS here; tests/ros runs the nodes).

- image_proc passes image_raw through when every coefficient of D is 0 (even with a rectifying R): a rotated,
  zero-distortion pair exports its last coefficient as ZERO_DISTORTION_MARKER, which changes no pixel of
  OpenCV's rectification maps and reads back as 0.
- One frame_id for the pair (stereo_image_proc asserts it).
- s2r -> ROS -> s2r keeps the pixel convention, the matcher (num_disparities, depth range) and the frame.
- stereo_image_proc.yaml: the matcher inside stereo_image_proc's ranges, each clamp warned.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from s2r.cli import main
from s2r.errors import FormatError
from s2r.formats.detect import load_any
from s2r.formats.ros import ZERO_DISTORTION_MARKER, dump_ros_pair, ros_pair_from_profile
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import MatcherSettings, StereoProfile
from tests.conftest import make_rig


def _rotated(**matcher: object) -> StereoProfile:
    rig = make_rig(name="rotated", width=320, height=240, rotation_deg=(0.4, -1.5, 0.3))
    update = {"provenance": rig.provenance.model_copy(update={"convention": "gazebo-classic"}),
              "left": rig.left.model_copy(update={"frame_id": "cam_left_optical", "cx_px": 160.5, "cy_px": 120.5}),
              "right": rig.right.model_copy(update={"frame_id": "cam_right_optical", "cx_px": 160.5, "cy_px": 120.5}),
              "matcher": MatcherSettings.model_validate({**rig.matcher.model_dump(), **matcher})}
    return StereoProfile.model_validate({**rig.model_dump(), **{k: v.model_dump() for k, v in update.items()}})


def test_zero_distortion_with_rotation_gets_a_marker_that_moves_no_pixel() -> None:
    left, right = ros_pair_from_profile(_rotated())
    for info in (left, right):
        assert info.D.tolist() == [0.0, 0.0, 0.0, 0.0, ZERO_DISTORTION_MARKER] and info.s2r["zero_distortion"]
        zero = cv2.initUndistortRectifyMap(info.K, np.zeros(5), info.R, info.P, (320, 240), cv2.CV_32FC1)
        marked = cv2.initUndistortRectifyMap(info.K, info.D, info.R, info.P, (320, 240), cv2.CV_32FC1)
        assert all(np.array_equal(a, b) for a, b in zip(zero, marked, strict=True))  # bit-identical maps
    plain, _ = ros_pair_from_profile(make_rig(width=320, height=240))  # R = I, P = K: pass-through is right
    assert not plain.D.any() and "zero_distortion" not in plain.s2r


def test_the_pair_shares_the_left_frame_id() -> None:
    left, right = ros_pair_from_profile(_rotated())
    assert left.frame_id == right.frame_id == "cam_left_optical"


def test_round_trip_keeps_convention_matcher_and_frame(tmp_path: Path) -> None:
    profile = _rotated(num_disparities=48, min_depth_m=0.6, max_depth_m=7.5, speckle_range=32)
    dump_ros_pair(profile, tmp_path / "ros")
    back = load_any([tmp_path / "ros" / "left.yaml", tmp_path / "ros" / "right.yaml"])
    assert back.provenance.convention == "gazebo-classic" and back.left.cx_px == 160.5
    assert back.matcher == profile.matcher and back.matcher.num_disparities == 48
    assert back.left.frame_id == back.right.frame_id == "cam_left_optical"
    assert back.left.distortion.coefficients == (0.0,) * 5  # the marker reads back as 0
    assert back.baseline_m == pytest.approx(profile.baseline_m, abs=1e-12)
    assert np.allclose(back.R, profile.R, atol=1e-12)


def test_s2r_block_with_a_bad_value_is_named(tmp_path: Path) -> None:
    dump_ros_pair(_rotated(), tmp_path / "ros")
    left = tmp_path / "ros" / "left.yaml"
    left.write_text(left.read_text().replace("convention: gazebo-classic", "convention: unreal"))
    with pytest.raises(FormatError, match=r"s2r\.convention: unknown pixel convention .unreal."):
        load_any([left, tmp_path / "ros" / "right.yaml"])


def test_convert_writes_stereo_image_proc_params_clamped_with_warnings(tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "rig.yaml"
    dump_profile(_rotated(block_size=11, speckle_range=40, num_disparities=48), src)
    assert main(["profile", "convert", str(src), "--to", "ros", "-o", str(tmp_path / "ros")]) == 0
    err = capsys.readouterr().err
    params = yaml.safe_load((tmp_path / "ros" / "stereo_image_proc.yaml").read_text())
    assert params["speckle_range"] == 31 and "speckle_range 40 is outside stereo_image_proc's range 0..31" in err
    assert params["P2"] == 3872 and params["P1"] == 8 * 121  # 32 * 1 * 11^2 = 3872 fits; grey images
    assert params["disparity_range"] == 48 and params["correlation_window_size"] == 11
    assert params["stereo_algorithm"] == 1 and params["fullDP"] is False and params["prefilter_cap"] == 63


def test_disparity_range_below_ros_minimum_is_raised_and_said(tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "rig.yaml"
    dump_profile(_rotated(num_disparities=16, block_size=3, speckle_range=4), src)
    assert main(["profile", "convert", str(src), "--to", "ros", "-o", str(tmp_path / "ros")]) == 0
    err = capsys.readouterr().err
    params = yaml.safe_load((tmp_path / "ros" / "stereo_image_proc.yaml").read_text())
    assert params["disparity_range"] == 32 and "disparity_range 16 is outside" in err
    assert params["correlation_window_size"] == 5 and "correlation_window_size 3 is outside" in err
