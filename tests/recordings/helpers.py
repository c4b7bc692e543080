"""Recordings made for the tests with tools that share no code with s2r: OpenCV's VideoWriter, Debian's ffmpeg,
rosbags' own writers."""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

OPENCV_SET = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "opencv_stereo_chessboard"
FOURCC = {"mjpg": ("MJPG", ".avi"), "mp4v": ("mp4v", ".mp4")}


def stills() -> list[tuple[np.ndarray, np.ndarray]]:
    """The 13 BGR pairs of the shared OpenCV stereo chessboard set (skips when absent)."""
    left = sorted(OPENCV_SET.glob("left*.jpg"))
    if len(left) != 13:
        pytest.skip(f"the shared OpenCV stereo set is not at {OPENCV_SET}")
    return [(cv2.imread(str(p)), cv2.imread(str(p.with_name(p.name.replace("left", "right"))))) for p in left]


def write_cv(path: Path, frames: Sequence[np.ndarray], *, codec: str = "mjpg", fps: float = 10.0,
             size: tuple[int, int] = (64, 48)) -> Path:
    """Frames (H, W, 3 uint8, all one size) as a video through OpenCV's VideoWriter (MJPG .avi or mp4v .mp4; the
    suffix of ``path`` picks the container); ``size`` (w, h) when there is no frame."""
    fourcc, _ = FOURCC[codec]
    h, w = frames[0].shape[:2] if frames else size[::-1]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert writer.isOpened(), f"OpenCV cannot write {codec}"
    for f in frames:
        writer.write(f)
    writer.release()
    return path


def write_h264(path: Path, frames: Sequence[np.ndarray], *, fps: float = 10.0, crf: int = 12) -> Path:
    """Frames as an H.264 .mp4 (yuv420p, what phones record) through Debian's ffmpeg; skips when it is absent
    (``make test-recordings`` installs it)."""
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test-recordings installs it)")
    h, w = frames[0].shape[:2]
    cmd = ["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "bgr24", "-s", f"{w}x{h}", "-r",
           str(fps), "-i", "-", "-c:v", "libx264", "-crf", str(crf), "-pix_fmt", "yuv420p", str(path)]
    subprocess.run(cmd, input=b"".join(np.ascontiguousarray(f).tobytes() for f in frames), check=True)
    return path


def image_msg(ts: Any, image: np.ndarray, stamp_ns: int, *, ros1: bool, compressed: bytes | None = None) -> Any:
    """A sensor_msgs Image (mono8) or, with ``compressed`` bytes, a CompressedImage."""
    Header, Time = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    stamp = Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    header = Header(seq=0, stamp=stamp, frame_id="cam_optical") if ros1 else Header(stamp=stamp,
                                                                                   frame_id="cam_optical")
    if compressed is not None:
        return ts.types["sensor_msgs/msg/CompressedImage"](header=header, format="png",
                                                           data=np.frombuffer(compressed, np.uint8))
    h, w = image.shape
    return ts.types["sensor_msgs/msg/Image"](header=header, height=h, width=w, encoding="mono8", is_bigendian=0,
                                             step=w, data=np.ascontiguousarray(image, np.uint8).reshape(-1))


def write_bag(path: Path, pairs: Sequence[tuple[np.ndarray, np.ndarray] | tuple[bytes, bytes]], *, kind: str = "ros1",
              compression: str | None = None) -> Path:
    """Stereo pairs on /l and /r (right 2 ms after left, 10 Hz) as a ROS 1 bag (optionally bz2/lz4 chunks) or a ROS 2
    bag (sqlite3/mcap); pairs of bytes become CompressedImage messages."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    ros1 = kind == "ros1"
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    writer: Any = Writer1(path) if ros1 else Writer2(
        path, version=9, storage_plugin=StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3)
    if compression:
        writer.set_compression(getattr(Writer1.CompressionFormat, compression.upper()))
    compressed = isinstance(pairs[0][0], bytes)
    msgtype = "sensor_msgs/msg/CompressedImage" if compressed else "sensor_msgs/msg/Image"
    with writer:
        conns = {t: writer.add_connection(t, msgtype, typestore=ts) for t in ("/l", "/r")}
        for i, pair in enumerate(pairs):
            for k, topic in enumerate(("/l", "/r")):
                t = 10**9 + i * 10**8 + 2 * 10**6 * k
                item = pair[k]
                msg = image_msg(ts, None if compressed else item, t, ros1=ros1,  # type: ignore[arg-type]
                                compressed=item if compressed else None)  # type: ignore[arg-type]
                raw = ts.serialize_ros1(msg, msgtype) if ros1 else ts.serialize_cdr(msg, msgtype)
                writer.write(conns[topic], t, raw)
    return path
