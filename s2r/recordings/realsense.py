"""Stereo frames of a librealsense recording: the Infrared 1 (left) and Infrared 2 (right) images, paired and
streamed.

A ``.db3`` (librealsense 2.56+) and the older ROS 1 ``.bag`` are both read as they are (no ``metadata.yaml``
needed). The two imagers of one exposure carry the same frame number: in a ``.db3`` it is the ``Frame number``
of the ``image/metadata`` message written beside each image, in a ROS 1 bag the image header's ``seq``. Pairs are
made by frame number when both images have one, else by the nearest header stamp within half a frame period
(the recorder stamps the two images of one frame up to ~7 ms apart); :attr:`RealSenseFrames.paired_by` counts
which rule made each pair. Each image's declared size (the PNG header, or the Image message's width, height and
step) is checked against the stream's recorded camera_info before anything is decoded.
"""

from __future__ import annotations

import logging
from collections import Counter, deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.formats.realsense.db3 import parse_key_values
from s2r.formats.realsense.facts import DEPTH_STREAM, LEFT_STREAM, RIGHT_STREAM, RecordingFacts, StreamFacts
from s2r.formats.realsense.recording import open_messages, read_recording
from s2r.imageio import _native_stderr_silenced, declared_size, oversize_reason
from s2r.limits import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.recordings.frames import StereoFrame, thinned

__all__ = ["RealSenseFrames", "RealSenseTopics", "find_realsense_topics"]

log = logging.getLogger(__name__)
#: Images buffered per side while waiting for a partner (a dropped frame is given up on after this many).
MAX_PENDING = 32
_GREY = frozenset({"mono8", "8UC1"})


@dataclass(frozen=True)
class RealSenseTopics:
    """The image topics of a RealSense recording and their message types (``sensor_msgs/msg/...``).

    Attributes:
        left, right: Infrared 1 and Infrared 2 image topics (the left and right imagers of a D4xx).
        depth: the depth image topic (16-bit, ``depth_units_m`` metres per unit), None when not recorded.
        facts: everything else the recording states (calibration, device, depth units).
    """

    left: str
    left_type: str
    right: str
    right_type: str
    depth: str | None
    depth_type: str | None
    facts: RecordingFacts


def find_realsense_topics(path: str | Path) -> RealSenseTopics:
    """The IR pair's (and the depth stream's) image topics of a librealsense recording; FormatError naming the
    streams it holds when one infrared stream has no frames."""
    facts = read_recording(path)
    found = []
    for name in (LEFT_STREAM, RIGHT_STREAM):
        stream = facts.stream(name)
        if stream.image_topic is None or stream.image_type is None:
            raise FormatError(f"the recording holds no {name} frames", path=facts.path, field=stream.prefix,
                              hint="record both infrared streams (Infrared 1 and Infrared 2)")
        found.append((stream.image_topic, stream.image_type))
    depth = facts.streams.get(DEPTH_STREAM)
    return RealSenseTopics(left=found[0][0], left_type=found[0][1], right=found[1][0], right_type=found[1][1],
                           depth=depth.image_topic if depth else None, depth_type=depth.image_type if depth else None,
                           facts=facts)


@dataclass
class _Pending:
    frame: int | None
    stamp_ns: int
    row: Any


def _expected_size(stream: StreamFacts, path: Path) -> tuple[int, int] | None:
    intr = stream.intrinsic
    if intr is None:
        return None
    if not (MIN_IMAGE_PX <= intr.width <= MAX_IMAGE_PX and MIN_IMAGE_PX <= intr.height <= MAX_IMAGE_PX):
        raise FormatError(f"camera_info declares {intr.width}x{intr.height} px, outside {MIN_IMAGE_PX}.."
                          f"{MAX_IMAGE_PX} px a side", path=path, field=f"{stream.prefix}/camera_info")
    return intr.width, intr.height


def _message_limit(size: tuple[int, int] | None) -> int:
    """Largest image message read (bytes): 4 bytes a pixel and 1 MiB of header room."""
    w, h = size or (MAX_IMAGE_PX, MAX_IMAGE_PX)
    return 4 * w * h + (1 << 20)


