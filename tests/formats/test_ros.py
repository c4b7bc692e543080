"""ROS camera_info: the parsers' YAML pair round trip, hand-computed P matrices, rostopic echo import."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from s2r.errors import FormatError, OutputExistsError
from s2r.formats.ros import camera_info_to_yaml, dump_ros_pair, ros_pair_from_profile
from s2r.formats.ros_read import load_ros_pair, read_camera_info
from s2r.formats.s2r_yaml import dump_profile, load_profile_file
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.formats.rigs import assert_same_rig, distorted_rotated_rig, with_distortion

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize(
    "rig",
    [
        distorted_rotated_rig(),
        make_rig(name="wide", width=848, height=480, hfov_rad=1.5, baseline_m=0.05, rotation_deg=(-1.0, 2.0, 0.5)),
    ],
)
def test_s2r_to_ros_pair_to_s2r_round_trip(rig: StereoProfile, tmp_path: Path) -> None:
    src = dump_profile(rig, tmp_path / "rig.yaml")
    left, right = dump_ros_pair(load_profile_file(src), tmp_path / "ros")
    assert (left.name, right.name) == ("left.yaml", "right.yaml")
    back = load_ros_pair(left, right)
    dump_profile(back, tmp_path / "back.yaml")
    assert_same_rig(load_profile_file(tmp_path / "back.yaml"), rig)
    assert back.provenance.origin == "real" and back.provenance.method == "imported from ROS camera_info"
    assert [s.path for s in back.provenance.sources] == [str(left), str(right)]
    assert all(len(s.sha256) == 64 for s in back.provenance.sources)


def test_equidistant_and_rational_models_round_trip(tmp_path: Path) -> None:
    base = make_rig(rotation_deg=(0.2, 0.1, -0.3))
    for model, coeffs in (("equidistant", (0.05, -0.01, 0.002, -0.0005)),
                          ("rational_polynomial", (-0.1, 0.03, 0.001, 0.0005, 0.002, 0.01, -0.003, 0.001))):
        rig = with_distortion(base, model, coeffs)
        left, right = dump_ros_pair(rig, tmp_path / model)
        assert_same_rig(load_ros_pair(left, right), rig)
        assert yaml.safe_load(left.read_text())["distortion_model"] == model


def test_hand_computed_projection_matrices() -> None:
    """Identical ideal cameras side by side: P1 = [K | 0], P2 = [K | (-fx B, 0, 0)], R1 = R2 = I."""
    rig = make_rig(baseline_m=0.1)
    fx, cx, cy = rig.left.fx_px, rig.left.cx_px, rig.left.cy_px
    left, right = ros_pair_from_profile(rig)
    np.testing.assert_allclose(left.P, [[fx, 0, cx, 0], [0, fx, cy, 0], [0, 0, 1, 0]], atol=1e-9)
    np.testing.assert_allclose(right.P, [[fx, 0, cx, -fx * 0.1], [0, fx, cy, 0], [0, 0, 1, 0]], atol=1e-9)
    np.testing.assert_allclose(left.R, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(right.R, np.eye(3), atol=1e-12)
    assert right.P[0, 3] == pytest.approx(-55.43827128226441, abs=1e-9)  # -554.3827 px * 0.1 m


def test_right_p3_is_minus_fx_prime_times_baseline_for_a_rotated_rig() -> None:
    rig = make_rig(baseline_m=0.12, rotation_deg=(0.5, -1.0, 0.3), distortion=(-0.1, 0.02, 0, 0, 0))
    left, right = ros_pair_from_profile(rig)
    fx_rect = right.P[0, 0]
    assert left.P[0, 3] == 0.0
    assert right.P[0, 3] == pytest.approx(-fx_rect * 0.12, rel=1e-12)
    assert left.P[0, 0] == right.P[0, 0] and left.P[1, 2] == right.P[1, 2]  # one rectified camera matrix


def test_written_yaml_has_the_parsers_layout(tmp_path: Path) -> None:
    left, _ = ros_pair_from_profile(make_rig(name="cam"))
    data = yaml.safe_load(camera_info_to_yaml(left))
    assert list(data) == ["image_width", "image_height", "camera_name", "camera_matrix", "distortion_model",
                          "distortion_coefficients", "rectification_matrix", "projection_matrix", "s2r"]
    assert data["camera_matrix"]["rows"] == 3 and data["projection_matrix"]["cols"] == 4
    assert data["s2r"]["convention"] == "exact" and data["s2r"]["matcher"]["algorithm"] == "sgbm"
    assert data["distortion_coefficients"] == {"rows": 1, "cols": 5, "data": [0.0] * 5}
    assert data["camera_name"] == "cam/left"


def test_rostopic_echo_of_the_seed_gazebo_pair() -> None:
    """The seed tutorial's camera_info (K 381.36, cx 320.5): ROS 1 echo for the left, ROS 2 echo for the right."""
    left = read_camera_info(DATA / "gazebo_left_camera_info.txt")
    assert left.width == 640 and left.height == 480 and left.frame_id == "left_camera_optical_frame"
    assert left.K[0, 0] == pytest.approx(381.36246688113556) and left.K[0, 2] == 320.5
    assert left.P.shape == (3, 4) and left.distortion_model == "plumb_bob"
    right = read_camera_info(DATA / "gazebo_right_camera_info_ros2.txt")
    assert right.P[0, 3] == pytest.approx(-38.136246688113556)
    rig = load_ros_pair(DATA / "gazebo_left_camera_info.txt", DATA / "gazebo_right_camera_info_ros2.txt",
                        origin="sim")
    np.testing.assert_allclose(rig.T, [-0.1, 0.0, 0.0], atol=1e-12)  # Tx / fx = -38.136 / 381.36
    np.testing.assert_allclose(rig.R, np.eye(3), atol=1e-15)
    assert rig.provenance.origin == "sim"


