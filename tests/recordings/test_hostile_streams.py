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
    assert err[0].startswith(f"error: {bag} /l @ 1000000000 ns: image size: left image is 8192x8192 px but the "
                             "profile's left camera is 848x480")


def test_video_of_another_size_refused_before_decoding(tmp_path: Path) -> None:
    video = write_cv(tmp_path / "v.avi", [np.zeros((480, 2 * 640, 3), np.uint8)] * 3)
    done = run_s2r("check", "realsense_d435_848x480", "--video", str(video), "--layout", "sbs")
    err = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(err) == 1, done.stderr
    assert err[0].startswith(f"error: {video}: --video (sbs): left image is 640x480 px but the profile's left "
                             "camera is 848x480")


def test_bz2_chunk_declaring_2_gib_refused_before_inflating(tmp_path: Path) -> None:
    """Issue 37 class 3 under the 1 GB cap: a bz2 chunk whose header states 2 GiB inflated is refused when the bag
    opens (calibrate and check), nothing inflated."""
    import struct

    from tests.recordings.test_bag_chunks import _pairs

    bag = write_bag(tmp_path / "bomb.bag", _pairs(), compression="bz2")
    data = bytearray(bag.read_bytes())
    pos = data.find(b"size=")
    struct.pack_into("<I", data, pos + 5, 2 << 30)
    bag.write_bytes(bytes(data))
    for argv in (["calibrate", "--pattern", "9x6", "--square", "0.025", "-o", str(tmp_path / "x.yaml")],
                 ["check", "realsense_d435_848x480"]):
        done = run_s2r(*argv, "--bag", str(bag), "--left-topic", "/l", "--right-topic", "/r")
        err = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(err) == 1, done.stderr
        assert f"{bag}: a bz2 chunk at byte" in err[0] and f"declares {2 << 30} bytes inflated" in err[0]