def decode_ir(msg: Any, msgtype: str, expected: tuple[int, int] | None, *, path: Path, topic: str
              ) -> NDArray[np.uint8]:
    """An infrared image message (CompressedImage PNG/JPEG or 8-bit Image) as uint8 (H, W); its declared size is
    checked against ``expected`` (width, height px, the stream's camera_info) and s2r's limit first."""
    if msgtype.endswith("CompressedImage"):
        data = bytes(msg.data)
        size = declared_size(data)
        reason = oversize_reason(data) or ("not a PNG or JPEG image" if size is None else "")
        if not reason and size is not None and expected is not None and size != expected:
            reason = f"the image declares {size[0]}x{size[1]} px, the stream's camera_info {expected[0]}x{expected[1]}"
        if reason:
            raise FormatError(f"an image message: {reason}", path=path, field=topic, hint="a damaged recording")
        with _native_stderr_silenced():
            image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise FormatError("an image message is corrupt (cannot be decoded)", path=path, field=topic,
                              hint="a damaged recording")
    else:
        width, height, step = int(msg.width), int(msg.height), int(msg.step)
        if str(msg.encoding) not in _GREY:
            raise FormatError(f"infrared images in {msg.encoding!r}; s2r reads 8-bit infrared (Y8)", path=path,
                              field=topic, hint="record the infrared streams as Y8")
        problem = (f"declares {width}x{height} px, the stream's camera_info {expected[0]}x{expected[1]}"
                   if expected is not None and (width, height) != expected else
                   f"declares {width}x{height} px, outside {MIN_IMAGE_PX}..{MAX_IMAGE_PX} px a side"
                   if not (MIN_IMAGE_PX <= width <= MAX_IMAGE_PX and MIN_IMAGE_PX <= height <= MAX_IMAGE_PX) else
                   f"holds {len(msg.data)} bytes, fewer than {height} rows of {step} bytes"
                   if step < width or len(msg.data) < step * height else "")
        if problem:
            raise FormatError(f"an image message {problem}", path=path, field=topic, hint="a damaged recording")
        rows = np.frombuffer(np.asarray(msg.data, np.uint8).tobytes()[:step * height], np.uint8)
        image = rows.reshape(height, step)[:, :width]
    if image.dtype != np.uint8 or image.ndim != 2:
        raise FormatError(f"infrared images of {image.dtype} x {image.shape[2] if image.ndim == 3 else 1} "
                          "channels; s2r reads 8-bit grey infrared (Y8)", path=path, field=topic,
                          hint="record the infrared streams as Y8")
    if expected is not None and (image.shape[1], image.shape[0]) != expected:
        raise FormatError(f"an image decodes to {image.shape[1]}x{image.shape[0]} px, the stream's camera_info "
                          f"says {expected[0]}x{expected[1]}", path=path, field=topic, hint="a damaged recording")
    return np.ascontiguousarray(image)


