"""Content-based format detection, load_any, and the registry loading any format from a path."""

from __future__ import annotations

from pathlib import Path

import pytest

import s2r
from s2r.errors import FormatError
from s2r.formats.detect import detect_format, load_any
from s2r.formats.kalibr import dump_kalibr
from s2r.formats.opencv import dump_opencv
from s2r.formats.ros import dump_ros_pair
from s2r.formats.s2r_yaml import dump_profile
from tests.formats.rigs import assert_same_rig, distorted_rotated_rig, with_distortion

DATA = Path(__file__).parent / "data"


@pytest.fixture
def written(tmp_path: Path) -> dict[str, Path]:
    """One file per format, under misleading names (detection must read the content)."""
    rig = distorted_rotated_rig()
    kalibr_rig = with_distortion(rig, "plumb_bob", (-0.12, 0.05, 0.001, -0.002, 0.0))
    left, right = dump_ros_pair(rig, tmp_path / "ros")
    return {
        "s2r": dump_profile(rig, tmp_path / "a.txt"),
        "opencv": dump_opencv(rig, tmp_path / "b.yaml"),
        "opencv_xml": dump_opencv(rig, tmp_path / "c.xml"),
        "kalibr": dump_kalibr(kalibr_rig, tmp_path / "d.yml"),
        "ros_left": left, "ros_right": right, "ros_dir": tmp_path / "ros",
        "realsense": DATA / "rs_enumerate_devices_d435.txt", "echo": DATA / "gazebo_left_camera_info.txt",
    }


def test_detection_reads_content(written: dict[str, Path]) -> None:
    expected = {"s2r": "s2r", "opencv": "opencv", "opencv_xml": "opencv", "kalibr": "kalibr", "ros_left": "ros",
                "ros_dir": "ros", "realsense": "realsense", "echo": "ros"}
    assert {key: detect_format(written[key]) for key in expected} == expected


def test_load_any_reproduces_the_rig_from_every_format(written: dict[str, Path]) -> None:
    rig = distorted_rotated_rig()
    assert load_any(written["s2r"]) == rig
    for source in (written["opencv"], written["opencv_xml"], [written["ros_left"], written["ros_right"]],
                   written["ros_dir"]):
        assert_same_rig(load_any(source), rig)
    assert load_any(written["kalibr"], name="from_kalibr").name == "from_kalibr"
    assert load_any(written["realsense"], resolution=(1280, 720)).image_size == (1280, 720)


def test_load_any_refuses_single_camera_and_mixed_pairs(written: dict[str, Path]) -> None:
    with pytest.raises(FormatError, match="a camera_info file holds one camera"):
        load_any(written["echo"])
    with pytest.raises(FormatError, match=r"two inputs \(ROS camera_info \+ Kalibr camchain\)"):
        load_any([written["ros_left"], written["kalibr"]])
    with pytest.raises(FormatError, match="expected one or two input files, got 3"):
        load_any([written["ros_left"], written["ros_right"], written["kalibr"]])


def test_unrecognised_content_names_the_file(tmp_path: Path) -> None:
    other = tmp_path / "other.yaml"
    other.write_text("foo: 1\nbar: [1, 2]\n")
    with pytest.raises(FormatError, match=r"other\.yaml: unrecognised format \(top-level keys: bar, foo\)"):
        detect_format(other)
    binary = tmp_path / "image.png"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe")
    with pytest.raises(FormatError, match=r"image\.png: cannot read"):
        detect_format(binary)
    with pytest.raises(FormatError, match=r"is a folder without left\.yaml and right\.yaml"):
        detect_format(tmp_path)


def test_registry_loads_any_single_file_format(written: dict[str, Path]) -> None:
    assert_same_rig(s2r.load_profile(written["opencv"]), distorted_rotated_rig())
    assert s2r.load_profile(str(written["kalibr"])).baseline_m == pytest.approx(0.1)
    assert s2r.load_profile(written["ros_dir"]).image_size == (640, 480)
    assert s2r.load_profile("realsense_d435_848x480").provenance.origin == "nominal"


def test_robot_descriptions_point_to_from_urdf(tmp_path: Path) -> None:
    shipped = Path(__file__).resolve().parents[2] / "urdf" / "xbot_u_stereo.sdf"
    renamed = tmp_path / "robot.txt"
    renamed.write_text('<?xml version="1.0"?>\n<robot name="r"><link name="a"/></robot>\n')
    for path in (shipped, renamed):
        with pytest.raises(FormatError, match="robot description") as info:
            detect_format(path)
        assert "s2r profile from-urdf" in str(info.value) and str(path) in str(info.value)
    scene = tmp_path / "scene.xml"
    scene.write_text('<mujoco model="m"><worldbody/></mujoco>\n')
    with pytest.raises(FormatError, match="MuJoCo model") as info:
        detect_format(scene)
    assert "s2r profile from-description" in str(info.value)
