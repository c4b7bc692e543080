"""One description of a recording's inputs, and the one function that opens any of them as a frame stream.

Forms (exactly one):

- ``folder``: a calibrate-style folder (``left/`` + ``right/``, ``cam0/`` + ``cam1/``, ``image_0/`` + ``image_1/``,
  ``leftNN`` / ``rightNN`` files);
- ``left_glob`` + ``right_glob``: two globs paired by the number in the names;
- ``bag`` + ``left_topic`` + ``right_topic``: a ROS 1 ``.bag``, or a ROS 2 bag (sqlite3 or mcap) folder or file,
  ``Image`` or ``CompressedImage`` topics paired by header stamp within ``max_dt_s``; a librealsense recording (a
  bare sqlite3 ``.db3`` of librealsense 2.56+, or a RealSense Viewer ROS 1 ``.bag`` given without topics) needs no
  topics: its Infrared 1 (left) and Infrared 2 (right) streams are found and paired by frame number
  (:mod:`s2r.recordings.realsense`);
- ``video`` + ``layout``: one video holding both images side by side (``sbs``) or top/bottom (``tb``);
- ``left_video`` + ``right_video``: two videos paired by frame index.

``every`` keeps every N-th frame (counted in the recording), ``max_frames`` stops after that many kept frames.
``start_ns`` (videos only): when the video began, ns since the Unix epoch, the base of its frames' stamps (default
the video file's modification time; see :mod:`s2r.recordings.video`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from s2r.errors import RecordingError, S2RError
from s2r.recordings.decode import ExpectedSize, SizeRule
from s2r.recordings.frames import FrameSource, refuse_same_sides

__all__ = ["RecordingSpec", "open_recording"]

_FORMS = "a FOLDER, --left/--right globs, --bag, --video or --left-video/--right-video"


@dataclass(frozen=True)
class RecordingSpec:
    """Where a recording's frames come from (module docstring). Paths as given; nothing is opened here."""

    folder: Path | None = None
    left_glob: str | None = None
    right_glob: str | None = None
    bag: Path | None = None
    left_topic: str | None = None
    right_topic: str | None = None
    max_dt_s: float = 0.01
    video: Path | None = None
    layout: str = "sbs"
    left_video: Path | None = None
    right_video: Path | None = None
    every: int = 1
    max_frames: int | None = None
    start_ns: int | None = None

    @property
    def kind(self) -> str:
        """'folder', 'globs', 'bag', 'video' or 'videos' (the first form given; :meth:`check` wants exactly one)."""
        for kind, given in self._given().items():
            if given:
                return kind
        return "none"

    def _given(self) -> dict[str, bool]:
        return {"folder": self.folder is not None, "globs": self.left_glob is not None or self.right_glob is not None,
                "bag": self.bag is not None, "video": self.video is not None,
                "videos": self.left_video is not None or self.right_video is not None}

    def check(self, *, error: type[S2RError] = RecordingError) -> RecordingSpec:
        """This spec when it names exactly one form with what that form needs; ``error`` in one line otherwise."""
        given = [k for k, v in self._given().items() if v]
        if len(given) != 1:
            raise error(f"give one recording: {_FORMS}" + (f" (got {', '.join(given)})" if given else ""),
                        field="RECORDING", hint="e.g. a folder with left/ and right/, or --video sbs.mp4")
        pairs = {"globs": (self.left_glob, self.right_glob, "--left and --right"),
                 "bag": (self.left_topic, self.right_topic, "--left-topic and --right-topic"),
                 "videos": (self.left_video, self.right_video, "--left-video and --right-video")}
        one_topic = given[0] == "bag" and (self.left_topic is None) != (self.right_topic is None)
        if (given[0] in pairs and given[0] != "bag" and (pairs[given[0]][0] is None or pairs[given[0]][1] is None)) \
                or one_topic:
            raise error(f"{pairs[given[0]][2]} go together", field=pairs[given[0]][2].replace(" and ", "/"),
                        hint="pass both")
        if self.every < 1:
            raise error(f"must be at least 1, got {self.every}", field="--every", hint="e.g. --every 5")
        if self.max_frames is not None and self.max_frames < 1:
            raise error(f"must be at least 1, got {self.max_frames}", field="--max-frames", hint="e.g. 20")
        if self.start_ns is not None and given[0] not in ("video", "videos"):
            raise error("applies to videos only (bags carry their own stamps, still files none)", field="--start-stamp",
                        hint="drop --start-stamp")
        if self.start_ns is not None and self.start_ns <= 0:
            raise error(f"must be after the Unix epoch, got {self.start_ns} ns", field="--start-stamp",
                        hint="e.g. --start-stamp 2024-05-01T12:00:00Z or 1714564800.0")
        if not 0 < self.max_dt_s < float("inf"):
            raise error(f"must be positive seconds, got {self.max_dt_s}", field="--max-dt", hint="e.g. 0.01")
        self._check_two_sides(given[0], error)
        return self

    def _check_two_sides(self, kind: str, error: type[S2RError]) -> None:
        """Refuse one input given for both cameras (:func:`~s2r.recordings.frames.refuse_same_sides`), before
        anything is opened."""
        if kind == "bag":
            refuse_same_sides(self.left_topic, self.right_topic, field="--left-topic/--right-topic", topics=True,
                              path=self.bag, error=error)
        elif kind == "globs":
            refuse_same_sides(self.left_glob, self.right_glob, field="--left/--right", error=error)
        elif kind == "videos":
            refuse_same_sides(self.left_video, self.right_video, field="--left-video/--right-video", error=error)

    def describe(self) -> str:
        """The recording in one phrase."""
        return {"folder": f"{self.folder}", "globs": f"{self.left_glob} + {self.right_glob}",
                "bag": f"bag {self.bag} ({self.left_topic}, {self.right_topic})",
                "video": f"video {self.video} ({self.layout})",
                "videos": f"videos {self.left_video} + {self.right_video}"}.get(self.kind, "no recording")

    def replace(self, **changes: object) -> RecordingSpec:
        """A copy with ``changes``."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(changes)
        return RecordingSpec(**values)  # type: ignore[arg-type]


def open_recording(spec: RecordingSpec | None = None, *, expected_size: ExpectedSize = None, grey: bool = False,
                   error: type[S2RError] = RecordingError, **forms: object) -> FrameSource:
    """Open a recording as a frame stream (nothing is decoded until its frames are iterated).

    Args:
        spec: the recording; or give its fields as keywords (``open_recording(video="sbs.mp4", layout="sbs")``).
        expected_size: (width, height) px of both cameras, or ((w, h) left, (w, h) right): every image's declared
            size is checked against it before decoding (None: any size up to the pixel limit).
        grey: decode to 8-bit grey (H, W) (else grey or BGR as recorded, 8-bit).
        error: the error class raised on bad input (the calling command's).

    Raises:
        ``error``: no form or several, a missing partner option, a path that is not there, a bag without the topics,
        a video that does not open, a declared size other than ``expected_size`` (when the frames are read).
    """
    if spec is None:
        spec = RecordingSpec(**forms)  # type: ignore[arg-type]
    elif forms:
        spec = spec.replace(**forms)
    spec.check(error=error)
    rule = SizeRule.of(expected_size, error=error)
    every, limit = spec.every, spec.max_frames
    if spec.kind == "bag" and _realsense(Path(str(spec.bag)), topics=spec.left_topic is not None):
        return _open_realsense(Path(str(spec.bag)), rule, every=every, max_frames=limit)
    if spec.kind == "bag":
        from s2r.recordings.bagsource import BagFrames

        return BagFrames(Path(str(spec.bag)), spec.left_topic or "", spec.right_topic or "", rule=rule, grey=grey,
                         every=every, max_frames=limit, max_dt_s=spec.max_dt_s)
    if spec.kind == "video":
        from s2r.recordings.video import VideoFrames

        return VideoFrames(Path(str(spec.video)), spec.layout, rule=rule, grey=grey, every=every, max_frames=limit,
                           start_ns=spec.start_ns)
    if spec.kind == "videos":
        from s2r.recordings.video import TwoVideoFrames

        return TwoVideoFrames(Path(str(spec.left_video)), Path(str(spec.right_video)), rule=rule, grey=grey,
                              every=every, max_frames=limit, start_ns=spec.start_ns)
    from s2r.recordings.files import FileFrames

    folder = None if spec.folder is None else Path(spec.folder)
    return FileFrames(folder, spec.left_glob, spec.right_glob, rule=rule, grey=grey, every=every, max_frames=limit)


def _realsense(bag: Path, *, topics: bool) -> bool:
    """Whether ``bag`` is read as a librealsense recording: a bare SQLite file (no ROS 2 bag folder around it), or
    a ROS 1 bag given without topics."""
    from s2r.formats.realsense.facts import BAG_MAGIC, SQLITE_MAGIC, file_head

    if not bag.is_file() or (bag.parent / "metadata.yaml").is_file():
        return False
    try:
        head = file_head(bag, 16)
    except S2RError:
        return False
    return head.startswith(SQLITE_MAGIC) or (not topics and head.startswith(BAG_MAGIC))


def _open_realsense(bag: Path, rule: SizeRule, *, every: int, max_frames: int | None) -> FrameSource:
    """The IR pair of a librealsense recording, its camera_info sizes checked against ``rule`` before any frame."""
    from s2r.formats.realsense.facts import LEFT_STREAM, RIGHT_STREAM
    from s2r.recordings.realsense import RealSenseFrames

    frames = RealSenseFrames(bag, every=every, max_frames=max_frames)
    for side, stream in (("left", LEFT_STREAM), ("right", RIGHT_STREAM)):
        intr = frames.topics.facts.stream(stream).intrinsic
        if intr is not None:
            rule.check(int(intr.width), int(intr.height), side, where=str(bag), field=f"{stream} camera_info")
    return frames
