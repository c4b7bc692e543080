"""Bags go through the regular-file rule (before: a FIFO as ``--bag``, or a FIFO .db3/.mcap inside a bag folder,
hung ``calibrate`` and ``depth-quality``), a link out of a bag folder is not followed, and only the bag's own
storage files are hashed for provenance (before: every file under the folder, through links too)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from s2r.calib.detect.bagfiles import bag_storage_files
from s2r.errors import CalibrationError
from tests.hostile._limits import run_s2r

pytest.importorskip("rosbags")
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs (POSIX)")
LEFT, RIGHT = "/cam/left/image_raw", "/cam/right/image_raw"
IMAGE = "sensor_msgs/msg/Image"


def _ros2_bag(folder: Path) -> Path:
    ts = get_typestore(Stores.ROS2_HUMBLE)
    Image, Header, Time = ts.types[IMAGE], ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    with Writer(folder, version=9) as writer:
        for topic in (LEFT, RIGHT):
            conn = writer.add_connection(topic, IMAGE, typestore=ts)
            header = Header(stamp=Time(sec=1, nanosec=0), frame_id="cam")
            msg = Image(header=header, height=4, width=4, encoding="mono8", is_bigendian=0, step=4,
                        data=np.zeros(16, np.uint8))
            writer.write(conn, 10**9, ts.serialize_cdr(msg, IMAGE))
    return folder


def _commands(bag: Path) -> list[list[str]]:
    return [["calibrate", "--bag", str(bag), "--left-topic", LEFT, "--right-topic", RIGHT, "--pattern", "9x6",
             "--square", "0.02", "-o", str(bag.parent / "rig.yaml")],
            ["depth-quality", "realsense_d435_848x480", "--bag", str(bag), "--left-topic", LEFT, "--right-topic",
             RIGHT, "--pattern", "9x6", "--square", "0.02"]]


def test_a_fifo_bag_is_refused_at_once(tmp_path: Path) -> None:
    fifo = tmp_path / "run.bag"
    os.mkfifo(fifo)
    for argv in _commands(fifo):
        done = run_s2r(*argv)
        assert done.returncode == 2 and "not a regular file" in done.stderr and str(fifo) in done.stderr


def test_a_fifo_storage_file_in_a_bag_folder_is_refused(tmp_path: Path) -> None:
    bag = _ros2_bag(tmp_path / "rec")
    storage = bag_storage_files(bag, error=CalibrationError)[1]
    storage.unlink()
    os.mkfifo(storage)
    for argv in _commands(bag):
        done = run_s2r(*argv)
        assert done.returncode == 2 and "not a regular file" in done.stderr and storage.name in done.stderr


def test_links_out_of_the_folder_are_not_followed_and_only_storage_is_hashed(tmp_path: Path) -> None:
    bag = _ros2_bag(tmp_path / "rec")
    secret = tmp_path / "secret.txt"
    secret.write_text("do not hash me", encoding="utf-8")
    (bag / "notes.txt").write_text("mine", encoding="utf-8")
    (bag / "link_to_secret").symlink_to(secret)
    files = bag_storage_files(bag, error=CalibrationError)
    assert files[0].name == "metadata.yaml" and len(files) == 2
    assert files[1].suffix in (".db3", ".mcap") and all(p.parent == bag for p in files)
    moved = tmp_path / "elsewhere.db3"
    files[1].rename(moved)
    files[1].symlink_to(moved)
    with pytest.raises(CalibrationError, match="leading out of the bag folder"):
        bag_storage_files(bag, error=CalibrationError)
