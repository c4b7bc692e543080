"""depth-quality from a ROS 2 bag (mono8 left + 16UC1 depth written with rosbags' writer) and bad input."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from s2r.cli import main
from s2r.registry import load_profile
from tests.quality.synth_device import render_frame, write_recording

pytest.importorskip("rosbags")
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

PROFILE = "realsense_d435_848x480"
IMAGE = "sensor_msgs/msg/Image"


def _msg(ts: Any, image: np.ndarray, stamp_ns: int, encoding: str) -> Any:
    Image, Header, Time = ts.types[IMAGE], ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    header = Header(stamp=Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id="camera_infra1")
    h, w = image.shape
    data = np.ascontiguousarray(image).view(np.uint8).reshape(-1)
    return Image(header=header, height=h, width=w, encoding=encoding, is_bigendian=0,
                 step=w * image.itemsize, data=data)


def test_device_depth_from_a_bag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    profile = load_profile(PROFILE)
    rng = np.random.default_rng(3)
    frames = [render_frame(profile.left.K, profile.image_size, (9, 6), 0.08, d, 15, 5, bias=0.01, rel_noise=0.005,
                           hole_rate=0.1, rng=rng) for d in (0.8, 1.4)]
    ts = get_typestore(Stores.ROS2_HUMBLE)
    bag = tmp_path / "rec"
    with Writer(bag, version=9) as writer:
        left = writer.add_connection("/camera/infra1/image_rect_raw", IMAGE, typestore=ts)
        depth = writer.add_connection("/camera/depth/image_rect_raw", IMAGE, typestore=ts)
        for i, f in enumerate(frames):
            t = 10**9 + i * 10**8
            writer.write(left, t, ts.serialize_cdr(_msg(ts, f.left, t, "mono8"), IMAGE))
            writer.write(depth, t + 10**6, ts.serialize_cdr(_msg(ts, f.depth_mm, t + 10**6, "16UC1"), IMAGE))
    code = main(["depth-quality", PROFILE, "--bag", str(bag), "--left-topic", "/camera/infra1/image_rect_raw",
                 "--depth-topic", "/camera/depth/image_rect_raw", "--pattern", "9x6", "--square", "0.08", "--json"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["frames"]) == 2
    for f in data["frames"]:
        assert f["z_accuracy_pct"] == pytest.approx(1.0, abs=0.1)
        assert f["fill_rate_pct"] == pytest.approx(90.0, abs=1.0)


def _err(capsys: pytest.CaptureFixture[str], args: list[str]) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


def test_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    profile = load_profile(PROFILE)
    rng = np.random.default_rng(4)
    f = render_frame(profile.left.K, profile.image_size, (9, 6), 0.08, 1.0, 0, 0, bias=0, rel_noise=0, hole_rate=0,
                     rng=rng)
    left, depth = write_recording(tmp_path / "rec", [f])
    base = ["depth-quality", PROFILE, "--left", str(left)]
    assert "exactly one depth source" in _err(capsys, [*base, "--pattern", "9x6", "--square", "0.08"])
    assert "--pattern" in _err(capsys, [*base, "--depth", str(depth)])
    assert "--square" in _err(capsys, [*base, "--depth", str(depth), "--pattern", "9x6", "--square", "-1"])
    assert "no such folder" in _err(capsys, [*base, "--depth", str(tmp_path / "nope"), "--pattern", "9x6",
                                             "--square", "0.08"])
    (tmp_path / "grey8").mkdir()
    (tmp_path / "grey8" / "000.png").write_bytes((left / "000.png").read_bytes())
    err = _err(capsys, [*base, "--depth", str(tmp_path / "grey8"), "--pattern", "9x6", "--square", "0.08"])
    assert "000.png" in err and "uint16" in err
    err = _err(capsys, [*base, "--depth", str(depth), "--pattern", "7x4", "--square", "0.08"])
    assert "no 7x4 chessboard" in err
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "depth_quality.html").write_text("keep")
    err = _err(capsys, [*base, "--depth", str(depth), "--pattern", "9x6", "--square", "0.08", "--report",
                        str(tmp_path / "rep")])
    assert "--force" in err and (tmp_path / "rep" / "depth_quality.html").read_text() == "keep"
