"""Image pairs from ROS bags (ROS 1 ``.bag``, ROS 2 sqlite3 and mcap) through rosbags.

Left and right ``sensor_msgs/Image`` (or ``CompressedImage``) messages are paired when their header
stamps differ by at most ``max_dt_s`` (as an approximate-time synchroniser would), thinned to every
N-th pair, decoded to grey images on the fly and streamed to the detector: the bag is never loaded whole.
The corner cache is keyed by the sha256 of each message's serialized bytes.
"""

from __future__ import annotations

import hashlib
import logging
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.bagfiles import bag_storage_files
from s2r.errors import CalibrationError, S2RError
from s2r.imageio import oversize_reason

__all__ = ["BagFrame", "bag_image_topics", "open_bag", "paired_bag_frames"]

log = logging.getLogger(__name__)
IMAGE_TYPES = frozenset({"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"})


@dataclass(frozen=True)
class BagFrame:
    """One decoded message: topic, header stamp (s), sha256 of the serialized message, grey image (H, W)."""

    topic: str
    stamp_s: float
    sha256: str
    image: NDArray[np.uint8]


def open_bag(bag: Path, *, error: type[S2RError] = CalibrationError) -> Any:
    """An open rosbags ``AnyReader`` on a ROS 1 or ROS 2 bag; a missing or unreadable bag raises ``error``."""
    from rosbags.highlevel import AnyReader

    if not bag.exists():
        raise error("bag not found", path=bag, hint="check the path (a ROS 2 bag is a folder)")
    bag_storage_files(bag, error=error)  # a FIFO would block rosbags for good: refused before it opens
    try:
        reader = AnyReader([bag])
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for unreadable bags
        raise error(f"cannot read the bag: {exc}", path=bag,
                    hint="pass a ROS 1 .bag file or a ROS 2 bag folder (sqlite3 or mcap)") from None
    return reader


def bag_image_topics(reader: Any) -> list[str]:
    """Sorted image topics (Image / CompressedImage) of an open rosbags reader."""
    return sorted({c.topic for c in reader.connections if c.msgtype in IMAGE_TYPES})


def image_from_message(msg: Any, msgtype: str, *, error: type[S2RError] = CalibrationError,
                       topic: str = "--left-topic") -> NDArray[Any]:
    """An ``Image`` / ``CompressedImage`` message as an OpenCV array (as rosbags decodes it), or ``error`` in one
    line: a compressed image whose header declares more than 16384 px a side is refused before decoding, and
    a raw image whose data do not fill its declared size or whose encoding is unknown is named."""
    from rosbags.image import compressed_image_to_cvimage, message_to_cvimage

    compressed = msgtype.endswith("CompressedImage")
    if compressed and (reason := oversize_reason(bytes(msg.data[:65536]))):
        raise error(f"an image message: {reason}", field=topic, hint="record sane images")
    try:
        image = compressed_image_to_cvimage(msg) if compressed else message_to_cvimage(msg)
    except Exception as exc:  # rosbags raises TypeError, ValueError, ImageFormatError, cv2.error
        size = "" if compressed else f" ({getattr(msg, 'width', '?')}x{getattr(msg, 'height', '?')} " \
                                     f"{getattr(msg, 'encoding', '?')}, {len(getattr(msg, 'data', b''))} bytes)"
        raise error(f"an image message{size} cannot be decoded: {exc}", field=topic,
                    hint="check the topic's encoding and that its messages are complete") from None
    if image is None:
        raise error("a compressed image message is not a readable image", field=topic, hint="check the topic")
    return np.asarray(image)


def _grey(msg: Any, msgtype: str) -> NDArray[np.uint8]:
    image = image_from_message(msg, msgtype)
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    if image.dtype != np.uint8:
        scaled = image.astype(np.float64) - float(image.min())
        image = (255.0 * scaled / max(float(scaled.max()), 1e-12)).astype(np.uint8)
    return np.ascontiguousarray(image, np.uint8)


def _frames(reader: Any, topics: tuple[str, str]) -> Iterator[tuple[str, float, str, Any, str]]:
    conns = [c for c in reader.connections if c.topic in topics]
    for conn, _t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, conn.msgtype)
        stamp = float(msg.header.stamp.sec) + 1e-9 * float(msg.header.stamp.nanosec)
        yield conn.topic, stamp, hashlib.sha256(bytes(raw)).hexdigest(), msg, conn.msgtype


def paired_bag_frames(reader: Any, left_topic: str, right_topic: str, *, max_dt_s: float = 0.01,
                      every: int = 1) -> Iterator[tuple[BagFrame, BagFrame]]:
    """Yield (left, right) frames whose stamps differ by at most ``max_dt_s``, every ``every``-th pair.

    Messages are buffered only until a partner arrives or a newer message makes one impossible.
    """
    buffers: dict[str, deque[tuple[float, str, Any, str]]] = {left_topic: deque(), right_topic: deque()}
    other = {left_topic: right_topic, right_topic: left_topic}
    count = 0
    for topic, stamp, sha, msg, msgtype in _frames(reader, (left_topic, right_topic)):
        partners = buffers[other[topic]]
        while partners and partners[0][0] < stamp - max_dt_s:
            partners.popleft()
        match = next((p for p in partners if abs(p[0] - stamp) <= max_dt_s), None)
        if match is None:
            buffers[topic].append((stamp, sha, msg, msgtype))
            continue
        while partners and partners[0] is not match:
            partners.popleft()
        partners.popleft()
        count += 1
        if (count - 1) % every:
            continue
        mine = BagFrame(topic, stamp, sha, _grey(msg, msgtype))
        theirs = BagFrame(other[topic], match[0], match[1], _grey(match[2], match[3]))
        yield (mine, theirs) if topic == left_topic else (theirs, mine)
