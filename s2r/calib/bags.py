"""Stereo calibration from ROS bags (ROS 1 ``.bag``, ROS 2 sqlite3 and mcap) through rosbags.

Left and right ``sensor_msgs/Image`` (or ``CompressedImage``) messages are paired when their header
stamps differ by at most ``max_dt_s`` (as an approximate-time synchroniser would), thinned to every
N-th pair, decoded to grey images on the fly and streamed to the detector: the bag is never loaded whole.
The corner cache is keyed by the sha256 of each message's serialized bytes.
"""

from __future__ import annotations

import hashlib
import logging
import os
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.bagfiles import bag_storage_files
from s2r.calib.detect import CornerCache, DetectItem, detect_stream
from s2r.calib.lens import DEFAULT_LENS
from s2r.calib.stereo import StereoCalibration, calibrate_stereo_detections
from s2r.errors import CalibrationError, S2RError
from s2r.fileio import sha256_file
from s2r.imageio import oversize_reason
from s2r.profile import SourceFile
from s2r.progress import ProgressCallback
from s2r.targets import AnyTarget

__all__ = ["BagFrame", "bag_image_topics", "calibrate_stereo_bag", "open_bag", "paired_bag_frames"]

log = logging.getLogger(__name__)
IMAGE_TYPES = frozenset({"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"})
_SAMPLES = 16


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


def _bag_sources(bag: Path) -> list[SourceFile]:
    return [SourceFile(path=str(p), sha256=sha256_file(p)) for p in bag_storage_files(bag, error=CalibrationError)]


def _check_topics(reader: Any, bag: Path, left_topic: str, right_topic: str) -> int:
    topics = bag_image_topics(reader)
    for flag, topic in (("--left-topic", left_topic), ("--right-topic", right_topic)):
        if topic not in topics:
            listed = ", ".join(topics) if topics else "none"
            raise CalibrationError(f"no image topic {topic!r} in the bag; its image topics: {listed}", path=bag,
                                   field=flag, hint="pass one of the listed topics")
    counts = {t: int(sum(c.msgcount for c in reader.connections if c.topic == t)) for t in (left_topic, right_topic)}
    return min(counts.values())


def calibrate_stereo_bag(
    bag: Path, *, left_topic: str, right_topic: str, max_dt_s: float = 0.01, every: int = 1,
    pattern: tuple[int, int] = (9, 6), square_m: float = 0.025, name: str = "calibrated",
    distortion: str = DEFAULT_LENS, max_error_px: float | None = None, fix_intrinsics: bool = False,
    swap: bool = False,
    jobs: int | None = None, cache_dir: Path | None = None, progress: ProgressCallback | None = None,
    target: AnyTarget | None = None, lens: str = "pinhole",
) -> StereoCalibration:
    """Calibrate a stereo pair from the image topics of a ROS bag; see :func:`s2r.calib.calibrate_stereo`
    (with ``target``: corner ids and partial views through ``lens``, see :mod:`s2r.calib.target_stereo`).

    Raises:
        CalibrationError: bag unreadable, a topic missing (the message lists the bag's image topics),
        no pairs within ``max_dt_s``, or the usual calibration input errors.
    """
    bag = Path(bag)
    reader = open_bag(bag)
    samples: dict[str, tuple[NDArray[np.uint8], NDArray[np.uint8]]] = {}
    names: list[str] = []
    try:
        n_max = _check_topics(reader, bag, left_topic, right_topic)

        def items() -> Iterator[DetectItem]:
            for i, (fl, fr) in enumerate(paired_bag_frames(reader, left_topic, right_topic, max_dt_s=max_dt_s,
                                                           every=every)):
                label = f"pair{i:05d}@{fl.stamp_s:.3f}s"
                names.append(label)
                if len(samples) < _SAMPLES:
                    samples[label] = (fl.image, fr.image)
                yield DetectItem(name=f"{left_topic}@{fl.stamp_s:.3f}", sha256=fl.sha256, source=fl.image)
                yield DetectItem(name=f"{right_topic}@{fr.stamp_s:.3f}", sha256=fr.sha256, source=fr.image)

        cache = CornerCache(cache_dir, target) if cache_dir is not None else None
        dets = list(detect_stream(items(), pattern=pattern, jobs=jobs or os.cpu_count() or 1, cache=cache,
                                  total=2 * max(1, n_max // every), progress=progress, target=target))
    finally:
        reader.close()
    if not names:
        raise CalibrationError(f"no {left_topic} / {right_topic} messages with stamps within {max_dt_s} s",
                               path=bag, field="--max-dt", hint="raise --max-dt or check the topics")
    pairs = [(n, dets[2 * i], dets[2 * i + 1]) for i, n in enumerate(names)]
    if target is not None:
        from s2r.calib.target_stereo import calibrate_stereo_target_detections

        result = calibrate_stereo_target_detections(
            pairs, target=target, lens=lens, distortion=distortion, name=name, max_error_px=max_error_px,
            fix_intrinsics=fix_intrinsics, swap=swap, sources=_bag_sources(bag))
        sample = next((samples[n] for n in result.used_names if n in samples), None)
        return replace(result, sample_images=sample if sample is None or not swap else (sample[1], sample[0]))
    result = calibrate_stereo_detections(
        pairs, pattern=pattern, square_m=square_m, name=name, distortion=distortion, max_error_px=max_error_px,
        fix_intrinsics=fix_intrinsics, swap=swap, sources=_bag_sources(bag))
    sample = next((samples[n] for n in result.used_names if n in samples), None)
    if sample is not None and swap:
        sample = (sample[1], sample[0])
    return replace(result, sample_images=sample)