class RealSenseFrames:
    """The Infrared 1 / Infrared 2 pairs of a librealsense recording, decoded one pair at a time.

    Args:
        path: a ``.db3`` (librealsense 2.56+) or ROS 1 ``.bag`` (older librealsense) recording.
        every: keep every ``every``-th pair (counted over all pairs; skipped pairs are never decoded).
        max_frames: stop after this many kept pairs (None: all).
    """

    def __init__(self, path: str | Path, *, every: int = 1, max_frames: int | None = None) -> None:
        if every < 1:
            raise FormatError(f"--every must be at least 1, got {every}", field="--every")
        self.path = Path(path)
        self.topics = find_realsense_topics(self.path)
        self.every, self.max_frames = every, max_frames
        self.paired_by: Counter[str] = Counter()
        self.unpaired = 0

    def describe(self) -> str:
        """One line naming the recording and how its pairs were made."""
        rules = " and ".join(f"{rule} ({n})" for rule, n in self.paired_by.items()) or "frame number or stamp"
        layout = "librealsense .db3" if self.topics.facts.layout == "ros2-sqlite3" else "librealsense ROS 1 bag"
        return f"RealSense recording {self.path} ({layout}; Infrared 1 left, Infrared 2 right, paired by {rules})"

    def frames(self) -> Iterator[StereoFrame]:
        """The pairs in recording order; see the module docstring for the pairing rule."""
        facts = self.topics.facts
        self.paired_by, self.unpaired = Counter(), 0
        sides = {self.topics.left: "left", self.topics.right: "right"}
        streams = {"left": facts.stream(LEFT_STREAM), "right": facts.stream(RIGHT_STREAM)}
        sizes = {side: _expected_size(s, facts.path) for side, s in streams.items()}
        fps = max(streams["left"].fps, streams["right"].fps) or 30.0
        tolerance_ns = int(0.5e9 / fps)
        with open_messages(facts) as messages:
            for index, (left, right) in thinned(self._pairs(messages, sides, streams, tolerance_ns), self.every,
                                                self.max_frames):
                yield self._frame(messages, index, left, right, sizes)
        if self.unpaired:
            log.warning("%s: %d infrared images had no partner (dropped frames) and were skipped", facts.path,
                        self.unpaired)

    def _frame(self, messages: Any, index: int, left: _Pending, right: _Pending,
               sizes: dict[str, tuple[int, int] | None]) -> StereoFrame:
        images, stamps, frame_ids = [], [], []
        for side, pending in (("left", left), ("right", right)):
            limit = _message_limit(sizes[side])
            msg = messages.load(pending.row, limit=limit)
            msgtype = self.topics.left_type if side == "left" else self.topics.right_type
            images.append(decode_ir(msg, msgtype, sizes[side], path=self.path, topic=pending.row.topic))
            stamps.append(int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec))
            frame_ids.append(str(msg.header.frame_id))
        if images[0].shape != images[1].shape:
            raise FormatError(f"Infrared 1 is {images[0].shape[1]}x{images[0].shape[0]} px, Infrared 2 "
                              f"{images[1].shape[1]}x{images[1].shape[0]}", path=self.path, hint="a damaged recording")
        number = "" if left.frame is None else f" frame {left.frame}"
        return StereoFrame(index=index, name=str(stamps[0]), stamp_ns=stamps[0], frame_id=frame_ids[0],
                           left=images[0], right=images[1],
                           source=f"realsense {self.path.name}{number} @ {stamps[0]} ns")

    def _pairs(self, messages: Any, sides: dict[str, str], streams: dict[str, StreamFacts], tolerance_ns: int
               ) -> Iterator[tuple[_Pending, _Pending]]:
        """(left, right) image rows paired by frame number or nearest stamp, counted in ``paired_by`` by rule;
        images left without a partner are counted in ``unpaired``."""
        queues: dict[str, deque[_Pending]] = {"left": deque(), "right": deque()}
        for side, item in _numbered(messages, sides, streams):
            other = queues["right" if side == "left" else "left"]
            match, rule = _partner(item, other, tolerance_ns)
            if match is None:
                queues[side].append(item)
                if len(queues[side]) > MAX_PENDING:
                    queues[side].popleft()
                    self.unpaired += 1
                continue
            while other[0] is not match:
                other.popleft()
                self.unpaired += 1
            other.popleft()
            self.paired_by[rule] += 1
            yield (item, match) if side == "left" else (match, item)
        self.unpaired += len(queues["left"]) + len(queues["right"])


def _partner(item: _Pending, other: deque[_Pending], tolerance_ns: int) -> tuple[_Pending | None, str]:
    """The waiting image of the other side that pairs with ``item``, and the rule that paired them."""
    if item.frame is not None and other and all(p.frame is not None for p in other):
        return next((p for p in other if p.frame == item.frame), None), "frame number"
    near = [p for p in other if abs(p.stamp_ns - item.stamp_ns) <= tolerance_ns]
    return (min(near, key=lambda p: abs(p.stamp_ns - item.stamp_ns)) if near else None), "nearest stamp"


def _numbered(messages: Any, sides: dict[str, str], streams: dict[str, StreamFacts]
              ) -> Iterator[tuple[str, _Pending]]:
    """Each infrared image row with its frame number: the row's own (ROS 1 header seq) or the ``Frame number``
    of the metadata message written right after it (same log time) in a ``.db3``."""
    meta = {streams[side].metadata_topic: side for side in ("left", "right") if streams[side].metadata_topic}
    topics = [*sides, *(t for t in meta if t is not None)]
    pending: dict[str, _Pending | None] = {"left": None, "right": None}
    for row in messages.rows(topics):
        if row.topic in sides:
            side = sides[row.topic]
            if (held := pending[side]) is not None:
                yield side, held
            pending[side] = _Pending(row.frame, row.time_ns, row)
            if row.frame is not None:
                yield side, pending[side]  # type: ignore[misc]
                pending[side] = None
            continue
        side = meta[row.topic]
        held = pending[side]
        if held is None or held.stamp_ns != row.time_ns:
            continue
        held.frame = _frame_number(messages.load(row, limit=1 << 20))
        yield side, held
        pending[side] = None
    for side in ("left", "right"):
        if (held := pending[side]) is not None:
            yield side, held


def _frame_number(msg: Any) -> int | None:
    """The ``Frame number`` of a librealsense metadata message (std_msgs/String ``key=value;...``)."""
    value = parse_key_values(str(getattr(msg, "data", ""))).get("Frame number")
    try:
        return int(value) if value is not None else None
    except ValueError:
        return None
