"""ROS 1 bags written by ``s2r depth ... --to ros1``, read by Debian's own rosbag (system Python) and played by
``rosbag play`` to rospy subscribers on a loopback roscore: every topic and type, the input stamps, one frame_id,
/tf_static, and depth equal, bit for bit, to ``--to files`` on the same frames. Run with ``make test-ros``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from s2r.cli import main
from tests.depth.stream_inputs import (
    FRAME_ID,
    LEFT_TOPIC,
    RECT_FRAME_ID,
    RIGHT_TOPIC,
    STAMPS_NS,
    known_frames,
    known_rig,
    write_folder,
    write_profile,
    write_ros2_bag,
)
from tests.ros.conftest import run_helper

pytestmark = pytest.mark.ros

TYPES = {"/stereo/left/image_rect": "sensor_msgs/Image", "/stereo/left/camera_info": "sensor_msgs/CameraInfo",
         "/stereo/right/camera_info": "sensor_msgs/CameraInfo", "/stereo/disparity": "stereo_msgs/DisparityImage",
         "/stereo/depth/image_rect": "sensor_msgs/Image", "/stereo/depth/camera_info": "sensor_msgs/CameraInfo",
         "/stereo/points2": "sensor_msgs/PointCloud2", "/tf_static": "tf2_msgs/TFMessage"}


@pytest.fixture(scope="module")
def outputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    frames = known_frames(rig)
    root = tmp_path_factory.mktemp("ros_stream")
    names = write_folder(frames, root / "rec")
    write_ros2_bag(frames, root / "in_bag")
    path = write_profile(profile, root / "profile.yaml")
    assert main(["-q", "depth", str(path), str(root / "rec"), "-o", str(root / "files")]) == 0
    assert main(["-q", "depth", str(path), "--bag", str(root / "in_bag"), "--left-topic", LEFT_TOPIC,
                 "--right-topic", RIGHT_TOPIC, "-o", str(root / "out.bag"), "--to", "ros1", "--points"]) == 0
    return {"root": root, "names": names, "profile": profile}


def _check(out: Path, outputs: dict[str, Any], *, played: bool) -> None:
    summary = json.loads((out / "summary.json").read_text())
    assert summary["depth_stamps"] == list(STAMPS_NS)
    assert set(summary["frame_ids"]) == {RECT_FRAME_ID}
    (parent, child, x, y, z), rect = summary["tf"]
    assert (parent, child) == (FRAME_ID, "raycast_right_optical")
    assert rect == [FRAME_ID, RECT_FRAME_ID, 0.0, 0.0, 0.0]  # the rectification turns, never moves
    profile = outputs["profile"]
    np.testing.assert_allclose([x, y, z], -profile.R.T @ profile.T, atol=1e-12)
    if played:  # tf2_ros's own listener and lookup: the depth's frame is placed, turned by R1^T
        from scipy.spatial.transform import Rotation

        from s2r.depth.pipeline import StereoPipeline

        assert summary["depth_frame_known_to_tf"]
        parent, *quat = summary["tf_lookups"][RECT_FRAME_ID]
        R1 = StereoPipeline(profile).rectification.R1
        assert parent == FRAME_ID
        np.testing.assert_allclose(Rotation.from_quat(quat).as_matrix(), R1.T, atol=1e-9)
    for k, name in enumerate(outputs["names"]):
        from_files = np.load(outputs["root"] / "files" / "depth" / f"{name}.npy")
        assert np.load(out / f"depth_{k}.npy").tobytes() == from_files.tobytes()
        disparity = np.load(out / f"disparity_{k}.npy")
        f, baseline, low, encoding = summary["disparity"][k]
        valid = disparity >= low
        assert encoding == "32FC1"
        np.testing.assert_array_equal(valid, np.isfinite(from_files))
        np.testing.assert_allclose(f * baseline / disparity[valid], from_files[valid], rtol=1e-6)
    expected = {t: 3 for t in TYPES if t != "/tf_static"} | {"/tf_static": 1}
    if played:
        expected = {t: expected[t] for t in ("/stereo/depth/image_rect", "/stereo/disparity", "/tf_static")}
    assert summary["topics"] == expected


def test_debian_rosbag_reads_the_bag(ros_env: dict[str, str], outputs: dict[str, Any], tmp_path: Path) -> None:
    run_helper(ros_env, "readbag", str(outputs["root"] / "out.bag"), str(tmp_path))
    assert json.loads((tmp_path / "types.json").read_text()) == TYPES
    _check(tmp_path, outputs, played=False)


def test_rosbag_play_reaches_a_subscriber(ros_env: dict[str, str], outputs: dict[str, Any], tmp_path: Path) -> None:
    run_helper(ros_env, "play", str(outputs["root"] / "out.bag"), str(tmp_path), "/stereo", timeout=180)
    _check(tmp_path, outputs, played=True)
