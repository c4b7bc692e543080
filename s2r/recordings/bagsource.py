"""A ROS bag's two image topics as a :class:`~s2r.recordings.frames.FrameSource` (see :mod:`s2r.recordings.bags`).

Frames are named by the left image's header stamp in nanoseconds and carry its frame_id. A bag that breaks while
it is read (a damaged chunk, a chunk inflating past its declared size) is one line naming the bag, not a traceback.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from s2r.errors import S2RError
from s2r.recordings.bags import (
    BagMessage,
    check_image_topics,
    grey_of,
    image_from_message,
    open_bag,
    paired_messages,
    refuse_non_camera,
)
from s2r.recordings.decode import SizeRule, to_uint8
from s2r.recordings.frames import StereoFrame, thinned

__all__ = ["BagFrames"]


@dataclass
class BagFrames:
    """``bag`` with ``left_topic`` / ``right_topic`` paired within ``max_dt_s`` seconds; every ``every``-th pair, at
    most ``max_frames`` of them (None: all). The bag is opened (and its topics checked) when this is made."""

    bag: Path
    left_topic: str
    right_topic: str
    rule: SizeRule = field(default_factory=SizeRule)
    grey: bool = False
    every: int = 1
    max_frames: int | None = None
    max_dt_s: float = 0.01

    def __post_init__(self) -> None:
        self.bag = Path(self.bag)
        #: Messages without a partner within ``max_dt_s`` (``TOPIC @ STAMP ns``), skipped; filled as frames are read.
        self.skipped: list[str] = []
        reader = self._open()
        reader.close()

    def _open(self) -> Any:
        reader = open_bag(self.bag, error=self.rule.error)
        try:
            check_image_topics(reader, self.bag, {"--left-topic": self.left_topic,
                                                  "--right-topic": self.right_topic}, error=self.rule.error)
        except BaseException:
            reader.close()
            raise
        return reader

    def describe(self) -> str:
        """The bag and its two topics."""
        return f"bag {self.bag} ({self.left_topic}, {self.right_topic})"

    def message_count(self) -> int:
        """The fewer of the two topics' message counts (an upper bound of the pairs), as the bag's index states."""
        reader = self._open()
        try:
            return min(int(sum(c.msgcount for c in reader.connections if c.topic == t))
                       for t in (self.left_topic, self.right_topic))
        finally:
            reader.close()

    def _image(self, message: BagMessage, side: str) -> Any:
        if self.grey:
            return grey_of(message, rule=self.rule, side=side, error=self.rule.error, bag=self.bag)
        where = f"{self.bag} {message.topic} @ {message.stamp_ns} ns"
        refuse_non_camera(message, error=self.rule.error, topic=f"--{side}-topic", where=where)
        image = image_from_message(message.msg, message.msgtype, error=self.rule.error, rule=self.rule, side=side,
                                   topic=f"--{side}-topic", where=where)
        return to_uint8(image, grey=False)

    def messages(self) -> Iterator[tuple[int, BagMessage, BagMessage]]:
        """``(index, left, right)`` undecoded message pairs after ``every`` / ``max_frames`` (the corner cache keys
        on their sha256); a bag failing while read raises the rule's error."""
        reader = self._open()
        self.skipped = []
        try:
            pairs = paired_messages(reader, self.left_topic, self.right_topic, max_dt_s=self.max_dt_s,
                                    unpaired=self.skipped)
            for index, (left, right) in thinned(_guarded(pairs, self.bag, self.rule.error), self.every,
                                                self.max_frames):
                yield index, left, right
        finally:
            reader.close()

    def frames(self) -> Iterator[StereoFrame]:
        """Decoded pairs in bag order, one at a time, each message's size checked before decoding."""
        for index, left, right in self.messages():
            yield StereoFrame(index=index, name=str(left.stamp_ns), stamp_ns=left.stamp_ns, frame_id=left.frame_id,
                              left=self._image(left, "left"), right=self._image(right, "right"),
                              source=f"bag {self.bag.name} {left.topic} @ {left.stamp_ns} ns")


def _guarded(pairs: Iterator[tuple[BagMessage, BagMessage]], bag: Path, error: type[S2RError]
             ) -> Iterator[tuple[BagMessage, BagMessage]]:
    """``pairs``, with whatever rosbags raises while reading (a damaged or oversized chunk) as one ``error``."""
    while True:
        try:
            pair = next(pairs)
        except StopIteration:
            return
        except S2RError:
            raise
        except Exception as exc:  # rosbags' ReaderError, struct.error, ChunkTooLarge, zlib/bz2/lz4 errors
            raise error(f"cannot read the bag's messages: {exc or type(exc).__name__}", path=bag,
                        hint="the bag is damaged or not a bag s2r can read") from None
        yield pair
