"""RealSenseFrames on pyrealsense2-written .db3 recordings: the pushed images come back pixel for pixel, paired by
frame number (a dropped right frame skipped), compressed and raw; hostile image messages refused in one line."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from s2r.errors import FormatError
from s2r.recordings.realsense import RealSenseFrames, find_realsense_topics
from tests.formats import realsense_writer as rw


@pytest.mark.parametrize("compress", [True, False])
def test_pairs_come_back_exactly(compress: bool, tmp_path: Path) -> None:
    path = tmp_path / "rec.db3"
    pushed = rw.write(path, rw.Spec(frames=4, compress=compress))
    topics = find_realsense_topics(path)
    kind = "CompressedImage" if compress else "Image"
    assert topics.left.endswith("Infrared_1/image/data" + ("/compressed" if compress else ""))
    assert topics.left_type == topics.right_type == f"sensor_msgs/msg/{kind}"
    assert topics.depth is not None and "Depth_0" in topics.depth
    source = RealSenseFrames(path)
    frames = list(source.frames())
    assert [f.index for f in frames] == [0, 1, 2, 3]
    for frame, (left, right) in zip(frames, pushed, strict=True):
        np.testing.assert_array_equal(frame.left, left)
        np.testing.assert_array_equal(frame.right, right)
        assert frame.frame_id == "Infrared1" and frame.name == str(frame.stamp_ns)
    stamps = [f.stamp_ns for f in frames]
    assert stamps == sorted(stamps) and stamps[0] is not None
    assert source.paired_by == {"frame number": 4} and "paired by frame number (4)" in source.describe()


def test_dropped_frame_is_skipped_and_thinning(tmp_path: Path) -> None:
    path = tmp_path / "rec.db3"
    pushed = rw.write(path, rw.Spec(frames=5, drop_right=(1,)))
    source = RealSenseFrames(path)
    frames = list(source.frames())
    assert len(frames) == 4 and source.unpaired == 1
    for frame, n in zip(frames, (0, 2, 3, 4), strict=True):
        np.testing.assert_array_equal(frame.left, pushed[n][0])
        np.testing.assert_array_equal(frame.right, pushed[n][1])
    thinned = list(RealSenseFrames(path, every=2, max_frames=1).frames())
    assert [f.index for f in thinned] == [0]


def _swap_image(path: Path, data: bytes) -> None:
    with sqlite3.connect(path) as conn:
        conn.execute("UPDATE messages SET data = ? WHERE id = (SELECT MIN(id) FROM messages WHERE topic_id = "
                     "(SELECT id FROM topics WHERE name LIKE '%Infrared_2/image/data%'))", (data,))


def _compressed(png: bytes) -> bytes:
    """A CDR sensor_msgs/CompressedImage (stamp 0, frame_id 'Infrared2', format 'png') around ``png``."""
    def string(text: str) -> bytes:
        raw = text.encode() + b"\0"
        out = len(raw).to_bytes(4, "little") + raw
        return out + b"\0" * (-len(out) % 4)
    body = (0).to_bytes(4, "little") * 2 + string("Infrared2") + string("png")
    return b"\x00\x01\x00\x00" + body + len(png).to_bytes(4, "little") + png


@pytest.mark.parametrize("case", ["huge-png", "wrong-size-png", "corrupt-png", "garbage"])
def test_hostile_image_messages(case: str, tmp_path: Path) -> None:
    path = tmp_path / "rec.db3"
    rw.write(path, rw.Spec(frames=2))
    header = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"
    blobs = {
        "huge-png": _compressed(header + (100000).to_bytes(4, "big") * 2 + b"\x08\x00\x00\x00\x00" + b"\0" * 64),
        "wrong-size-png": _compressed(header + (32).to_bytes(4, "big") * 2 + b"\x08\x00\x00\x00\x00" + b"\0" * 64),
        "corrupt-png": _compressed(header + (64).to_bytes(4, "big") + (48).to_bytes(4, "big") + b"\x08\0\0\0\0"
                                   + b"\x01" * 64),
        "garbage": b"\x00\x01\x00\x00\xff\xff\xff\x7f",
    }
    _swap_image(path, blobs[case])
    with pytest.raises(FormatError) as info:
        list(RealSenseFrames(path).frames())
    assert "\n" not in str(info.value) and "rec.db3" in str(info.value)
