"""A librealsense recording (``.db3`` of librealsense 2.56+, or the ROS 1 ``.bag`` of older releases) as a stereo
profile: the two infrared imagers' intrinsics, distortion and extrinsics as the recording states them, the depth
scale, and the camera's name, serial number and firmware as provenance.

Both layouts name their topics after the stream (librealsense's ``ros_file_format.h``):
``/device_D/sensor_S/<Type>_<index>/...`` with ``Infrared_1`` the left imager, ``Infrared_2`` the right one and
``Depth_0`` the depth stream. Each stream's extrinsic (``.../tf/<group>``) maps points from its group's reference
(pin) stream into the stream: ``X_stream = R X_ref + t`` (metres), R column-major in storage as ``rs2_extrinsics``
keeps it (``rsutil.h``: ``to[i] = rotation[j*3 + i] * from[j] + translation[i]``). The pair's OpenCV extrinsics
follow as ``R = R2 R1^T``, ``T = t2 - R t1`` (``X_right = R X_left + T``); with Infrared 1 as the reference
(as librealsense records a D4xx) that is Infrared 2's own extrinsic. ``/tf_static`` holds the inverse transforms
(parent = reference, ROS's child pose in its parent) and is not read.

The layout readers (:mod:`s2r.formats.realsense_db3`, :mod:`s2r.formats.realsense_bag`) turn a file into
:class:`RecordingFacts`; this module holds that model and builds the profile from it.
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
from s2r.formats._common import build_stereo, provenance_for
from s2r.formats.realsense import RealSenseIntrinsic, camera_from_intrinsic
from s2r.profile import StereoProfile

__all__ = ["BAG_MAGIC", "DEPTH_STREAM", "LEFT_STREAM", "RIGHT_STREAM", "RecordingFacts", "Row", "StreamFacts",
           "file_head", "is_realsense_recording", "load_realsense_recording", "open_messages", "pair_extrinsics",
           "read_recording", "streams_by_name"]

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


def read_recording(path: str | Path) -> RecordingFacts:
    """The facts of a librealsense recording, from its content (SQLite: ROS 2 layout; ``#ROSBAG``: ROS 1)."""
    source = Path(path)
    head = file_head(source, 16)
    if head.startswith(SQLITE_MAGIC):
        from s2r.formats.realsense_db3 import read_db3_facts

        return read_db3_facts(source)
    if head.startswith(BAG_MAGIC):
        from s2r.formats.realsense_bag import read_bag_facts

        return read_bag_facts(source)
    raise FormatError("not a librealsense recording (neither an SQLite .db3 nor a ROS 1 .bag)", path=source,
                      hint=HINT)


def open_messages(facts: RecordingFacts) -> Any:
    """The recording's messages (a context manager with ``rows(topics)`` and ``load(row, limit=...)``), for the
    layout ``facts`` were read from."""
    if facts.layout == "ros2-sqlite3":
        from s2r.formats.realsense_db3 import Db3Recording

        return Db3Recording(facts.path)
    from s2r.formats.realsense_bag import BagRecording

    return BagRecording(facts.path)


def pair_extrinsics(facts: RecordingFacts, left: str = LEFT_STREAM, right: str = RIGHT_STREAM
                    ) -> tuple[FloatArray, FloatArray]:
    """OpenCV ``(R, T)`` of the pair, ``X_right = R X_left + T`` (T in metres), from the streams' extrinsics to
    their common reference stream (see the module docstring); FormatError when one is missing."""
    a, b = facts.stream(left), facts.stream(right)
    for name, s in ((left, a), (right, b)):
        if s.R_from_ref is None or s.t_from_ref is None or s.ref_group is None:
            raise FormatError(f"the recording holds no extrinsic of {name}", path=facts.path,
                              field=f"{s.prefix}/tf", hint="record with librealsense, which writes them")
    assert a.R_from_ref is not None and b.R_from_ref is not None  # for mypy: checked above
    assert a.t_from_ref is not None and b.t_from_ref is not None
    if a.ref_group != b.ref_group:
        raise FormatError(f"{left} and {right} have no common reference (extrinsic groups {a.ref_group} and "
                          f"{b.ref_group})", path=facts.path, field=f"{b.prefix}/tf",
                          hint="the two imagers must belong to one device's extrinsic group")
    R = b.R_from_ref @ a.R_from_ref.T
    return R, b.t_from_ref - R @ a.t_from_ref


def _provenance_notes(facts: RecordingFacts) -> str:
    dev = facts.device
    parts = [f"factory calibration as a librealsense recording ({facts.layout}) states it"]
    who = " ".join(v for v in (dev.get("Name", ""), f"S/N {dev['Serial Number']}" if dev.get("Serial Number")
                               else "", f"firmware {dev['Firmware Version']}" if dev.get("Firmware Version")
                               else "") if v)
    if who:
        parts.append(who)
    if facts.depth_units_m is not None:
        parts.append(f"depth units {facts.depth_units_m:.9g} m")
    return "; ".join(parts)


def load_realsense_recording(path: str | Path, *, name: str | None = None, origin: str = "real") -> StereoProfile:
    """A stereo profile of the recording's infrared pair (Infrared 1 left, Infrared 2 right), as recorded.

    The profile's frame_ids are realsense2_camera's (``camera_infra1_optical_frame``); the serial number,
    firmware and depth scale go to ``provenance.notes``.
    """
    facts = read_recording(path)
    cams = []
    for stream, frame_id in ((LEFT_STREAM, "camera_infra1_optical_frame"),
                             (RIGHT_STREAM, "camera_infra2_optical_frame")):
        intr = facts.stream(stream).intrinsic
        if intr is None:
            raise FormatError(f"the recording holds no intrinsics of {stream}", path=facts.path,
                              field=f"{facts.stream(stream).prefix}/camera_info", hint=HINT)
        cams.append(camera_from_intrinsic(intr, facts.path, frame_id))
    R, T = pair_extrinsics(facts)
    size = cams[0].image_size
    serial = facts.device.get("Serial Number", "")
    default = f"realsense_{serial}_{size[0]}x{size[1]}" if serial else f"realsense_{size[0]}x{size[1]}"
    method = "librealsense recording (ROS 2 sqlite3)" if facts.layout == "ros2-sqlite3" else \
        "librealsense recording (ROS 1 bag)"
    return build_stereo(
        name=name or default, left=cams[0], right=cams[1], R=R, T=T, path=facts.path,
        provenance=provenance_for([facts.path], method, origin=origin, notes=_provenance_notes(facts)),
        description=f"{facts.device.get('Name') or 'RealSense'} Infrared 1 + Infrared 2 at {size[0]}x{size[1]} "
                    "(factory calibration, from a recording)",
    )
