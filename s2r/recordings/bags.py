"""Image pairs from ROS bags (ROS 1 ``.bag``, ROS 2 sqlite3 and mcap) through rosbags.

Left and right ``sensor_msgs/Image`` (or ``CompressedImage``) messages are paired when their header stamps differ
by at most ``max_dt_s`` (as an approximate-time synchroniser would), thinned to every N-th pair, and decoded one
pair at a time: the bag is never loaded whole. Each message's declared size (a raw image's width/height, a
compressed image's PNG/JPEG header) is checked before it is decoded (:class:`s2r.recordings.decode.SizeRule`), and
a ROS 1 bag's compressed chunks are bounded before they are inflated (:mod:`s2r.recordings.bagchunks`).
"""

from __future__ import annotations

import hashlib
import logging
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import CalibrationError, S2RError
from s2r.imageio import declared_size, oversize_reason
from s2r.recordings.bagchunks import bound_ros1_chunks
from s2r.recordings.bagfiles import bag_storage_files
from s2r.recordings.decode import SizeRule, to_uint8

__all__ = ["BagFrame", "BagMessage", "bag_image_topics", "check_image_topics", "image_from_message", "open_bag",
           "paired_bag_frames", "paired_messages", "refuse_non_camera"]

log = logging.getLogger(__name__)
IMAGE_TYPES = frozenset({"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"})


@dataclass(frozen=True)
class BagFrame:
    """One decoded message: topic, header stamp (s), sha256 of the serialized message, grey image (H, W)."""

    topic: str
    stamp_s: float
    sha256: str
    image: NDArray[np.uint8]


@dataclass(frozen=True)
class BagMessage:
    """One image message, not yet decoded: topic, header stamp (ns), sha256 of its serialized bytes, the
    deserialized message, its type name and its header frame_id."""

    topic: str
    stamp_ns: int
    sha256: str
    msg: Any
    msgtype: str
    frame_id: str


def open_bag(bag: Path, *, error: type[S2RError] = CalibrationError) -> Any:
    """An open rosbags ``AnyReader`` on a ROS 1 or ROS 2 bag; a missing or unreadable bag raises ``error``.

    A ROS 1 bag's compressed chunks are checked and bounded here (:func:`bound_ros1_chunks`).
    """
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag1 import Reader as Ros1Reader

    bag = Path(bag)
    if not bag.exists():
        raise error("bag not found", path=bag, hint="check the path (a ROS 2 bag is a folder)")
    bag_storage_files(bag, error=error)  # a FIFO would block rosbags for good: refused before it opens
    try:
        reader = AnyReader([bag])
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for unreadable bags
        raise error(f"cannot read the bag: {exc}", path=bag,
                    hint="pass a ROS 1 .bag file or a ROS 2 bag folder (sqlite3 or mcap)") from None
    try:
        for sub in reader.readers:
            if isinstance(sub, Ros1Reader):
                bound_ros1_chunks(sub, bag=bag, error=error)
    except S2RError:
        reader.close()
        raise
    except Exception as exc:  # a chunk header rosbags read but s2r cannot
        reader.close()
        raise error(f"cannot read the bag's chunks: {exc}", path=bag, hint="the bag is damaged") from None
    return reader


def bag_image_topics(reader: Any) -> list[str]:
    """Sorted image topics (Image / CompressedImage) of an open rosbags reader."""
    return sorted({c.topic for c in reader.connections if c.msgtype in IMAGE_TYPES})


def check_image_topics(reader: Any, bag: Path, topics: dict[str, str], *, error: type[S2RError]) -> None:
    """``error`` naming the flag when a topic of ``topics`` (flag -> topic) is not an image topic of the bag."""
    found = bag_image_topics(reader)
    for flag, topic in topics.items():
        if not topic:
            raise error("a bag needs both image topics", path=bag, field=flag,
                        hint=f"pass {flag}; the bag's image topics: {', '.join(found) or 'none'}")
        if topic not in found:
            raise error(f"no image topic {topic!r} in the bag; its image topics: {', '.join(found) or 'none'}",
                        path=bag, field=flag, hint="pass one of the listed topics")


def _declared(msg: Any, compressed: bool) -> tuple[int, int] | None:
    if compressed:
        return declared_size(bytes(msg.data[:65536]))
    return int(msg.width), int(msg.height)


