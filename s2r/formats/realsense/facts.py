"""What a librealsense recording states, read without decoding a frame: the model (:class:`RecordingFacts`, one
:class:`StreamFacts` per stream, :class:`Row` per message) that the layout readers (:mod:`s2r.formats.realsense.db3`,
:mod:`s2r.formats.realsense.bag`) fill, their one per-stream dispatch (:func:`streams_by_name`), the stream names and
container signatures, and the guarded read of a file's first bytes. Topics and extrinsics as
:mod:`s2r.formats.realsense.recording` describes them.
"""

from __future__ import annotations

import logging
import os
import re
import stat
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.formats.realsense.text import RealSenseIntrinsic

__all__ = ["BAG_MAGIC", "DEPTH_STREAM", "HINT", "LEFT_STREAM", "RIGHT_STREAM", "SQLITE_MAGIC", "RecordingFacts", "Row",
           "StreamFacts", "file_head", "is_realsense_recording", "streams_by_name"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]

LEFT_STREAM, RIGHT_STREAM, DEPTH_STREAM = "Infrared_1", "Infrared_2", "Depth_0"
SQLITE_MAGIC = b"SQLite format 3\x00"
BAG_MAGIC = b"#ROSBAG V2.0\n"
HINT = "pass a recording made by librealsense (RealSense Viewer, rs-record, or pyrealsense2's recorder)"


class Row(NamedTuple):
    """One message of a recording, not yet read: topic, log time (ns), the layout's storage key, size (bytes),
    and the frame number when the layout tells it without reading the message (a ROS 1 image's header seq)."""

    topic: str
    time_ns: int
    key: Any
    size: int
    frame: int | None = None


@dataclass(frozen=True, eq=False)
class StreamFacts:
    """What a recording states about one stream (``Infrared_1``, ``Depth_0``, ...).

    Attributes:
        prefix: the stream's topic prefix, ``/device_0/sensor_0/Infrared_1``.
        intrinsic: size (px), focal lengths and principal point (px), distortion model and coefficients.
        ref_group: the extrinsic group (the ``N`` of ``tf/N`` or ``tf/ref_N``), None when none was recorded.
        R_from_ref, t_from_ref: ``X_stream = R X_ref + t`` (t in metres) from the group's reference stream.
        image_topic, image_type: the frames' topic and message type (``sensor_msgs/msg/CompressedImage`` or
            ``sensor_msgs/msg/Image``), None when no frame was recorded.
        metadata_topic: the per-frame metadata topic (frame number, timestamps), None when absent.
        fps: frames per second as recorded (0 when unknown).
        encoding: the stream's pixel format as recorded (``Y8``, ``Z16``; '' when unknown).
    """

    prefix: str
    intrinsic: RealSenseIntrinsic | None = None
    ref_group: int | None = None
    R_from_ref: FloatArray | None = None
    t_from_ref: FloatArray | None = None
    image_topic: str | None = None
    image_type: str | None = None
    metadata_topic: str | None = None
    fps: float = 0.0
    encoding: str = ""


@dataclass(frozen=True)
class RecordingFacts:
    """A librealsense recording's calibration and device facts, read without decoding a frame.

    Attributes:
        path: the recording.
        layout: ``ros2-sqlite3`` (librealsense 2.56+ ``.db3``) or ``ros1-bag`` (older ``.bag``).
        device: the device's camera info (``Name``, ``Serial Number``, ``Firmware Version``, ...), as recorded.
        streams: per stream name (``Infrared_1``), what the recording states about it.
        depth_units_m: metres per depth unit (the ``Depth Units`` option), None when not recorded.
    """

    path: Path
    layout: str
    device: Mapping[str, str]
    streams: Mapping[str, StreamFacts] = field(default_factory=dict)
    depth_units_m: float | None = None

    def stream(self, name: str) -> StreamFacts:
        """The facts of stream ``name``; FormatError naming the streams found when it was not recorded."""
        if name not in self.streams:
            found = ", ".join(sorted(self.streams)) or "none"
            raise FormatError(f"no {name} stream in the recording (streams: {found})", path=self.path,
                              hint="record both infrared streams (Infrared 1 and Infrared 2) of a D4xx")
        return self.streams[name]


#: A stream's topics: ``/device_0/sensor_S/<Type>_<index>/...`` (device 0); group 1 is the stream's prefix.
_STREAM_TOPIC = re.compile(r"^(/device_0/sensor_\d+/[A-Za-z]+_\d+)/.+$")


def streams_by_name(path: Path, topics: Iterable[str], read_stream: Callable[[str], StreamFacts]
                    ) -> dict[str, StreamFacts]:
    """Each stream of device 0 by name (``Infrared_1``...), read from its topic prefix by the layout's
    ``read_stream``; a name two sensors record is read from the first (logged). FormatError naming a few topics
    when the recording has no stream topic."""
    topics = list(topics)
    prefixes = sorted({m.group(1) for topic in topics if (m := _STREAM_TOPIC.match(topic))})
    if not prefixes:
        sample = ", ".join(sorted(topics)[:4]) or "none"
        raise FormatError(f"no librealsense stream topics (/device_0/sensor_N/<stream>/...; topics: {sample})",
                          path=path, hint=HINT)
    streams: dict[str, StreamFacts] = {}
    for prefix in prefixes:
        name = prefix.rsplit("/", 1)[1]
        if name in streams:
            log.info("%s: stream %s recorded by two sensors; reading %s", path, name, streams[name].prefix)
            continue
        streams[name] = read_stream(prefix)
    return streams


def file_head(path: str | Path, size: int, *, error: type[FormatError] = FormatError) -> bytes:
    """The first ``size`` bytes of the regular file ``path`` (a FIFO or device refused before a byte is read)."""
    source = Path(path)
    try:
        fd = os.open(source, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise error(f"cannot read the recording: {exc.strerror or exc}", path=source, hint=HINT) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error("not a regular file (a folder, device, FIFO or socket)", path=source, hint=HINT)
        return os.read(fd, size)
    finally:
        os.close(fd)


def is_realsense_recording(path: str | Path) -> bool:
    """True when ``path`` is an SQLite database or a ROS 1 bag (the two containers librealsense records to);
    whether it holds a RealSense recording is told by :func:`read_recording`."""
    source = Path(path)
    if not source.is_file():
        return False
    try:
        head = file_head(source, 16)
    except FormatError:
        return False
    return head.startswith(SQLITE_MAGIC) or head.startswith(BAG_MAGIC)
