"""librealsense recordings before 2.56: a ROS 1 bag (file format 3), read with rosbags' ROS 1 reader.

The layout, as librealsense's ``src/media/ros/ros_writer.cpp`` / ``ros_file_format.h`` write it, per stream
``/device_0/sensor_S/<Type>_<index>``: ``info/camera_info`` (sensor_msgs/CameraInfo: K, D and the model's name,
``Brown Conrady``), ``tf/<group>`` (geometry_msgs/Transform: ``X_stream = R(q) X_ref + t``; the writer's
``rot2quat`` stores the quaternion of R itself), ``image/data`` (sensor_msgs/Image, header seq = frame number,
header stamp = the frame's own timestamp) and ``image/metadata`` (diagnostic_msgs/KeyValue). ``/device_0/info``
holds one KeyValue per camera-info field (``Name``, ``Serial Number``, ``Firmware Version``) and
``/device_0/sensor_S/option/Depth_Units/value`` the depth scale (std_msgs/Float32).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterator
from functools import lru_cache
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from s2r.errors import FormatError
from s2r.formats._common import as_float, rotation_as_printed
from s2r.formats.realsense.facts import HINT, RecordingFacts, Row, StreamFacts, file_head, streams_by_name
from s2r.formats.realsense.text import RealSenseIntrinsic

__all__ = ["BagRecording", "read_bag_facts"]

log = logging.getLogger(__name__)
MAX_INFO_BYTES = 1 << 20
_OPTION_TOPIC = re.compile(r"^/device_0/sensor_\d+/option/Depth_Units/value$")


@lru_cache(maxsize=1)
def _typestore() -> Any:
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise FormatError("reading a ROS 1 .bag recording needs rosbags", hint="pip install 's2r[ros]'") from None
    return get_typestore(Stores.ROS1_NOETIC)


class BagRecording:
    """An open librealsense ROS 1 bag: its topics and messages in log-time order, streamed."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        file_head(self.path, 13)  # a FIFO or device is refused before rosbags opens it
        try:
            from rosbags.rosbag1 import Reader
        except ImportError:
            raise FormatError("reading a ROS 1 .bag recording needs rosbags", hint="pip install 's2r[ros]'") from None
        try:
            self._reader = Reader(self.path)
            self._reader.open()
        except Exception as exc:  # rosbags raises ReaderError, and struct/Index errors on damaged files
            raise FormatError(f"cannot read the ROS 1 bag: {exc}", path=self.path, hint=HINT) from None
        self.topics: dict[str, str] = {c.topic: c.msgtype for c in self._reader.connections}

    def __enter__(self) -> BagRecording:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None, tb: TracebackType | None
                 ) -> None:
        self.close()

    def close(self) -> None:
        """Close the bag."""
        self._reader.close()

    def rows(self, topics: list[str]) -> Iterator[Row]:
        """The messages of ``topics`` in log-time order; an image row carries its header seq (frame number)."""
        conns = [c for c in self._reader.connections if c.topic in topics]
        if not conns:
            return
        try:
            for conn, stamp, raw in self._reader.messages(connections=conns):
                data = bytes(raw)
                image = conn.msgtype == "sensor_msgs/msg/Image" and len(data) >= 4
                yield Row(conn.topic, int(stamp), data, len(data),
                          int.from_bytes(data[:4], "little") if image else None)
        except FormatError:
            raise
        except Exception as exc:  # a damaged chunk met half-way
            raise FormatError(f"cannot read the ROS 1 bag: {exc}", path=self.path, hint=HINT) from None

    def load(self, row: Row, *, limit: int) -> Any:
        """The deserialized message of ``row``, its size checked against ``limit`` (bytes) first."""
        if row.size > limit:
            raise FormatError(f"a message of {row.size} bytes, over the {limit} this topic's messages can need",
                              path=self.path, field=row.topic, hint="a damaged or foreign recording")
        msgtype = self.topics[row.topic]
        try:
            return _typestore().deserialize_ros1(row.key, msgtype)
        except FormatError:
            raise
        except Exception as exc:  # rosbags raises KeyError, struct.error, IndexError, UnicodeDecodeError ...
            raise FormatError(f"a malformed {msgtype} message ({type(exc).__name__}: {exc})", path=self.path,
                              field=row.topic, hint=HINT) from None

    def all(self, topic: str, msgtype: str) -> list[Any]:
        """Every message of ``topic`` (checked to be a ``msgtype``); [] when the topic is absent."""
        if topic not in self.topics:
            return []
        if self.topics[topic] != msgtype:
            raise FormatError(f"expected {msgtype} messages, the recording holds {self.topics[topic]}",
                              path=self.path, field=topic, hint=HINT)
        return [self.load(row, limit=MAX_INFO_BYTES) for row in self.rows([topic])]


