"""Sim profiles from URDF / xacro / SDF with hand-computed geometry."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main as cli_main
from s2r.errors import SourceError
from s2r.sources import lint_description, load_description, load_description_profile
from s2r.sources.kinematics import KinematicTree
from s2r.sources.loader import optical_pose
from tests.conftest import CAMERA_MACRO_XACRO
from tests.sources.rigs import FIXED_URDF, SEED_URDF, XBOT_SDF, joint, sensor, two_camera_urdf, urdf, write

S30, C30 = 0.5, math.sqrt(3) / 2


def test_xbot_profile_done_when_figures() -> None:
    p = load_description_profile(XBOT_SDF)
    assert p.left.fx_px == pytest.approx(320.255, abs=5e-4) and p.left.fy_px == p.left.fx_px
    assert (p.left.cx_px, p.left.cy_px) == (320.5, 240.5)
    assert p.baseline_m == pytest.approx(0.06, abs=1e-12)
    assert pytest.approx([-0.06, 0.0, 0.0], abs=1e-12) == p.T
    assert np.allclose(p.R, np.eye(3))
    assert p.provenance.origin == "sim" and p.provenance.convention == "gazebo-classic"
    sim = p.simulation
    assert sim is not None and (sim.clip_near_m, sim.clip_far_m, sim.update_rate_hz) == (0.05, 50.0, 30.0)
    assert p.left.frame_id == "stereo_camera_optical_frame"


def test_seed_matcher_and_working_range() -> None:
    p = load_description_profile(FIXED_URDF, name="gazebo_dual_camera")
    m = p.matcher
    assert (m.num_disparities, m.block_size, m.p1, m.p2) == (112, 5, 600, 2400)
    assert (m.disp12_max_diff, m.uniqueness_ratio, m.speckle_window_size, m.speckle_range) == (1, 10, 100, 32)
    # fx B / 111 px = 554.38 * 0.1 / 111 = 0.4994 m -> 0.50 m; 112 disparities are what that depth needs
    assert m.min_depth_m == 0.5
    assert p.num_disparities_for() == 112
    assert pytest.approx([-0.1, 0, 0], abs=1e-12) == p.T
    assert p.provenance.sources[0].sha256 and p.name == "gazebo_dual_camera"


def test_seed_rig_as_written_has_its_right_camera_behind(caplog: pytest.LogCaptureFixture) -> None:
    # joint xyz (-0.1, 0, 0) in the left link: 10 cm behind along the viewing axis -> optical (0, 0, -0.1).
    # One rule with lint: refused (naming lint's code and the corrected joint), written only when asked, loudly.
    with pytest.raises(SourceError, match=r"\[baseline-axis\].*10.0 cm behind.*xyz=\"0 -0.1 0\"") as info:
        load_description_profile(SEED_URDF)
    assert f"{SEED_URDF}: line " in str(info.value)
    with caplog.at_level(logging.WARNING, logger="s2r"):
        p = load_description_profile(SEED_URDF, allow_bad_baseline=True)
    assert pytest.approx([0.0, 0.0, 0.1], abs=1e-12) == p.T
    assert "ERROR [baseline-axis]" in caplog.text


@pytest.mark.parametrize(("convention", "cx"), [("gazebo-classic", 320.5), ("gz-sim", 320.0), ("exact", 319.5)])
def test_convention_recorded(convention: str, cx: float) -> None:
    p = load_description_profile(FIXED_URDF, convention=convention)
    assert p.provenance.convention == convention and p.left.cx_px == cx


def test_cameras_pitched_down_30_degrees(tmp_path: Path) -> None:
    """A bar pitched down 30 deg: extrinsics unchanged, optical axes point 30 deg below the horizon."""
    text = urdf(["base", "bar", "left_link", "right_link"],
                [joint("pitch", "base", "bar", "0 0 1", f"0 {math.radians(30)} 0"),
                 joint("l", "bar", "left_link", "0 0.05 0"), joint("r", "bar", "right_link", "0 -0.05 0")],
                {"left_link": sensor("left_cam"), "right_link": sensor("right_cam")})
    path = write(tmp_path, "pitched.urdf", text)
    p = load_description_profile(path)
    assert pytest.approx([-0.1, 0, 0], abs=1e-12) == p.T and np.allclose(p.R, np.eye(3), atol=1e-12)
    description = load_description(path)
    T_root_link, _ = KinematicTree(description).pose_in_root("left_link")
    z_axis = (T_root_link @ optical_pose(description.cameras[0]))[:3, 2]
    assert z_axis == pytest.approx([C30, 0.0, -S30], abs=1e-12)


def test_right_camera_alone_pitched_down_30_degrees(tmp_path: Path) -> None:
    # link pitch +30 deg about y = optical rotation -30 deg about x; OpenCV R (right from left) = Rx(+30 deg)
    path = write(tmp_path, "p.urdf", two_camera_urdf(right_rpy=f"0 {math.radians(30)} 0"))
    p = load_description_profile(path)
    assert pytest.approx(np.array([[1, 0, 0], [0, C30, -S30], [0, S30, C30]]), abs=1e-12) == p.R
    assert pytest.approx(-p.R @ np.array([0.1, 0, 0]), abs=1e-12) == p.T


def test_rig_three_joints_deep_through_a_common_parent(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """base -> torso (yaw 0.3) -> head (revolute neck, off the path) -> bar -> left / head -> mount -> right."""
    text = urdf(["base", "torso", "head", "bar", "mount", "left_link", "right_link"],
                [joint("torso", "base", "torso", "0 0 0.5", "0 0 0.3"),
                 joint("neck", "torso", "head", "0.1 0 0.3", kind="revolute"),
                 joint("bar", "head", "bar", "0.05 0 0.02"), joint("left", "bar", "left_link", "0 0.06 0"),
                 joint("mount", "head", "mount", "0.05 -0.03 0.02"),
                 joint("right", "mount", "right_link", "0 -0.09 0")],
                {"left_link": sensor("left_cam"), "right_link": sensor("right_cam")})
    with caplog.at_level(logging.WARNING, logger="s2r"):
        p = load_description_profile(write(tmp_path, "robot.urdf", text))
    # left at head (0.05, 0.06, 0.02), right at head (0.05, -0.12, 0.02): 0.18 m along -y -> T = (-0.18, 0, 0)
    assert pytest.approx([-0.18, 0, 0], abs=1e-12) == p.T
    assert "neck" not in caplog.text  # the revolute neck is above the common parent


def test_movable_joint_on_the_path_warns(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    text = two_camera_urdf().replace('type="fixed"', 'type="revolute"')
    with caplog.at_level(logging.WARNING, logger="s2r"):
        p = load_description_profile(write(tmp_path, "m.urdf", text))
    assert pytest.approx([-0.1, 0, 0], abs=1e-12) == p.T
    assert "'left_to_right' (revolute)" in caplog.text and "position 0" in caplog.text


def test_optical_links_without_a_pose_rotation_render_along_the_link_x(tmp_path: Path) -> None:
    """Sensors on *_optical links with no <pose> rotation: Gazebo renders along the link's +x (= the robot's -y
    for the left link here), whatever the name says, so both cameras look along the line joining them."""
    rpy = f"{-math.pi / 2} 0 {-math.pi / 2}"
    text = urdf(["base", "left_optical", "right_optical"],
                [joint("l", "base", "left_optical", "0 0.05 0", rpy), joint("r", "base", "right_optical", "0 -0.05 0",
                                                                             rpy)],
                {"left_optical": sensor("left_cam"), "right_optical": sensor("right_cam")})
    path = write(tmp_path, "optical.urdf", text)
    with pytest.raises(SourceError, match=r"\[baseline-axis\] baseline along the optical axis: the right camera is "
                       r"10.0 cm in front of"):
        load_description_profile(path)
    assert [f.code for f in lint_description(path) if f.severity == "error"] == ["baseline-axis"]
    assert any(f.code == "optical-link" for f in lint_description(path))


def test_sensor_and_camera_poses_are_applied(tmp_path: Path) -> None:
    # both on one link; right sensor pose (0, -0.07, 0) plus yaw 0 -> T = (-0.07, 0, 0)
    text = urdf(["body"], [], {"body": sensor("left_cam", pose="0 0 0 0 0 0") + sensor("right_cam",
                                                                                       pose="0.2 -0.07 0 0 0 0")})
    # the 0.2 m forward offset puts the right camera ahead: T = -(0.07 right, 0, 0.2 forward) in optical
    p = load_description_profile(write(tmp_path, "poses.urdf", text), allow_bad_baseline=True)
    assert pytest.approx([-0.07, 0, -0.2], abs=1e-12) == p.T


def test_xacro_macros_with_arguments_and_find(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    pkg = tmp_path / "ws" / "src" / "my_cams"
    write(pkg, "package.xml", "<package><name>my_cams</name></package>\n")
    write(pkg, "urdf/camera.xacro", CAMERA_MACRO_XACRO)
    main = write(tmp_path, "rig.urdf.xacro", """<?xml version="1.0"?>