def image_from_message(msg: Any, msgtype: str, *, error: type[S2RError] = CalibrationError,
                       topic: str = "--left-topic", rule: SizeRule | None = None, side: str = "left",
                       where: str = "") -> NDArray[Any]:
    """An ``Image`` / ``CompressedImage`` message as an OpenCV array (as rosbags decodes it), or ``error`` in one
    line. Before decoding: a compressed image whose header declares more than 16384 px a side is refused, and with
    a ``rule`` the declared size (raw width/height, compressed header) must be the ``side`` camera's. A raw image
    whose data do not fill its declared size or whose encoding is unknown is named."""
    from rosbags.image import compressed_image_to_cvimage, message_to_cvimage

    compressed = msgtype.endswith("CompressedImage")
    if compressed and (reason := oversize_reason(bytes(msg.data[:65536]))):
        raise error(f"an image message: {reason}", field=topic, hint="record sane images")
    size = _declared(msg, compressed)
    if rule is not None and size is not None:
        rule.check(size[0], size[1], side, where=where or topic)
    try:
        image = compressed_image_to_cvimage(msg) if compressed else message_to_cvimage(msg)
    except Exception as exc:  # rosbags raises TypeError, ValueError, ImageFormatError, cv2.error, AssertionError
        size_text = "" if compressed else f" ({getattr(msg, 'width', '?')}x{getattr(msg, 'height', '?')} " \
                                          f"{getattr(msg, 'encoding', '?')}, {len(getattr(msg, 'data', b''))} bytes)"
        raise error(f"an image message{size_text} cannot be decoded: {exc or type(exc).__name__}", field=topic,
                    hint="check the topic's encoding and that its messages are complete") from None
    if image is None:
        raise error("a compressed image message is not a readable image", field=topic, hint="check the topic")
    image = np.asarray(image)
    if rule is not None:
        rule.check(int(image.shape[1]), int(image.shape[0]), side, where=where or topic)
    return image


def _messages(reader: Any, topics: tuple[str, str]) -> Iterator[BagMessage]:
    conns = [c for c in reader.connections if c.topic in topics]
    for conn, _t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, conn.msgtype)
        stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
        yield BagMessage(conn.topic, stamp, hashlib.sha256(bytes(raw)).hexdigest(), msg, conn.msgtype,
                         str(getattr(msg.header, "frame_id", "")))


def paired_messages(reader: Any, left_topic: str, right_topic: str, *, max_dt_s: float = 0.01,
                    unpaired: list[str] | None = None) -> Iterator[tuple[BagMessage, BagMessage]]:
    """Yield (left, right) messages whose header stamps differ by at most ``max_dt_s``, not decoded.

    Messages are buffered only until a partner arrives or a newer message makes one impossible; each message left
    without a partner is appended to ``unpaired`` as ``TOPIC @ STAMP ns`` (those still buffered when the bag ends
    too, when it is read to the end).
    """
    max_dt_ns = round(max_dt_s * 1e9)
    buffers: dict[str, deque[BagMessage]] = {left_topic: deque(), right_topic: deque()}
    other = {left_topic: right_topic, right_topic: left_topic}
    dropped = unpaired if unpaired is not None else []
    for message in _messages(reader, (left_topic, right_topic)):
        partners = buffers[other[message.topic]]
        while partners and partners[0].stamp_ns < message.stamp_ns - max_dt_ns:
            dropped.append(_named(partners.popleft()))
        match = next((p for p in partners if abs(p.stamp_ns - message.stamp_ns) <= max_dt_ns), None)
        if match is None:
            buffers[message.topic].append(message)
            continue
        while partners and partners[0] is not match:
            dropped.append(_named(partners.popleft()))
        partners.popleft()
        yield (message, match) if message.topic == left_topic else (match, message)
    dropped.extend(sorted((_named(m) for q in buffers.values() for m in q), key=lambda n: int(n.split()[-2])))


def _named(message: BagMessage) -> str:
    return f"{message.topic} @ {message.stamp_ns} ns"


def refuse_non_camera(message: BagMessage, *, error: type[S2RError], topic: str, where: str) -> None:
    """A raw image in a float encoding (32FC1, 64FC1: depth or disparity, as s2r's own and ROS's depth topics)
    is not a camera's image: refuse it in one line instead of matching on its scaled values."""
    encoding = str(getattr(message.msg, "encoding", ""))
    if encoding.upper().startswith(("32FC", "64FC")):
        raise error(f"{where}: a {encoding} image (depth or disparity, not a camera image)", field=topic,
                    hint="give the topics of the left and right camera images (e.g. .../image_raw or image_rect)")


def grey_of(message: BagMessage, *, rule: SizeRule | None = None, side: str = "left",
            error: type[S2RError] = CalibrationError, bag: Path | None = None) -> NDArray[np.uint8]:
    """A message's image as 8-bit grey (H, W), its size checked by ``rule`` before decoding (an error names
    ``bag``, the topic and the stamp)."""
    flag = "--left-topic" if side == "left" else "--right-topic"
    where = f"{'' if bag is None else f'{bag} '}{message.topic} @ {message.stamp_ns} ns"
    refuse_non_camera(message, error=error, topic=flag, where=where)
    image = image_from_message(message.msg, message.msgtype, error=error, topic=flag, rule=rule, side=side,
                               where=where)
    return to_uint8(image, grey=True)


def paired_bag_frames(reader: Any, left_topic: str, right_topic: str, *, max_dt_s: float = 0.01,
                      every: int = 1) -> Iterator[tuple[BagFrame, BagFrame]]:
    """Yield (left, right) grey frames whose stamps differ by at most ``max_dt_s``, every ``every``-th pair."""
    for count, (left, right) in enumerate(paired_messages(reader, left_topic, right_topic, max_dt_s=max_dt_s)):
        if count % every:
            continue
        yield (BagFrame(left.topic, left.stamp_ns * 1e-9, left.sha256, grey_of(left)),
               BagFrame(right.topic, right.stamp_ns * 1e-9, right.sha256, grey_of(right, side="right")))