def rotation_from_quaternion(x: float, y: float, z: float, w: float, path: Path, field: str) -> Any:
    """The rotation matrix of a unit quaternion (Hamilton, ``w`` the scalar); a far-from-unit one refused."""
    q = np.array([as_float(v, path, field) for v in (x, y, z, w)])
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-3:
        raise FormatError(f"not a unit quaternion (norm {norm:.6g})", path=path, field=field, hint=HINT)
    x, y, z, w = q / norm
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _intrinsic(bag: BagRecording, prefix: str) -> RealSenseIntrinsic | None:
    msgs = bag.all(f"{prefix}/info/camera_info", "sensor_msgs/msg/CameraInfo")
    if not msgs:
        return None
    msg, field = msgs[0], f"{prefix}/info/camera_info"
    k, d = np.asarray(msg.K, np.float64), np.asarray(msg.D, np.float64)
    if k.size != 9 or d.size != 5:
        raise FormatError(f"expected 9 K and 5 D values, got {k.size} and {d.size}", path=bag.path, field=field)
    if int(msg.width) <= 0 or int(msg.height) <= 0:
        raise FormatError(f"image size {msg.width}x{msg.height}", path=bag.path, field=field)
    v = [as_float(float(x), bag.path, field) for x in (k[0], k[2], k[4], k[5], *d)]
    return RealSenseIntrinsic(stream=prefix, width=int(msg.width), height=int(msg.height), formats="", fx=v[0],
                              ppx=v[1], fy=v[2], ppy=v[3], distortion=str(msg.distortion_model),
                              coeffs=tuple(v[4:]), line=0)


def _stream(bag: BagRecording, prefix: str) -> StreamFacts:
    tfs = sorted(t for t in bag.topics if re.fullmatch(re.escape(prefix) + r"/tf/\d+", t))
    group = R = t = None
    if tfs:
        msgs = bag.all(tfs[0], "geometry_msgs/msg/Transform")
        if msgs:
            q, tr = msgs[0].rotation, msgs[0].translation
            R = rotation_as_printed(rotation_from_quaternion(q.x, q.y, q.z, q.w, bag.path, tfs[0]), bag.path,
                                    f"{tfs[0]}: rotation")
            t = np.array([as_float(float(v), bag.path, f"{tfs[0]}: translation") for v in (tr.x, tr.y, tr.z)])
            group = int(tfs[0].rsplit("/", 1)[1])
    image = f"{prefix}/image/data"
    has_image = image in bag.topics and bag.topics[image] == "sensor_msgs/msg/Image"
    metadata = f"{prefix}/image/metadata"
    return StreamFacts(prefix=prefix, intrinsic=_intrinsic(bag, prefix), ref_group=group, R_from_ref=R,
                       t_from_ref=t, image_topic=image if has_image else None,
                       image_type="sensor_msgs/msg/Image" if has_image else None,
                       metadata_topic=metadata if metadata in bag.topics else None)


def read_bag_facts(path: str | Path) -> RecordingFacts:
    """The facts of a librealsense ROS 1 ``.bag`` recording (device 0); FormatError when it is not one."""
    with BagRecording(path) as bag:
        streams = streams_by_name(bag.path, bag.topics, lambda prefix: _stream(bag, prefix))
        device = {str(m.key): str(m.value) for m in bag.all("/device_0/info", "diagnostic_msgs/msg/KeyValue")}
        units = None
        for topic in sorted(t for t in bag.topics if _OPTION_TOPIC.match(t)):
            values = bag.all(topic, "std_msgs/msg/Float32")
            # a Float32: its shortest float32 text (0.001, not 0.00100000005)
            units = as_float(float(str(np.float32(values[0].data))), bag.path, topic) if values else None
            break
        return RecordingFacts(path=bag.path, layout="ros1-bag", device=device, streams=streams, depth_units_m=units)
