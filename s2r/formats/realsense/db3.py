"""librealsense 2.56+ recordings: a bare ROS 2 sqlite3 ``.db3`` (no ``metadata.yaml``, so rosbags' Reader does not
open it), read with the standard library's sqlite3 in read-only mode and rosbags' typestore for the CDR messages.

What librealsense (2.59, checked with pyrealsense2's own recorder) writes, per stream ``/device_0/sensor_S/T_N``:
``info`` (String ``encoding=Y8;fps=30``), ``camera_info`` (String ``width=..;height=..;fx=..;ppx=..;fy=..;ppy=..;
model=Brown Conrady;coeffs=..``), ``tf/ref_G`` (String ``rotation=<9 column-major>;translation=<3>``, 6 decimals),
and per frame ``image/data`` (Image) or ``image/data/compressed`` / ``compressedDepth`` (CompressedImage, PNG),
``image/metadata`` (String ``Frame number=..;timestamp=..;...``) and ``image/camera_info`` (CameraInfo with the
float32 intrinsics exactly). ``/device_0/info`` holds ``Name=..;Serial Number=..;Firmware Version=..``, and
``/device_0/sensor_S/option/Depth_Units/value`` the depth scale (String, 6 decimals). Header stamps are the
recorder's clock, starting at 0 s.

Every sqlite error, short blob or malformed message becomes one :class:`~s2r.errors.FormatError` line.
"""

from __future__ import annotations

import logging
import re
import sqlite3
from collections.abc import Iterator
from functools import lru_cache
from pathlib import Path
from types import TracebackType
from typing import Any
from urllib.parse import quote

import numpy as np

from s2r.errors import FormatError
from s2r.formats._common import as_float, rotation_as_printed
from s2r.formats.realsense.facts import HINT, RecordingFacts, Row, StreamFacts, file_head, streams_by_name
from s2r.formats.realsense.text import RealSenseIntrinsic

__all__ = ["Db3Recording", "parse_key_values", "read_db3_facts"]

log = logging.getLogger(__name__)

#: Largest info / camera_info / metadata message read (bytes): librealsense's are a few hundred bytes.
MAX_INFO_BYTES = 1 << 20
_OPTION_TOPIC = re.compile(r"^/device_0/sensor_\d+/option/Depth_Units/value$")
_IMAGE_TOPICS = {"image/data": "sensor_msgs/msg/Image", "image/data/compressed": "sensor_msgs/msg/CompressedImage",
                 "image/data/compressedDepth": "sensor_msgs/msg/CompressedImage"}


@lru_cache(maxsize=1)
def _typestore() -> Any:
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise FormatError("reading a .db3 recording needs rosbags", hint="pip install 's2r[ros]'") from None
    return get_typestore(Stores.ROS2_HUMBLE)


def _check_header(path: Path) -> None:
    """Refuse a database whose header declares more pages than the file holds (a truncated copy)."""
    head = file_head(path, 100)
    if len(head) < 100:
        raise FormatError(f"truncated: {len(head)} bytes, shorter than an SQLite header", path=path, hint=HINT)
    page = int.from_bytes(head[16:18], "big")
    page = 65536 if page == 1 else page
    pages = int.from_bytes(head[28:32], "big")
    valid = head[24:28] == head[92:96]  # the in-header size is valid when the change counters agree
    size = path.stat().st_size
    if valid and pages and pages * page > size:
        raise FormatError(f"truncated: the SQLite header declares {pages * page} bytes, the file holds {size}",
                          path=path, hint="copy the whole recording again")


