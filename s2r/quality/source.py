"""A recording as one value: any input ``depth-quality`` takes, named by one command-line argument, opened as views.

Forms of ``SRC`` (``validate --recording SRC --sim-recording SRC``):

- ``DIR``: stereo pairs as ``s2r calibrate`` finds them (``left/`` + ``right/``, ``cam0/`` + ``cam1/``, ``leftNN`` /
  ``rightNN`` files), or device depth when ``DIR`` holds ``left/`` and ``depth/``;
- ``key=value,...`` with ``left=DIR|GLOB`` and ``right=DIR|GLOB`` (stereo pairs) or ``depth=DIR|GLOB`` (device
  depth registered to the left images: uint16 mm PNG or float32 metres ``.npy``), optional ``depth-scale=M``;
- ``bag=BAG,left-topic=T,right-topic=T`` or ``bag=BAG,left-topic=T,depth-topic=T``, optional ``max-dt=S``.

A ``SRC`` naming an existing file or folder is that path, whatever characters it holds (``=``, ``,``, quotes); a
value of ``key=value`` may be quoted (``left="a,b=c/",right='r/'``) to hold commas or ``=``. Stereo pairs may also
be any recording form of :mod:`s2r.recordings` (videos too), given as a :class:`~s2r.recordings.RecordingSpec`
(``RecordingSource(recording=...)``: the commands' shared recording options).

Stereo pairs go through the profile's pipeline (depth in the rectified left camera); device depth is scored in
the left camera with the profile's intrinsics and distortion.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sized
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.profile import StereoProfile
from s2r.quality.inputs import DEFAULT_DEPTH_SCALE_M
from s2r.quality.run import DepthView
from s2r.recordings import RecordingSpec, open_recording, refuse_same_sides

__all__ = ["OpenedSource", "RecordingSource", "check_source", "open_source", "parse_source", "stereo_spec"]

_KEYS = {"left": "left", "right": "right", "depth": "depth", "bag": "bag", "left-topic": "left_topic",
         "right-topic": "right_topic", "depth-topic": "depth_topic", "max-dt": "max_dt_s",
         "depth-scale": "depth_scale_m"}


@dataclass(frozen=True)
class RecordingSource:
    """Where a recording's frames come from (module docstring); ``folder`` a calibrate-style folder."""

    folder: str | None = None
    left: str | None = None
    right: str | None = None
    depth: str | None = None
    bag: str | None = None
    left_topic: str | None = None
    right_topic: str | None = None
    depth_topic: str | None = None
    max_dt_s: float = 0.01
    depth_scale_m: float = DEFAULT_DEPTH_SCALE_M
    recording: RecordingSpec | None = None

    @property
    def stereo(self) -> bool:
        """True for stereo pairs through the pipeline, False for device depth."""
        return self.depth is None and self.depth_topic is None

    def describe(self) -> str:
        """A short human name: the folder, the globs or the bag and its topics."""
        if self.recording is not None:
            return self.recording.describe()
        if self.bag is not None:
            return f"{self.bag} ({self.left_topic} + {self.right_topic or self.depth_topic})"
        if self.folder is not None and self.left is None:
            return self.folder
        return f"{self.left} + {self.right or self.depth}"


