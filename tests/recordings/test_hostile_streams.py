"""Issue 37's stream classes as a child under the fuzz suite's bounds (1 GB address space, 20 s): a bag of huge
CompressedImages is refused at its first message's header (class 2), and a video header declaring another size than the
profile's before its first frame is decoded."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from tests.hostile._limits import run_s2r
from tests.recordings.helpers import write_bag, write_cv


def test_check_bag_of_8192px_frames_refused_at_the_first_header(tmp_path: Path) -> None:
    png = cv2.imencode(".png", np.zeros((8192, 8192), np.uint8))[1].tobytes()  # ~260 kB declaring 64 MiB
    bag = write_bag(tmp_path / "big.bag", [(png, png)] * 12)
    done = run_s2r("check", "realsense_d435_848x480", "--bag", str(bag), "--left-topic", "/l", "--right-topic", "/r")
    err = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(err) == 1, done.stderr
    assert "left image is 8192x8192 px but the profile's left camera is 848x480" in err[0]


def test_video_of_another_size_refused_before_decoding(tmp_path: Path) -> None:
    video = write_cv(tmp_path / "v.avi", [np.zeros((480, 2 * 640, 3), np.uint8)] * 3)
    done = run_s2r("check", "realsense_d435_848x480", "--video", str(video), "--layout", "sbs")
    err = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(err) == 1, done.stderr
    assert err[0].startswith(f"error: {video}: --video (sbs): left image is 640x480 px but the profile's left "
                             "camera is 848x480")