def test_read_camera_info_of_the_parsers_yaml(tmp_path: Path) -> None:
    left, _ = dump_ros_pair(make_rig(distortion=(-0.1, 0.01, 0, 0, 0)), tmp_path / "ros")
    info = read_camera_info(left)
    assert info.camera_name == "test_rig/left" and info.image_size == (640, 480)
    assert info.K.shape == (3, 3) and info.R.shape == (3, 3) and info.P.shape == (3, 4)
    np.testing.assert_array_equal(info.D, [-0.1, 0.01, 0, 0, 0])


def test_dump_refuses_to_overwrite(tmp_path: Path) -> None:
    left, _ = dump_ros_pair(make_rig(), tmp_path / "ros")
    before = left.read_text()
    with pytest.raises(OutputExistsError, match=r"left\.yaml"):
        dump_ros_pair(make_rig(baseline_m=0.3), tmp_path / "ros")
    assert left.read_text() == before
    dump_ros_pair(make_rig(baseline_m=0.3), tmp_path / "ros", force=True)
    assert load_ros_pair(tmp_path / "ros" / "left.yaml", tmp_path / "ros" / "right.yaml").baseline_m == \
        pytest.approx(0.3)


def test_pair_with_different_image_sizes_is_refused(tmp_path: Path) -> None:
    a, _ = dump_ros_pair(make_rig(), tmp_path / "a")
    _, b = dump_ros_pair(make_rig(width=1280, height=960), tmp_path / "b")
    with pytest.raises(FormatError, match=r"image size 1280x960 differs from 640x480") as info:
        load_ros_pair(a, b)
    assert str(b) in str(info.value) and "image_width" in str(info.value)


def test_pair_without_baseline_names_tx(tmp_path: Path) -> None:
    left, _ = dump_ros_pair(make_rig(), tmp_path / "ros")
    with pytest.raises(FormatError, match=r"projection_matrix: P\[0,3\] \(Tx\) is 0"):
        load_ros_pair(left, left)


def test_vertical_rig_puts_the_baseline_in_ty_and_round_trips(tmp_path: Path) -> None:
    data = make_rig(distortion=(-0.1, 0.01, 0.0, 0.0, 0.0)).model_dump()
    data["extrinsics"]["translation_m"] = (0.002, -0.1, 0.001)  # right camera below the left one
    rig = StereoProfile.model_validate(data)
    left, right = dump_ros_pair(rig, tmp_path / "ros")
    info = read_camera_info(right)
    assert info.P[0, 3] == 0.0
    assert info.P[1, 3] == pytest.approx(-info.P[1, 1] * rig.baseline_m, rel=1e-12)
    assert_same_rig(load_ros_pair(left, right), rig)


def test_swapped_pair_warns(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    left, right = dump_ros_pair(make_rig(), tmp_path / "ros")
    with caplog.at_level("WARNING", logger="s2r"):
        swapped = load_ros_pair(right, left)
    assert swapped.T[0] == pytest.approx(0.1)
    assert "second camera sits to the LEFT of the first" in caplog.text