<robot name="rig" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="baseline" default="0.1"/>
  <xacro:property name="b" value="$(arg baseline)"/>
  <xacro:include filename="$(find my_cams)/urdf/camera.xacro"/>
  <link name="base"/>
  <xacro:cam side="left" y="${b / 2}"/>
  <xacro:cam side="right" y="${-b / 2}"/>
</robot>
""")
    p = load_description_profile(main, xacro_args={"baseline": "0.24"}, package_paths=[tmp_path / "ws"])
    assert pytest.approx([-0.24, 0, 0], abs=1e-12) == p.T
    assert "baseline:=0.24" in p.provenance.notes
    out = tmp_path / "rig.yaml"
    argv = ["profile", "from-urdf", str(main), "baseline:=0.3", "--package-path", str(tmp_path / "ws"), "-o", str(out)]
    assert cli_main(argv) == 0 and "T = (-0.3000, +0.0000, +0.0000)" in capsys.readouterr().out
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws" / "src"))
    assert pytest.approx([-0.1, 0, 0], abs=1e-12) == load_description_profile(main).T


def test_sdf_nested_model_and_world(tmp_path: Path) -> None:
    cams = (f'<link name="cam"><pose>0.1 0 0.2 0 0 0</pose>{sensor("left_cam")}'
            f'{sensor("right_cam", pose="0 -0.05 0 0 0 0")}</link>')
    text = (f'<sdf version="1.7"><world name="w"><model name="robot"><pose>1 2 0 0 0 1.0</pose>'
            f'<link name="base"/><model name="head"><pose>0 0 1 0 0 0</pose>{cams}</model></model></world></sdf>')
    p = load_description_profile(write(tmp_path, "world.world", text))
    assert pytest.approx([-0.05, 0, 0], abs=1e-12) == p.T
    assert "robot::head::cam" in p.left.frame_id


def test_multicamera_distortion_is_converted(tmp_path: Path) -> None:
    dist = "<distortion><k1>-0.2</k1><k2>0.05</k2><k3>0</k3><p1>0</p1><p2>0</p2><center>0.5 0.5</center></distortion>"
    text = XBOT_SDF.read_text().replace("<width>640</width>", "<width>480</width>").replace(
        "<clip>", dist + "<clip>")
    p = load_description_profile(write(tmp_path, "d.sdf", text))
    a = p.left.fx_px / 480.0  # square 480x480: exact, k1 a^2 and k2 a^4
    assert pytest.approx([-0.2 * a**2, 0.05 * a**4, 0, 0, 0], abs=1e-12) == p.left.D


def test_noise_goes_into_simulation_settings(tmp_path: Path) -> None:
    noise = "<noise><type>gaussian</type><mean>0</mean><stddev>0.007</stddev></noise>"
    text = two_camera_urdf(left_sensor=sensor("left_cam", extra=noise), right_sensor=sensor("right_cam", extra=noise))
    p = load_description_profile(write(tmp_path, "n.urdf", text))
    assert p.simulation is not None and p.simulation.noise_stddev == 0.007
