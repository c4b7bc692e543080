"""The files of a ROS bag, checked before rosbags opens them: the regular-file rule, no link out of the folder.

A ROS 1 bag is one ``.bag`` file; a ROS 2 bag is a folder whose ``metadata.yaml`` lists its storage files
(``.db3`` / ``.mcap``, opened by rosbags by name inside the folder). Each of these must be a regular file (a
FIFO would block rosbags for good, a device never ends) and, inside a folder, must not be a symbolic link
leading out of it. Only these files are hashed for the profile's provenance, never anything else that lies
in the folder.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path, PurePath
from typing import Any

from s2r.errors import S2RError
from s2r.fileio import MAX_TEXT_BYTES, NotARegularFile, protect_read_files, read_regular_file
from s2r.safeparse import parse_yaml

__all__ = ["bag_storage_files"]

_HINT = "pass a ROS 1 .bag file or a ROS 2 bag folder (metadata.yaml with .db3 or .mcap files)"


def _regular(path: Path, *, folder: Path | None, error: type[S2RError]) -> Path:
    """``path`` when it is a regular file (inside ``folder`` without leaving it through a link)."""
    try:
        link = os.lstat(path)
        info = os.stat(path)
    except FileNotFoundError:
        raise error("bag file not found", path=path, hint=_HINT) from None
    except OSError as exc:
        raise error(f"cannot read the bag: {exc.strerror}", path=path, hint=_HINT) from None
    if folder is not None and stat.S_ISLNK(link.st_mode):
        target = Path(os.path.realpath(path))
        if not target.is_relative_to(Path(os.path.realpath(folder))):
            raise error("is a symbolic link leading out of the bag folder; s2r does not follow it", path=path,
                        hint="copy the file into the bag folder")
    if stat.S_ISDIR(info.st_mode) and folder is not None:
        raise error("is a folder where a bag storage file belongs", path=path, hint=_HINT)
    if not stat.S_ISREG(info.st_mode) and not stat.S_ISDIR(info.st_mode):
        raise error("not a regular file (a device, FIFO or socket): s2r reads files only", path=path, hint=_HINT)
    return path


def _listed(metadata: Path, error: type[S2RError]) -> list[str]:
    """The storage file names ``metadata.yaml`` lists (``rosbag2_bagfile_information.relative_file_paths``)."""
    try:
        text = read_regular_file(metadata, limit=MAX_TEXT_BYTES).decode("utf-8")
    except NotARegularFile as exc:
        raise error(str(exc), path=metadata, hint=_HINT) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read the bag's metadata: {exc}", path=metadata, hint=_HINT) from None
    data: Any = parse_yaml(text, path=metadata, error=error)
    info = data.get("rosbag2_bagfile_information") if isinstance(data, dict) else None
    paths = info.get("relative_file_paths") if isinstance(info, dict) else None
    if not isinstance(paths, list) or not paths or not all(isinstance(p, str) and p for p in paths):
        raise error("no storage files listed", path=metadata, field="rosbag2_bagfile_information.relative_file_paths",
                    hint=_HINT)
    return [PurePath(p).name for p in paths]  # rosbags opens each by its name inside the folder


def bag_storage_files(bag: Path, *, error: type[S2RError]) -> list[Path]:
    """The files rosbags will read for ``bag``, each checked (see the module docstring); ``error`` otherwise.

    A ``.bag`` file: itself. A folder: its ``metadata.yaml`` and the storage files it lists, in that order. Each
    is an input of the running command (:func:`s2r.fileio.protect_read_files`).
    """
    info = _regular(bag, folder=None, error=error)
    files = [bag]
    if info.is_dir():
        metadata = _regular(bag / "metadata.yaml", folder=bag, error=error)
        files = [metadata, *(_regular(bag / name, folder=bag, error=error) for name in _listed(metadata, error))]
    protect_read_files(files)  # inputs of the running command: no output may be one of them
    return files