def _number(key: str, text: str, option: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise DepthError(f"{key} must be a positive number, got {text!r}", field=option, hint=f"e.g. {key}=0.001")
    return value


def _parts(text: str, option: str) -> list[str]:
    """``text`` split at the commas outside quotes, each part's quotes removed (a value may hold ``,`` and ``=``)."""
    parts, current, quote = [], [], ""
    for ch in text:
        if quote:
            if ch == quote:
                quote = ""
            else:
                current.append(ch)
        elif ch in "\"'":
            quote = ch
        elif ch == ",":
            parts.append("".join(current))
            current = []
        else:
            current.append(ch)
    if quote:
        raise DepthError(f"unclosed {quote} quote in {text!r}", field=option, hint="close the quote around the value")
    return [*parts, "".join(current)]


def parse_source(text: str, *, option: str = "--recording") -> RecordingSource:
    """``SRC`` (module docstring) as a :class:`RecordingSource`; DepthError naming ``option`` when malformed."""
    if "=" not in text or Path(text).exists():  # an existing path is that path, whatever it holds
        folder = Path(text)
        if folder.is_dir() and (folder / "left").is_dir() and (folder / "depth").is_dir():
            return check_source(RecordingSource(folder=text, left=str(folder / "left"), depth=str(folder / "depth")),
                                option=option)
        return check_source(RecordingSource(folder=text), option=option)
    values: dict[str, str | float] = {}
    for part in _parts(text, option):
        key, sep, value = part.partition("=")
        key = key.strip()
        if not sep or key not in _KEYS or not value:
            raise DepthError(f"cannot read {part!r}: expected key=value with a key of {', '.join(_KEYS)}",
                             field=option, hint="e.g. left=L/,right=R/ or bag=run.bag,left-topic=/l,depth-topic=/d; "
                             "quote a value holding commas: left=\"a,b/\"")
        values[_KEYS[key]] = _number(key, value, option) if key in ("max-dt", "depth-scale") else value
    return check_source(RecordingSource(**values), option=option)  # type: ignore[arg-type]


def check_source(source: RecordingSource, *, option: str, need_left: bool = True) -> RecordingSource:
    """``source`` when it names exactly one depth source and what that needs (left images unless ``need_left`` is
    False: device depth of a flat wall); DepthError naming ``option``."""
    if source.recording is not None:
        source.recording.check(error=DepthError)
        return source
    if source.folder is not None and source.left is None:
        if not Path(source.folder).is_dir():
            raise DepthError("recording folder not found", path=source.folder, field=option,
                             hint="pass a folder with left/ and right/ (or left/ and depth/) images, or key=value,...")
        return source
    stereo = source.right is not None or source.right_topic is not None
    device = source.depth is not None or source.depth_topic is not None
    if stereo == device:
        raise DepthError("give exactly one depth source", field=option,
                         hint="right=... (stereo through the pipeline) or depth=... (device depth)")
    if source.bag is None and (source.left_topic or source.right_topic or source.depth_topic):
        raise DepthError("topics need a bag", field=option, hint="add bag=BAG")
    if source.bag is not None and not source.left_topic:
        raise DepthError("a bag needs left-topic", field=option, hint="e.g. left-topic=/camera/infra1/image_rect_raw")
    if source.bag is None and source.left is None and (need_left or stereo):
        raise DepthError("missing left images", field=option, hint="add left=DIR|GLOB")
    if stereo:
        refuse_same_sides(source.left_topic, source.right_topic, field=option, topics=True, path=source.bag,
                          error=DepthError)
        refuse_same_sides(source.left, source.right, field=option, error=DepthError)
    return source


@dataclass
class OpenedSource:
    """An opened recording: its views (read lazily), their count when known, ``f B`` (px m) of the depth's grid,
    a description, the matcher's visible depth range (stereo) and the rectification rotation ``R1`` (3x3) that
    takes the left camera's frame to the rectified one the stereo views are in (None for device depth)."""

    views: Iterator[DepthView]
    total: int | None
    fb_px_m: float
    description: str
    visible_m: tuple[float, float] | None
    R1: NDArray[np.float64] | None


def stereo_spec(source: RecordingSource) -> RecordingSpec:
    """The stereo pairs of ``source`` as a :class:`~s2r.recordings.RecordingSpec` (folder, globs or bag)."""
    if source.recording is not None:
        return source.recording
    if source.bag is not None:
        return RecordingSpec(bag=Path(source.bag), left_topic=source.left_topic, right_topic=source.right_topic,
                             max_dt_s=source.max_dt_s)
    if source.left is None:
        return RecordingSpec(folder=Path(str(source.folder)))
    return RecordingSpec(left_glob=source.left, right_glob=source.right)


def open_source(profile: StereoProfile, source: RecordingSource, *, preset: str = "profile",
                num_disparities: int | None = None) -> OpenedSource:
    """Open ``source`` for ``profile`` (see the module docstring); nothing is read until the views are iterated,
    except the folder listings (bad paths fail here)."""
    from s2r.depth.pipeline import StereoPipeline
    from s2r.quality import views as v
    from s2r.quality.inputs import DEPTH_SUFFIXES, IMAGE_SUFFIXES, FramePaths, list_files, pair_files

    if source.stereo:
        pipe = StereoPipeline(profile, preset=preset, num_disparities=num_disparities)
        R1 = np.asarray(pipe.rectification.R1, np.float64)
        fb, visible = v.stereo_fb(pipe), v.stereo_visible_m(pipe)
        sizes = ((profile.left.width_px, profile.left.height_px), (profile.right.width_px, profile.right.height_px))
        recording = open_recording(stereo_spec(source), expected_size=sizes, error=DepthError)
        total = len(recording) if isinstance(recording, Sized) else None
        kind = "from bag" if source.bag is not None else ""
        return OpenedSource(v.frame_views(pipe, recording), total, fb,
                            " ".join(w for w in ("stereo", kind) if w) + f", preset {preset}", visible, R1)
    fb = v.device_fb(profile)
    if source.bag is not None:
        views = v.bag_device_views(profile, Path(source.bag), str(source.left_topic), str(source.depth_topic),
                                   max_dt_s=source.max_dt_s, depth_scale_m=source.depth_scale_m)
        return OpenedSource(views, None, fb, "device depth from bag", None, None)
    depth = list_files(str(source.depth), DEPTH_SUFFIXES, option="--depth")
    if source.left is None:  # flat wall without images
        device = [FramePaths(d, depth=d) for d in depth]
    else:
        device = pair_files(list_files(source.left, IMAGE_SUFFIXES, option="--left"), depth, kind="depth")
    return OpenedSource(v.device_views(profile, device, depth_scale_m=source.depth_scale_m), len(device), fb,
                        "device depth", None, None)
