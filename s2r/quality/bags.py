"""Depth-quality frames from a ROS bag (ROS 1, ROS 2 sqlite3 / mcap) through rosbags.

The left image topic (``sensor_msgs/Image`` or ``CompressedImage``) pairs with either the right image topic or a
device depth topic (``sensor_msgs/Image`` 16UC1 in 1 mm units, 0 = no data, as realsense-ros publishes
``/camera/depth/image_rect_raw``; or 32FC1 metres) when their header stamps differ by at most ``max_dt_s``.
Messages are streamed: at most a few wait for their partner.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.bags import bag_image_topics, image_from_message, open_bag
from s2r.errors import DepthError
from s2r.quality.inputs import DEFAULT_DEPTH_SCALE_M, depth_from_array

__all__ = ["BagPair", "bag_pairs", "decode_depth", "decode_image"]

BagPair = tuple[str, Any, Any]  # (name, left payload, other payload)


def decode_image(msg: Any, msgtype: str) -> NDArray[np.uint8]:
    """An image message as 8-bit BGR (H, W, 3) or grey (H, W); 16-bit infrared is scaled by 1/256."""
    image = image_from_message(msg, msgtype, error=DepthError)
    if image.dtype == np.uint16:
        image = (image // 256).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.ascontiguousarray(image, np.uint8)


def decode_depth(msg: Any, msgtype: str, *, scale_m: float = DEFAULT_DEPTH_SCALE_M, name: str = "depth"
                 ) -> NDArray[np.float32]:
    """A depth image message (16UC1 counts of ``scale_m`` metres, or 32FC1 metres) as float32 metres, NaN no data."""
    if msgtype.endswith("CompressedImage"):
        raise DepthError("compressed depth topics are not supported", field="--depth-topic",
                         hint="record the raw depth topic (16UC1)")
    encoding = str(getattr(msg, "encoding", "")).upper()
    if encoding not in ("16UC1", "MONO16", "32FC1"):
        raise DepthError(f"depth topic has encoding {encoding or '?'}", path=name, field="--depth-topic",
                         hint="pass a 16UC1 (mm) or 32FC1 (m) depth topic")
    image = image_from_message(msg, msgtype, error=DepthError, topic="--depth-topic")
    return depth_from_array(image, scale_m=scale_m, name=name)


def _check(reader: Any, bag: Path, topics: dict[str, str]) -> None:
    found = bag_image_topics(reader)
    for flag, topic in topics.items():
        if topic not in found:
            raise DepthError(f"no image topic {topic!r} in the bag; its image topics: "
                             f"{', '.join(found) or 'none'}", path=bag, field=flag,
                             hint="pass one of the listed topics")


def bag_pairs(bag: Path, left_topic: str, other_topic: str, *, other_flag: str, max_dt_s: float = 0.01
              ) -> Iterator[tuple[str, tuple[Any, str], tuple[Any, str]]]:
    """Yield ``(name, (left msg, type), (other msg, type))`` for messages whose stamps differ <= ``max_dt_s``."""
    bag = Path(bag)
    reader = open_bag(bag, error=DepthError)
    try:
        _check(reader, bag, {"--left-topic": left_topic, other_flag: other_topic})
        buffers: dict[str, deque[tuple[float, Any, str]]] = {left_topic: deque(), other_topic: deque()}
        partner_of = {left_topic: other_topic, other_topic: left_topic}
        conns = [c for c in reader.connections if c.topic in buffers]
        for conn, _t, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            stamp = float(msg.header.stamp.sec) + 1e-9 * float(msg.header.stamp.nanosec)
            partners = buffers[partner_of[conn.topic]]
            while partners and partners[0][0] < stamp - max_dt_s:
                partners.popleft()
            if not partners:
                buffers[conn.topic].append((stamp, msg, conn.msgtype))
                continue
            p_stamp, p_msg, p_type = partners.popleft()
            mine, theirs = (msg, conn.msgtype), (p_msg, p_type)
            left, other = (mine, theirs) if conn.topic == left_topic else (theirs, mine)
            yield f"{left_topic}@{min(stamp, p_stamp):.3f}", left, other
    finally:
        reader.close()
