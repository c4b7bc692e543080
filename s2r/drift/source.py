"""Where a drift check's ordinary stereo pairs come from: any recording input (:mod:`s2r.recordings`): a folder, two
globs, a bag and two topics, one side-by-side / top-bottom video, or two videos.

The same layouts ``s2r calibrate`` reads. At most ``max_frames`` pairs are used, spread evenly over the recording
(files: only those are decoded; streams: every ``every``-th frame is read and the kept ones thinned as it goes, so
memory stays bounded), and every image's declared size is checked against the profile before it is decoded.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import CheckError
from s2r.profile import StereoProfile
from s2r.recordings import NAMED_SKIPPED, RecordingSpec, open_recording, skipped_inputs
from s2r.recordings.files import FileFrames

log = logging.getLogger(__name__)

__all__ = ["Sizes", "StereoSource", "profile_sizes", "read_pairs", "spread"]

GreyPair = tuple[str, NDArray[np.uint8], NDArray[np.uint8]]
#: Expected (width, height) px of the left and the right images, or None for any size.
Sizes = tuple[tuple[int, int], tuple[int, int]] | None


#: The recording fields a :class:`StereoSource` reads through to its :class:`RecordingSpec`.
_SPEC_FIELDS = frozenset(f.name for f in fields(RecordingSpec))


@dataclass(frozen=True, init=False)
class StereoSource:
    """One recording (a :class:`~s2r.recordings.RecordingSpec`: a folder, two globs, a bag and two topics, a video
    or two) and how many pairs a check uses, ``max_frames``, spread over it.

    ``StereoSource(folder=...)``, ``StereoSource(bag=..., left_topic=..., right_topic=..., max_frames=8)`` or
    ``StereoSource(spec, max_frames=8)``; the spec's fields read through (``source.folder``). It pickles as the
    spec and the number (a fleet sends it to Dask workers).
    """

    recording: RecordingSpec
    max_frames: int = 20

    def __init__(self, recording: RecordingSpec | None = None, *, max_frames: int = 20, **forms: Any) -> None:
        spec = recording if recording is not None else RecordingSpec()
        # the spread is this module's: the spec reads every frame (its own max_frames stays None)
        object.__setattr__(self, "recording", spec.replace(**forms, max_frames=None))
        object.__setattr__(self, "max_frames", max_frames)

    def __getattr__(self, name: str) -> Any:
        if name in _SPEC_FIELDS and "recording" in self.__dict__:
            return getattr(self.__dict__["recording"], name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def spec(self) -> RecordingSpec:
        """The recording as a :class:`~s2r.recordings.RecordingSpec` (all frames: the spread is this module's)."""
        return self.recording

    def describe(self) -> str:
        """The recording in one phrase, for reports."""
        r = self.recording
        if r.kind == "bag":
            return f"{r.bag} ({r.left_topic}, {r.right_topic})"
        return r.describe()


def spread(count: int, limit: int) -> list[int]:
    """``limit`` indices spread evenly over ``count`` items (all of them when there are fewer)."""
    if count <= limit:
        return list(range(count))
    if limit == 1:
        return [count // 2]
    return sorted({round(k * (count - 1) / (limit - 1)) for k in range(limit)})


def _decimated(frames: Iterator[GreyPair], limit: int) -> list[GreyPair]:
    """Every ``step``-th frame, ``step`` doubling whenever more than ``2 * limit`` are held: memory stays
    bounded on a long recording and the kept frames still span all of it."""
    kept: list[GreyPair] = []
    step = 1
    for k, frame in enumerate(frames):
        if k % step:
            continue
        kept.append(frame)
        if len(kept) > 2 * limit:
            kept, step = kept[::2], step * 2
    return kept


def read_pairs(source: StereoSource, *, sizes: Sizes = None, skipped: list[str] | None = None) -> Iterator[GreyPair]:
    """``(name, left, right)`` grey (H, W) uint8 pairs of the recording, at most ``max_frames`` of them.

    Args:
        sizes: the profile's ``((w, h) left, (w, h) right)`` px: an image declaring another size is a CheckError
            naming its file (or bag topic and stamp, or video), before it is decoded.
        skipped: filled, once the pairs are read, with the inputs that had no partner (image files, ``TOPIC @
            STAMP ns`` bag messages), which were not checked (:func:`s2r.recordings.skipped_fields` puts them in
            ``--json``).
    """
    if source.max_frames < 1:
        raise CheckError(f"must be at least 1, got {source.max_frames}", field="--max-frames", hint="e.g. 20")
    recording = open_recording(source.recording, expected_size=sizes, grey=True, error=CheckError)
    if isinstance(recording, FileFrames):
        recording.indices = tuple(spread(len(recording), source.max_frames))
        return _warning_skipped(((f.name, f.left, f.right) for f in recording.frames()), recording, skipped)
    return _warning_skipped(_spread_stream(recording.frames(), source), recording, skipped)


def _warning_skipped(pairs: Iterator[GreyPair], recording: object, noted: list[str] | None) -> Iterator[GreyPair]:
    """``pairs``, then one warning naming the inputs the recording skipped for want of a partner (as depth and
    calibrate say): a check on fewer frames than the folder seems to hold says why. They go into ``noted`` too."""
    yield from pairs
    skipped = skipped_inputs(recording)
    if noted is not None:
        noted[:] = skipped
    if skipped:
        log.warning("%d input image(s) had no partner and were not checked: %s%s", len(skipped),
                    ", ".join(skipped[:NAMED_SKIPPED]), ", ..." if len(skipped) > NAMED_SKIPPED else "")


def _spread_stream(frames: Iterator[Any], source: StereoSource) -> Iterator[GreyPair]:
    kept = _decimated(((f.name, f.left, f.right) for f in frames), source.max_frames)
    if not kept:
        raise CheckError("no stereo pairs in the recording", path=source.describe(),
                         hint="check --left-topic and --right-topic (bags) or the video")
    for k in spread(len(kept), source.max_frames):
        yield kept[k]


def profile_sizes(profile: StereoProfile) -> Sizes:
    """The ``sizes`` of :func:`read_pairs` for ``profile``'s two cameras."""
    return ((profile.left.width_px, profile.left.height_px), (profile.right.width_px, profile.right.height_px))
