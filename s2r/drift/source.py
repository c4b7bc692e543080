"""Where a drift check's ordinary stereo pairs come from: a folder, two globs, or a bag and two topics.

The same layouts ``s2r calibrate`` reads (``left/`` + ``right/``, ``leftNN``/``rightNN`` files, globs paired by
number, ROS 1 or ROS 2 bags paired by stamp). At most ``max_frames`` pairs are used, spread evenly over the
recording, and every image is read through s2r's bounded image reader.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib import find_stereo_pairs
from s2r.errors import CalibrationError, CheckError
from s2r.imageio import decode_image_file
from s2r.profile import StereoProfile

__all__ = ["Sizes", "StereoSource", "profile_sizes", "read_pairs"]

GreyPair = tuple[str, NDArray[np.uint8], NDArray[np.uint8]]
#: Expected (width, height) px of the left and the right images, or None for any size.
Sizes = tuple[tuple[int, int], tuple[int, int]] | None


@dataclass(frozen=True)
class StereoSource:
    """One recording: ``folder``, or ``left_glob`` + ``right_glob``, or ``bag`` + ``left_topic`` + ``right_topic``."""

    folder: Path | None = None
    left_glob: str | None = None
    right_glob: str | None = None
    bag: Path | None = None
    left_topic: str | None = None
    right_topic: str | None = None
    max_frames: int = 20

    def describe(self) -> str:
        """The recording in one phrase, for reports."""
        if self.bag is not None:
            return f"{self.bag} ({self.left_topic}, {self.right_topic})"
        if self.folder is not None:
            return str(self.folder)
        return f"{self.left_glob} + {self.right_glob}"


def _spread(count: int, limit: int) -> list[int]:
    """``limit`` indices spread evenly over ``count`` items (all of them when there are fewer)."""
    if count <= limit:
        return list(range(count))
    if limit == 1:
        return [count // 2]
    return sorted({round(k * (count - 1) / (limit - 1)) for k in range(limit)})


def _check_size(image: NDArray[np.uint8], size: tuple[int, int] | None, where: str | Path, side: str) -> None:
    if size is not None and image.shape[:2] != (size[1], size[0]):
        raise CheckError(f"{side} image is {image.shape[1]}x{image.shape[0]} px but the profile's {side} camera "
                         f"is {size[0]}x{size[1]}", path=where, field="image size",
                         hint="check the recording with the profile of the camera that took it")


def _grey(path: Path, size: tuple[int, int] | None, side: str) -> NDArray[np.uint8]:
    image, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise CheckError(reason, path=path, hint="pass readable image files")
    _check_size(image, size, path, side)
    return np.asarray(image, np.uint8)


def _folder_pairs(source: StereoSource, sizes: Sizes) -> Iterator[GreyPair]:
    try:
        pairs = find_stereo_pairs(source.folder, left_glob=source.left_glob, right_glob=source.right_glob)
    except CalibrationError as exc:  # the same finder as calibrate; its message names the folder or glob
        raise CheckError(exc.message, path=exc.path, field=exc.field, hint=exc.hint) from None
    if not pairs.names:
        unpaired = f"; unpaired: {', '.join(p.name for p in pairs.unpaired[:3])}" if pairs.unpaired else ""
        raise CheckError(f"no left/right image pairs (regular image files) found{unpaired}",
                         path=source.describe(), hint="give each left image a right partner with the same number")
    left_size, right_size = sizes if sizes is not None else (None, None)
    for k in _spread(len(pairs.names), source.max_frames):
        yield (pairs.names[k], _grey(pairs.left[k], left_size, "left"),
               _grey(pairs.right[k], right_size, "right"))


def _decimated(frames: Iterator[GreyPair], limit: int) -> list[GreyPair]:
    """Every ``step``-th frame, ``step`` doubling whenever more than ``2 * limit`` are held: memory stays
    bounded on a long bag and the kept frames still span all of it."""
    kept: list[GreyPair] = []
    step = 1
    for k, frame in enumerate(frames):
        if k % step:
            continue
        kept.append(frame)
        if len(kept) > 2 * limit:
            kept, step = kept[::2], step * 2
    return kept


def _bag_pairs(source: StereoSource, sizes: Sizes) -> Iterator[GreyPair]:
    from s2r.calib.detect.bags import open_bag, paired_bag_frames

    assert source.bag is not None
    if not source.left_topic or not source.right_topic:
        raise CheckError("a bag needs both image topics", path=source.bag, field="--left-topic/--right-topic",
                         hint="pass --left-topic and --right-topic")
    reader = open_bag(source.bag, error=CheckError)
    try:
        names = {c.topic for c in reader.connections}
        for topic in (source.left_topic, source.right_topic):
            if topic not in names:
                raise CheckError(f"no topic {topic}", path=source.bag, field="topic",
                                 hint=f"image topics here: {', '.join(sorted(names)) or 'none'}")
        frames = _decimated(((f"{left.stamp_s:.3f}", left.image, right.image)
                             for left, right in paired_bag_frames(reader, source.left_topic, source.right_topic)),
                            source.max_frames)
    finally:
        reader.close()
    if not frames:
        raise CheckError("no stereo pairs on these topics", path=source.bag, field="topic",
                         hint="check --left-topic and --right-topic")
    for k in _spread(len(frames), source.max_frames):
        name, left, right = frames[k]
        for side, image, size in zip(("left", "right"), (left, right), sizes or (None, None), strict=True):
            _check_size(image, size, f"{source.bag} @ {name} s", side)
        yield frames[k]


def read_pairs(source: StereoSource, *, sizes: Sizes = None) -> Iterator[GreyPair]:
    """``(name, left, right)`` grey (H, W) uint8 pairs of the recording, at most ``max_frames`` of them.

    Args:
        sizes: the profile's ``((w, h) left, (w, h) right)`` px: an image of another size is a CheckError naming
            its file (or bag and stamp), not a meaningless fit.
    """
    if source.max_frames < 1:
        raise CheckError(f"must be at least 1, got {source.max_frames}", field="--max-frames", hint="e.g. 20")
    if source.bag is not None:
        return _bag_pairs(source, sizes)
    return _folder_pairs(source, sizes)


def profile_sizes(profile: StereoProfile) -> Sizes:
    """The ``sizes`` of :func:`read_pairs` for ``profile``'s two cameras."""
    return ((profile.left.width_px, profile.left.height_px), (profile.right.width_px, profile.right.height_px))
