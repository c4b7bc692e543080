"""Hostile ROS bags, written with rosbags' own writer: an Image message whose data do not fill its declared size,
one with an unknown encoding, and a CompressedImage whose PNG header declares 30000x30000 px. Each is one exit-2
line naming the topic's problem, from calibrate and depth-quality, never the internal-error exit 3."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from s2r.cli import main
from tests.hostile.test_image_bombs import png_bomb

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

LEFT, RIGHT = "/cam/left/image_raw", "/cam/right/image_raw"


def _bag(path: Path, make: Any, msgtype: str) -> Path:
    ts = get_typestore(Stores.ROS1_NOETIC)
    Header, Time = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    with Writer(path) as writer:
        conns = {t: writer.add_connection(t, msgtype, typestore=ts) for t in (LEFT, RIGHT)}
        for i in range(2):
            for topic in (LEFT, RIGHT):
                stamp = 10**9 + i * 10**8
                header = Header(seq=i, stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="cam")
                msg = make(ts.types[msgtype], header)
                writer.write(conns[topic], stamp, ts.serialize_ros1(msg, msgtype))
    return path


def _short_data(Image: Any, header: Any) -> Any:
    return Image(header=header, height=100000, width=100000, encoding="mono8", is_bigendian=0, step=100000,
                 data=np.zeros(64, np.uint8))


def _unknown_encoding(Image: Any, header: Any) -> Any:
    return Image(header=header, height=4, width=4, encoding="weird9", is_bigendian=0, step=4,
                 data=np.zeros(16, np.uint8))


def _bomb(tmp: Path) -> Any:
    data = np.frombuffer(png_bomb(tmp / "b.png").read_bytes(), np.uint8)
    return lambda CompressedImage, header: CompressedImage(header=header, format="png", data=data)


@pytest.mark.parametrize("case", ["short", "encoding", "bomb"])
def test_hostile_bag_messages_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    if case == "bomb":
        bag = _bag(tmp_path / "h.bag", _bomb(tmp_path), "sensor_msgs/msg/CompressedImage")
        expected: tuple[str, ...] = ("30000x30000",)
    else:
        bag = _bag(tmp_path / "h.bag", _short_data if case == "short" else _unknown_encoding, "sensor_msgs/msg/Image")
        # with a profile (depth-quality) the one size rule refuses the declared size before decoding
        expected = ("cannot be decoded", "declares 100000x100000 px" if case == "short" else "is 4x4 px but the")
    runs = [["calibrate", "--bag", str(bag), "--left-topic", LEFT, "--right-topic", RIGHT, "--pattern", "9x6",
             "--square", "0.025", "-o", str(tmp_path / "p.yaml")],
            ["depth-quality", "realsense_d435_848x480", "--bag", str(bag), "--left-topic", LEFT, "--right-topic",
             RIGHT, "--pattern", "9x6", "--square", "0.025"]]
    for argv in runs:
        code = main(argv)
        err = capsys.readouterr().err
        assert code == 2, (argv[0], err)
        assert any(e in err for e in expected) and "Traceback" not in err, err
        assert len(err.strip().splitlines()) == 1, err
