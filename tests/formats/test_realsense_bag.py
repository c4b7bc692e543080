"""The ROS 1 .bag layout of librealsense < 2.56, constructed here per its ros_writer.cpp / ros_file_format.h
(pyrealsense2 2.56+ no longer writes it): topics, message types, the writer's rot2quat and header seq."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from s2r.formats.realsense.recording import load_realsense_recording
from s2r.recordings.realsense import RealSenseFrames
from tests.formats.realsense_writer import rotation

rosbag1 = pytest.importorskip("rosbags.rosbag1")
typesys = pytest.importorskip("rosbags.typesys")


def rot2quat(r: list[float]) -> tuple[float, float, float, float]:
    """librealsense's rot2quat, line for line: ``m = (float(&)[3][3]) r`` reads the column-major array row-major,
    then ``q.w = -q.w``. Returns (x, y, z, w)."""
    m = [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]]
    tr = [m[0][0] + m[1][1] + m[2][2], m[0][0] - m[1][1] - m[2][2], -m[0][0] + m[1][1] - m[2][2],
          -m[0][0] - m[1][1] + m[2][2]]
    assert tr[0] >= max(tr[1:])  # a small rotation: the first branch
    s = 2 * math.sqrt(tr[0] + 1)
    w, x, y, z = s / 4, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s
    return x, y, z, -w


def _write_bag(path: Path, R: np.ndarray, t: tuple[float, float, float], frames: list[tuple[np.ndarray, ...]]) -> None:
    store = typesys.get_typestore(typesys.Stores.ROS1_NOETIC)
    T = store.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    with rosbag1.Writer(path) as bag:
        def put(topic: str, msgtype: str, msg: object, stamp: int = 0) -> None:
            conns = {c.topic: c for c in bag.connections}
            conn = conns.get(topic) or bag.add_connection(topic, msgtype, typestore=store)
            bag.write(conn, stamp, store.serialize_ros1(msg, msgtype))

        put("/file_version", "std_msgs/msg/UInt32", T["std_msgs/msg/UInt32"](data=3))
        for key, value in (("Name", "Intel RealSense D415"), ("Serial Number", "987654321"),
                           ("Firmware Version", "5.12.7.100")):
            put("/device_0/info", "diagnostic_msgs/msg/KeyValue", T["diagnostic_msgs/msg/KeyValue"](key=key,
                                                                                                   value=value))
        put("/device_0/sensor_0/option/Depth_Units/value", "std_msgs/msg/Float32",
            T["std_msgs/msg/Float32"](data=0.001))
        cams = {1: ([50.5, 0, 32.25, 0, 51.0, 24.5, 0, 0, 1], [0.01, -0.02, 0.0, 0.001, 0.0]),
                2: ([52.0, 0, 30.75, 0, 52.5, 23.0, 0, 0, 1], [-0.03, 0.01, 0.002, 0.0, 0.004])}
        rot = [float(v) for v in R.T.ravel()]  # rs2_extrinsics: column-major
        for index, (k, d) in cams.items():
            prefix = f"/device_0/sensor_0/Infrared_{index}"
            info = T["sensor_msgs/msg/CameraInfo"](
                header=Header(seq=0, stamp=Time(sec=0, nanosec=0), frame_id=""), height=48, width=64,
                distortion_model="Brown Conrady", D=np.array(d), K=np.array(k, float), R=np.zeros(9), P=np.zeros(12),
                binning_x=0, binning_y=0, roi=T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0,
                                                                                  width=0, do_rectify=False))
            put(f"{prefix}/info/camera_info", "sensor_msgs/msg/CameraInfo", info)
            x, y, z, w = rot2quat(rot) if index == 2 else (0.0, 0.0, 0.0, 1.0)
            tr = t if index == 2 else (0.0, 0.0, 0.0)
            put(f"{prefix}/tf/0", "geometry_msgs/msg/Transform", T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=tr[0], y=tr[1], z=tr[2]),
                rotation=T["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w)))
        for n, pair in enumerate(frames):
            for index, image in ((1, pair[0]), (2, pair[1])):
                stamp = 1_000_000_000 + n * 33_333_333 + (4_000_000 if index == 2 else 0)
                msg = T["sensor_msgs/msg/Image"](header=Header(seq=n + 100, stamp=Time(sec=1, nanosec=stamp - 10**9),
                                                               frame_id=""), height=48, width=64, encoding="mono8",
                                                 is_bigendian=0, step=64, data=image.ravel())
                put(f"/device_0/sensor_0/Infrared_{index}/image/data", "sensor_msgs/msg/Image", msg, stamp)


def test_ros1_layout_profile_and_frames(tmp_path: Path) -> None:
    R, t = rotation((0.2, -1.0, 0.4), 0.015), (-0.055, 0.0004, -0.0012)
    rng = np.random.default_rng(5)
    frames = [tuple(rng.integers(0, 256, (48, 64), dtype=np.uint8) for _ in range(2)) for _ in range(3)]
    path = tmp_path / "old.bag"
    _write_bag(path, R, t, frames)
    rig = load_realsense_recording(path)
    assert (rig.left.fx_px, rig.left.cx_px, rig.right.fy_px, rig.right.cy_px) == (50.5, 32.25, 52.5, 23.0)
    assert list(rig.right.distortion.coefficients) == [-0.03, 0.01, 0.002, 0.0, 0.004]
    np.testing.assert_allclose(rig.R, R, atol=1e-12)
    np.testing.assert_allclose(rig.T, t, atol=1e-15)
    notes = rig.provenance.notes
    assert "S/N 987654321" in notes and "5.12.7.100" in notes and "depth units 0.001 m" in notes
    source = RealSenseFrames(path)
    got = list(source.frames())
    assert len(got) == 3 and source.paired_by == {"frame number": 3}
    for frame, (left, right) in zip(got, frames, strict=True):
        np.testing.assert_array_equal(frame.left, left)
        np.testing.assert_array_equal(frame.right, right)
