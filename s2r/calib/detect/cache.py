"""The corner cache's files are untrusted input: confined folder, bounded reads, validated entries.

A cache folder (``OUT.yaml.corners/``) that is a symbolic link or not a folder is not used at all: nothing is
read from it, written through it or deleted in it. An entry is read only when it is a regular file (not a
link, FIFO or device) of at most :data:`MAX_ENTRY_BYTES`; its JSON must have a mapping root, a known
``status``, an image size, and for a found board finite corners inside the image (one id each for a target,
the pattern's count for a chessboard). Anything else is discarded with a debug line and the image is
detected again. The stale-temporary clean-up deletes only s2r's own half-written entries
(``.s2r-tmp-<entry name>.<random>.tmp``), never another file of the folder.
"""

from __future__ import annotations

import json
import logging
import math
import os
import re
import stat
import time
from pathlib import Path
from typing import Any

from s2r.fileio import TEMP_PREFIX, NotARegularFile, read_regular_file

__all__ = ["MAX_ENTRY_BYTES", "folder_usable", "read_entry", "remove_stale_temporaries", "validate_entry"]

log = logging.getLogger(__name__)

#: Largest cache entry read (bytes): a 10 000-corner target entry is about 0.3 MB.
MAX_ENTRY_BYTES = 4 << 20
_MAX_CORNERS = 100_000
_MAX_SIDE_PX = 100_000
_STATUSES = ("ok", "no_board", "unreadable")
#: s2r's own half-written entry: the temporary of ``<sha256>-<board>-v<N>.json`` (and its publish backup).
_OWN_TEMPORARY = re.compile(re.escape(TEMP_PREFIX) + r"[0-9a-f]{64}-[A-Za-z0-9x]+-v\d+\.json\.[A-Za-z0-9_]+\.tmp"
                            r"(\.bak)?")


def folder_usable(folder: Path) -> bool:
    """Whether ``folder`` may hold the cache: missing (it will be created) or a real folder, not a link."""
    try:
        info = os.lstat(folder)
    except FileNotFoundError:
        return True
    except OSError:
        return False
    return stat.S_ISDIR(info.st_mode)


def _read_bounded(folder: Path, name: str) -> bytes:
    """The bytes of ``folder/name``, opened without following a link at either level and without blocking."""
    dir_fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_NOFOLLOW", 0))
    try:
        return read_regular_file(name, limit=MAX_ENTRY_BYTES, dir_fd=dir_fd, follow_links=False)
    finally:
        os.close(dir_fd)


def read_entry(folder: Path, name: str) -> Any | None:
    """The parsed JSON of the entry ``folder/name``; None (with a debug line) when it is missing, a link, not a
    regular file, too large or not JSON."""
    try:
        data = _read_bounded(folder, name)
        return json.loads(data.decode("utf-8"), parse_constant=lambda c: float("nan"))
    except FileNotFoundError:
        return None
    except (OSError, NotARegularFile, ValueError, RecursionError) as exc:
        log.debug("corner cache entry %s ignored (detected again): %s", folder / name, exc)
        return None


def _size(value: Any) -> tuple[int, int] | None:
    if value is None:
        return None
    if (not isinstance(value, list) or len(value) != 2 or not all(type(v) is int for v in value)
            or not all(0 < v <= _MAX_SIDE_PX for v in value)):
        raise ValueError("size is not [width, height] in pixels")
    return int(value[0]), int(value[1])


def _corners(value: Any, size: tuple[int, int] | None) -> list[tuple[float, float]] | None:
    if value is None:
        return None
    if not isinstance(value, list) or not 0 < len(value) <= _MAX_CORNERS or size is None:
        raise ValueError("corners are not a non-empty list of [x, y] (with the image size)")
    points = []
    for point in value:
        if (not isinstance(point, list) or len(point) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in point)):
            raise ValueError("a corner is not [x, y]")
        x, y = float(point[0]), float(point[1])
        if not (math.isfinite(x) and math.isfinite(y) and -1.0 <= x <= size[0] and -1.0 <= y <= size[1]):
            raise ValueError(f"corner ({x}, {y}) is not a finite point inside the {size[0]}x{size[1]} image")
        points.append((x, y))
    return points


def _ids(value: Any, count: int) -> list[int] | None:
    if value is None:
        return None
    if (not isinstance(value, list) or len(value) != count
            or not all(type(v) is int and 0 <= v < _MAX_CORNERS for v in value)):
        raise ValueError("ids are not one non-negative integer per corner")
    return [int(v) for v in value]


def validate_entry(data: Any, *, corner_count: int | None, with_ids: bool) -> dict[str, Any]:
    """The fields of a cache entry, checked: ``status``, ``size`` (w, h), ``corners`` (list of (x, y) px inside
    the image), ``ids``, ``detector``, ``detail``.

    ``corner_count``: the chessboard's corner count (None for a target, whose views may be cut);
    ``with_ids``: a target's entry must carry one id per corner.

    Raises:
        ValueError: the entry is malformed (the caller detects the image again).
    """
    if not isinstance(data, dict):
        raise ValueError("the root is not a mapping")
    status = data.get("status")
    if status not in _STATUSES:
        raise ValueError(f"status {status!r} is not one of {_STATUSES}")
    size = _size(data.get("size"))
    corners = _corners(data.get("corners"), size)
    if (status == "ok") != (corners is not None):
        raise ValueError("a found board needs corners, a missing one has none")
    if corners is not None and corner_count is not None and len(corners) != corner_count:
        raise ValueError(f"{len(corners)} corners, the pattern has {corner_count}")
    ids = _ids(data.get("ids"), len(corners or []))
    if with_ids and corners is not None and ids is None:
        raise ValueError("a target's entry needs one id per corner")
    detector, detail = data.get("detector", ""), data.get("detail", "")
    if not isinstance(detector, str) or not isinstance(detail, str) or len(detector) + len(detail) > 1000:
        raise ValueError("detector / detail are not short strings")
    return {"status": status, "size": size, "corners": corners, "ids": ids, "detector": detector, "detail": detail}


def remove_stale_temporaries(folder: Path, *, max_age_s: float) -> int:
    """Delete s2r's own half-written entries (``.s2r-tmp-...json....tmp``, regular files older than
    ``max_age_s``) left by a killed run; their count. Nothing else is touched, nothing in a linked folder."""
    if not folder_usable(folder):
        return 0
    removed = 0
    now = time.time()
    try:
        names = os.listdir(folder)
    except OSError:
        return 0
    for name in names:
        if not _OWN_TEMPORARY.fullmatch(name):
            continue
        path = folder / name
        try:
            info = os.lstat(path)
            if stat.S_ISREG(info.st_mode) and now - info.st_mtime > max_age_s:
                path.unlink()
                removed += 1
        except OSError:
            continue
    return removed