class Db3Recording:
    """An open read-only librealsense ``.db3``: its topics, its messages in log-time order, streamed."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        _check_header(self.path)
        uri = f"file:{quote(str(self.path.resolve()))}?mode=ro"
        try:
            self._conn = sqlite3.connect(uri, uri=True)
        except sqlite3.Error as exc:
            raise self._error(exc) from None
        self.topics: dict[str, tuple[int, str]] = {}
        for tid, name, msgtype in self._query("SELECT id, name, type FROM topics"):
            if not isinstance(name, str) or not isinstance(msgtype, str) or not isinstance(tid, int):
                raise FormatError("a malformed row in the topics table", path=self.path, hint=HINT)
            self.topics[name] = (tid, msgtype)
        self._names = {tid: name for name, (tid, _) in self.topics.items()}

    def __enter__(self) -> Db3Recording:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None, tb: TracebackType | None
                 ) -> None:
        self.close()

    def close(self) -> None:
        """Close the database."""
        self._conn.close()

    def _error(self, exc: BaseException) -> FormatError:
        return FormatError(f"cannot read the recording as an SQLite ROS 2 bag: {exc}", path=self.path, hint=HINT)

    def _query(self, sql: str, args: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
        """Rows of ``sql``, streamed; any sqlite error (a malformed page met half-way too) as FormatError."""
        try:
            cursor = self._conn.execute(sql, args)
            while True:
                batch = cursor.fetchmany(256)
                if not batch:
                    return
                yield from batch
        except sqlite3.Error as exc:
            raise self._error(exc) from None

    def rows(self, topics: list[str]) -> Iterator[Row]:
        """The messages of ``topics`` in log-time order (ties in write order), without their data."""
        ids = [self.topics[t][0] for t in topics if t in self.topics]
        if not ids:
            return
        marks = ",".join("?" * len(ids))
        sql = f"SELECT id, topic_id, timestamp, length(data) FROM messages WHERE topic_id IN ({marks}) " \
              "ORDER BY timestamp, id"
        for mid, tid, stamp, size in self._query(sql, tuple(ids)):
            if not isinstance(stamp, int) or not isinstance(size, int):
                raise FormatError(f"a malformed message row (id {mid})", path=self.path, hint=HINT)
            yield Row(self._names[tid], stamp, mid, size)

    def load(self, row: Row, *, limit: int) -> Any:
        """The deserialized message of ``row``; its size is checked against ``limit`` (bytes) before it is read."""
        if row.size > limit:
            raise FormatError(f"a message of {row.size} bytes, over the {limit} this topic's messages can need",
                              path=self.path, field=row.topic, hint="a damaged or foreign recording")
        data = next(iter(self._query("SELECT data FROM messages WHERE id = ?", (row.key,))), (None,))[0]
        if not isinstance(data, bytes):
            raise FormatError("a message without data", path=self.path, field=row.topic, hint=HINT)
        return self.deserialize(data, self.topics[row.topic][1], row.topic)

    def deserialize(self, data: bytes, msgtype: str, topic: str) -> Any:
        """One CDR message as rosbags' typestore reads it; a malformed one as FormatError naming the topic."""
        try:
            return _typestore().deserialize_cdr(data, msgtype)
        except FormatError:
            raise
        except Exception as exc:  # rosbags raises KeyError, struct.error, IndexError, UnicodeDecodeError ...
            raise FormatError(f"a malformed {msgtype} message ({type(exc).__name__}: {exc})", path=self.path,
                              field=topic, hint=HINT) from None

    def first(self, topic: str, msgtype: str) -> Any | None:
        """The first message of ``topic`` (checked to be a ``msgtype``), None when the topic is absent or empty."""
        if topic not in self.topics:
            return None
        if self.topics[topic][1] != msgtype:
            raise FormatError(f"expected {msgtype} messages, the recording holds {self.topics[topic][1]}",
                              path=self.path, field=topic, hint=HINT)
        row = next(self.rows([topic]), None)
        return None if row is None else self.load(row, limit=MAX_INFO_BYTES)

    def first_string(self, topic: str) -> str | None:
        """The text of the first ``std_msgs/String`` message of ``topic`` (None when absent)."""
        msg = self.first(topic, "std_msgs/msg/String")
        return None if msg is None else str(msg.data)


def parse_key_values(text: str) -> dict[str, str]:
    """``"a=1;b=x y;"`` as ``{"a": "1", "b": "x y"}`` (librealsense's info, camera_info, tf and metadata text)."""
    out: dict[str, str] = {}
    for item in text.split(";"):
        key, sep, value = item.partition("=")
        if sep:
            out[key.strip()] = value.strip()
    return out


def _numbers(text: str, count: int, path: Path, field: str) -> list[float]:
    parts = [p for p in text.split(",") if p.strip()]
    if len(parts) != count:
        raise FormatError(f"expected {count} comma-separated numbers, got {len(parts)}", path=path, field=field)
    try:
        return [as_float(float(p), path, field) for p in parts]
    except ValueError:
        raise FormatError(f"expected numbers, got {text[:80]!r}", path=path, field=field) from None


