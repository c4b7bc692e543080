"""ROS bags (ROS 1, ROS 2 sqlite3 and mcap) written with rosbags' own writers, calibrated from topics."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from s2r.calib.solve.pipelines.stereo_bag import calibrate_stereo_bag
from s2r.cli import main
from s2r.profile import StereoProfile

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

IMAGE = "sensor_msgs/msg/Image"


def _image_msg(ts: Any, image: np.ndarray, stamp_ns: int, *, ros1: bool) -> Any:
    Image, Header, Time = ts.types[IMAGE], ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    stamp = Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    header = Header(seq=0, stamp=stamp, frame_id="cam") if ros1 else Header(stamp=stamp, frame_id="cam")
    h, w = image.shape
    return Image(header=header, height=h, width=w, encoding="mono8", is_bigendian=0, step=w,
                 data=np.ascontiguousarray(image, np.uint8).reshape(-1))


def _messages(folder: Path, pairs: int) -> list[tuple[str, int, np.ndarray]]:
    """Left at 10 Hz, right 3 ms later, plus one left frame without a right partner."""
    out = []
    for i in range(pairs):
        t = 10**9 + i * 10**8
        out.append(("/stereo/left/image_raw", t, cv2.imread(str(folder / "left" / f"{i:02d}.png"), 0)))
        out.append(("/stereo/right/image_raw", t + 3 * 10**6, cv2.imread(str(folder / "right" / f"{i:02d}.png"), 0)))
    out.append(("/stereo/left/image_raw", 10**9 + pairs * 10**8, out[0][2]))
    return out


def write_bag(path: Path, folder: Path, *, kind: str, pairs: int = 8) -> Path:
    """Write ``pairs`` stereo pairs of ``folder`` as a ROS 1 bag or a ROS 2 bag (sqlite3 or mcap)."""
    ros1 = kind == "ros1"
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    writer: Any = Writer1(path) if ros1 else Writer2(
        path, version=9, storage_plugin=StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3)
    with writer:
        conns = {t: writer.add_connection(t, IMAGE, typestore=ts)
                 for t in ("/stereo/left/image_raw", "/stereo/right/image_raw")}
        for topic, t, image in _messages(folder, pairs):
            msg = _image_msg(ts, image, t, ros1=ros1)
            raw = ts.serialize_ros1(msg, IMAGE) if ros1 else ts.serialize_cdr(msg, IMAGE)
            writer.write(conns[topic], t, raw)
    return path


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_bag_pairs_by_stamp_and_calibrates(kind: str, synthetic_set: tuple[Path, StereoProfile],
                                           tmp_path: Path) -> None:
    folder, truth = synthetic_set
    bag = write_bag(tmp_path / ("cal.bag" if kind == "ros1" else "cal"), folder, kind=kind)
    result = calibrate_stereo_bag(bag, left_topic="/stereo/left/image_raw", right_topic="/stereo/right/image_raw",
                                  jobs=2, cache_dir=tmp_path / "cache")
    p = result.profile
    # 8 pairs: the lone left frame found no partner within 10 ms (pairs whose board was missed are listed)
    assert len(result.views) + len({d.name.split("@")[1] for d in result.dropped}) == 8
    assert abs(p.left.fx_px - truth.left.fx_px) < 0.01 * truth.left.fx_px
    assert abs(p.baseline_m - truth.baseline_m) < 0.01 * truth.baseline_m
    assert result.sample_images is not None and result.sample_images[0].shape == (480, 640)
    assert all(len(s.sha256) == 64 for s in p.provenance.sources) and p.provenance.sources


def test_bag_every_and_max_dt(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                              capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "cal.bag", synthetic_set[0], kind="ros1", pairs=12)
    args = ["calibrate", "--bag", str(bag), "--left-topic", "/stereo/left/image_raw", "--right-topic",
            "/stereo/right/image_raw", "--json", "--jobs", "1", "--pattern", "9x6", "--square", "0.025"]
    assert main([*args, "-o", str(tmp_path / "a.yaml"), "--every", "2", "--report", str(tmp_path / "rep")]) == 0
    assert len(json.loads(capsys.readouterr().out)["views"]) == 6
    page = (tmp_path / "rep" / "index.html").read_text()
    assert "rectified pair with horizontal lines" in page  # bag frames kept in memory for the report
    assert main([*args, "-o", str(tmp_path / "b.yaml"), "--max-dt", "0.001"]) == 2
    err = capsys.readouterr().err
    assert "within 0.001 s" in err and "--max-dt" in err


def test_bag_without_the_topics_lists_its_image_topics(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "cal.bag", synthetic_set[0], kind="ros1", pairs=1)
    code = main(["calibrate", "--bag", str(bag), "--left-topic", "/left/image", "--right-topic",
                 "/stereo/right/image_raw", "-o", str(tmp_path / "out.yaml"), "--pattern", "9x6", "--square", "0.025"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "no image topic '/left/image'" in err and "/stereo/left/image_raw, /stereo/right/image_raw" in err
    assert "--left-topic" in err


def test_unreadable_bag_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "broken.bag"
    bad.write_bytes(b"not a bag")
    code = main(["calibrate", "--bag", str(bad), "--left-topic", "/l", "--right-topic", "/r",
                 "-o", str(tmp_path / "out.yaml"), "--pattern", "9x6", "--square", "0.025"])
    err = capsys.readouterr().err
    assert code == 2 and "broken.bag" in err and "cannot read the bag" in err
