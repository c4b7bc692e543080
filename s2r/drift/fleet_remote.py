"""A fleet robot's recording at a URL, read by the worker itself into a bounded local copy.

A folder URL is listed (its ``left/`` + ``right/`` or ``cam0/`` + ``cam1/`` subfolders, or its ``leftNN`` /
``rightNN`` files), paired by the same rules as a local folder on empty stand-ins of its files, and only the
pairs the check uses (``max_frames`` spread over the recording, as locally) are downloaded: a remote recording
gives the same frames, so the same verdict, as its local copy. A bag URL (one ``.bag`` / ``.db3`` / ``.mcap`` file)
is copied whole, up to :data:`MAX_BAG_BYTES`. Every file goes through :func:`s2r.recordings.remote.copy_to`
(schemes checked, no redirect followed, sizes bounded).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from urllib.parse import unquote, urlsplit

from s2r.calib import find_stereo_pairs
from s2r.calib.detect.inputs import CAMERA_SUBFOLDERS, IMAGE_SUFFIXES
from s2r.drift.source import StereoSource, spread
from s2r.errors import CalibrationError, CheckError
from s2r.imageio import MAX_IMAGE_FILE_BYTES
from s2r.recordings.remote import RemoteError, copy_to, join, list_folder

__all__ = ["MAX_BAG_BYTES", "RemoteRecording", "local_source"]

#: Largest bag file copied from a URL (bytes).
MAX_BAG_BYTES = 8 << 30
_FOLDERS = {name for pair in CAMERA_SUBFOLDERS for name in pair} | {"data"}


@dataclass(frozen=True)
class RemoteRecording:
    """A recording at ``url``: a folder of pairs, or (with both topics) one bag file."""

    url: str
    max_frames: int = 20
    left_topic: str | None = None
    right_topic: str | None = None

    @property
    def is_bag(self) -> bool:
        return self.left_topic is not None or self.right_topic is not None

    def describe(self) -> str:
        return f"{self.url} ({self.left_topic}, {self.right_topic})" if self.is_bag else self.url


def _mirror(url: str, into: Path, depth: int = 0) -> int:
    """Empty stand-ins in ``into`` for the image files of the folder at ``url`` and of its camera subfolders;
    how many files were listed."""
    count = 0
    for entry in list_folder(url):
        if entry.is_dir and depth < 2 and entry.name.lower() in _FOLDERS:
            (into / entry.name).mkdir()
            count += _mirror(join(url, entry.name), into / entry.name, depth + 1)
        elif not entry.is_dir and PurePosixPath(entry.name.lower()).suffix in IMAGE_SUFFIXES:
            (into / entry.name).touch()
            count += 1
    return count


def _relative(path: Path, root: Path) -> list[str]:
    return list(PurePosixPath(path.relative_to(root).as_posix()).parts)


def _fetch_folder(recording: RemoteRecording, into: Path) -> StereoSource:
    if not _mirror(recording.url, into):
        raise CheckError("no images listed at this URL", path=recording.url,
                         hint="give the URL of a folder with left/ and right/ (or leftNN/rightNN images)")
    try:
        pairs = find_stereo_pairs(into)
    except CalibrationError as exc:  # names the stand-in folder: name the URL instead
        raise CheckError(exc.message, path=recording.url, hint=exc.hint) from None
    keep = set()
    for k in spread(len(pairs.names), recording.max_frames):
        for local in (pairs.left[k], pairs.right[k]):
            copy_to(join(recording.url, *_relative(local, into)), local, limit=MAX_IMAGE_FILE_BYTES)
            keep.add(local)
    for stand_in in [p for p in into.rglob("*") if p.is_file() and p not in keep]:
        stand_in.unlink()
    return StereoSource(folder=into, max_frames=recording.max_frames)


def _fetch_bag(recording: RemoteRecording, into: Path) -> StereoSource:
    name = unquote(PurePosixPath(urlsplit(recording.url).path).name)
    if not name.lower().endswith((".bag", ".db3", ".mcap")):
        raise CheckError("a bag URL names one .bag, .db3 or .mcap file", path=recording.url,
                         hint="give the URL of the bag file itself")
    local = copy_to(recording.url, into / name, limit=MAX_BAG_BYTES)
    return StereoSource(bag=local, left_topic=recording.left_topic, right_topic=recording.right_topic,
                        max_frames=recording.max_frames)


def local_source(recording: RemoteRecording, into: Path) -> StereoSource:
    """The recording copied (the part the check reads) into the empty folder ``into``; the local source to read.

    Raises:
        CheckError: the URL is refused, missing, over a size limit, or holds no pairs (one line naming it).
    """
    try:
        return _fetch_bag(recording, into) if recording.is_bag else _fetch_folder(recording, into)
    except RemoteError as exc:
        raise CheckError(exc.message, path=exc.path, field=exc.field, hint=exc.hint) from None