def _intrinsic(db: Db3Recording, prefix: str, encoding: str) -> RealSenseIntrinsic | None:
    """The stream's intrinsics: the model name from the ``camera_info`` text, the values from the first
    ``image/camera_info`` message (the float32 values exactly) or, without frames, from the text."""
    text = db.first_string(f"{prefix}/camera_info")
    info = parse_key_values(text) if text is not None else {}
    msg = db.first(f"{prefix}/image/camera_info", "sensor_msgs/msg/CameraInfo")
    if msg is None and not info:
        return None
    field = f"{prefix}/camera_info"
    if msg is not None:
        k, d = np.asarray(msg.k, np.float64), np.asarray(msg.d, np.float64)
        values = {"width": float(msg.width), "height": float(msg.height), "fx": k[0], "ppx": k[2], "fy": k[4],
                  "ppy": k[5]}
        coeffs = [float(c) for c in d]
        model = info.get("model") or {"plumb_bob": "Brown Conrady", "equidistant": "Kannala Brandt4"}.get(
            str(msg.distortion_model), str(msg.distortion_model))
    else:
        missing = [key for key in ("width", "height", "fx", "ppx", "fy", "ppy", "coeffs") if key not in info]
        if missing:
            raise FormatError(f"missing {', '.join(missing)}", path=db.path, field=field, hint=HINT)
        values = {key: _numbers(info[key], 1, db.path, f"{field}: {key}")[0]
                  for key in ("width", "height", "fx", "ppx", "fy", "ppy")}
        coeffs = _numbers(info["coeffs"], 5, db.path, f"{field}: coeffs")
        model = info.get("model", "")
    if len(coeffs) != 5:
        raise FormatError(f"expected 5 distortion coefficients, got {len(coeffs)}", path=db.path, field=field)
    checked = {key: as_float(value, db.path, f"{field}: {key}") for key, value in values.items()}
    if not all(float(checked[k]).is_integer() and checked[k] > 0 for k in ("width", "height")):
        raise FormatError(f"image size {checked['width']:g}x{checked['height']:g} is not a positive whole number",
                          path=db.path, field=field)
    return RealSenseIntrinsic(
        stream=prefix, width=int(checked["width"]), height=int(checked["height"]), formats=encoding,
        ppx=checked["ppx"], ppy=checked["ppy"], fx=checked["fx"], fy=checked["fy"], distortion=model,
        coeffs=tuple(as_float(c, db.path, f"{field}: coeffs") for c in coeffs), line=0)


def _extrinsic(db: Db3Recording, prefix: str) -> tuple[int | None, Any, Any]:
    """``(group, R, t)``: ``X_stream = R X_ref + t`` from the stream's ``tf/ref_G`` text (R stored column-major)."""
    found = sorted(t for t in db.topics if t.startswith(f"{prefix}/tf/ref_"))
    if not found:
        return None, None, None
    topic = found[0]
    text = db.first_string(topic)
    values = parse_key_values(text or "")
    if "rotation" not in values or "translation" not in values:
        raise FormatError("expected rotation=...;translation=...", path=db.path, field=topic, hint=HINT)
    rot = np.array(_numbers(values["rotation"], 9, db.path, f"{topic}: rotation")).reshape(3, 3).T  # column-major
    t = np.array(_numbers(values["translation"], 3, db.path, f"{topic}: translation"))
    try:
        group = int(topic.rsplit("_", 1)[1])
    except ValueError:
        raise FormatError("expected tf/ref_<number>", path=db.path, field=topic, hint=HINT) from None
    return group, rotation_as_printed(rot, db.path, f"{topic}: rotation"), t


def _stream(db: Db3Recording, prefix: str) -> StreamFacts:
    info = parse_key_values(db.first_string(f"{prefix}/info") or "")
    encoding = info.get("encoding", "")
    try:
        fps = float(info.get("fps", "0"))
    except ValueError:
        fps = 0.0
    group, rot, t = _extrinsic(db, prefix)
    image = next(((f"{prefix}/{suffix}", db.topics[f"{prefix}/{suffix}"][1]) for suffix in _IMAGE_TOPICS
                  if f"{prefix}/{suffix}" in db.topics), (None, None))
    if image[0] is not None and image[1] != _IMAGE_TOPICS[image[0][len(prefix) + 1:]]:
        raise FormatError(f"expected {_IMAGE_TOPICS[image[0][len(prefix) + 1:]]}, the recording holds {image[1]}",
                          path=db.path, field=image[0], hint=HINT)
    metadata = f"{prefix}/image/metadata" if f"{prefix}/image/metadata" in db.topics else None
    return StreamFacts(prefix=prefix, intrinsic=_intrinsic(db, prefix, encoding), ref_group=group, R_from_ref=rot,
                       t_from_ref=t, image_topic=image[0], image_type=image[1], metadata_topic=metadata,
                       fps=fps if np.isfinite(fps) and fps > 0 else 0.0, encoding=encoding)


def _depth_units(db: Db3Recording) -> float | None:
    for topic in sorted(db.topics):
        if _OPTION_TOPIC.match(topic):
            text = db.first_string(topic)
            return _numbers(text or "", 1, db.path, topic)[0] if text is not None else None
    return None


def read_db3_facts(path: str | Path) -> RecordingFacts:
    """The facts of a librealsense ``.db3`` recording (device 0); FormatError when it is not one."""
    with Db3Recording(path) as db:
        streams = streams_by_name(db.path, db.topics, lambda prefix: _stream(db, prefix))
        device = parse_key_values(db.first_string("/device_0/info") or "")
        return RecordingFacts(path=db.path, layout="ros2-sqlite3", device=device, streams=streams,
                              depth_units_m=_depth_units(db))
