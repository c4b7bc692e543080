"""Depth files judged from their headers before any is decoded: each must have the profile's size.

``sensor apply`` used to decode whatever it was given: an 8192x8192 uint16 PNG (151 kB of zeros) took 2.4 GB
before anything compared it with the 848x480 camera the model is applied for. The size a file declares is read
from its first bytes (PNG IHDR, JPEG start-of-frame, TIFF's first image directory, a ``.npy`` header) and compared
with the profile's; every file is checked before the first is decoded and before an output folder is made.
"""

from __future__ import annotations

import io
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from s2r.errors import DepthError
from s2r.fileio import NotARegularFile, read_file_head
from s2r.imageio import declared_size

__all__ = ["check_depth_sizes", "declared_depth_size"]

#: Bytes read to judge a header (a .npy header is at most 64 KiB; a TIFF's first directory is usually near the
#: start: one further than this is read as "size unknown", decoded and checked after decoding).
_HEAD_BYTES = 1 << 16
_TIFF_WIDTH, _TIFF_LENGTH = 256, 257


def _tiff_size(head: bytes) -> tuple[int, int] | None:
    """(width, height) of a classic TIFF's first image directory, or None when not found in ``head``."""
    order = {b"II": "<", b"MM": ">"}.get(head[:2])
    if order is None or len(head) < 8 or struct.unpack(order + "H", head[2:4])[0] != 42:
        return None
    offset = struct.unpack(order + "I", head[4:8])[0]
    if offset + 2 > len(head):
        return None
    count = struct.unpack(order + "H", head[offset:offset + 2])[0]
    found: dict[int, int] = {}
    for k in range(count):
        entry = head[offset + 2 + 12 * k: offset + 14 + 12 * k]
        if len(entry) < 12:
            return None
        tag, kind = struct.unpack(order + "HH", entry[:4])
        if tag in (_TIFF_WIDTH, _TIFF_LENGTH):  # SHORT (type 3) or LONG
            found[tag] = struct.unpack(order + "H", entry[8:10])[0] if kind == 3 else \
                struct.unpack(order + "I", entry[8:12])[0]
    if len(found) < 2:
        return None
    return found[_TIFF_WIDTH], found[_TIFF_LENGTH]


def _npy_size(head: bytes) -> tuple[int, int] | None:
    """(width, height) of a 2-D ``.npy`` array from its header, None when the header says otherwise."""
    stream = io.BytesIO(head)
    try:
        version = np.lib.format.read_magic(stream)
        reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape = reader(stream)[0]
    except (ValueError, OSError, SyntaxError):
        return None  # read_npy says what is wrong with it
    return (int(shape[1]), int(shape[0])) if len(shape) == 2 else None


def declared_depth_size(path: Path) -> tuple[int, int] | None:
    """(width, height) the depth file ``path`` declares in its header, None when it cannot be told from it.

    Raises:
        DepthError: missing, a folder, or not a regular file.
    """
    try:
        head = read_file_head(path, _HEAD_BYTES)
    except FileNotFoundError:
        raise DepthError("file not found", path=path, hint="check the path") from None
    except (OSError, NotARegularFile) as exc:
        raise DepthError(f"cannot read: {getattr(exc, 'strerror', None) or exc}", path=path,
                         hint="pass depth files (uint16 PNG/TIFF or .npy)") from None
    if path.suffix.lower() == ".npy":
        return _npy_size(head)
    return declared_size(head) or _tiff_size(head)


def check_depth_sizes(paths: Sequence[Path], *, size: tuple[int, int]) -> None:
    """Refuse the first depth file whose header declares another size than ``size`` (width, height in px), or
    whose header does not tell its size (a truncated file, a TIFF whose first directory lies past 64 KiB).

    Raises:
        DepthError: naming the file, both sizes and what to do.
    """
    for path in paths:
        declared = declared_depth_size(path)
        if declared is None:
            raise DepthError("its header does not tell the image size (truncated, or not a PNG, TIFF or .npy "
                             "depth file)", path=path, hint="pass uint16 PNG/TIFF or float .npy depth")
        if declared != tuple(size):
            raise DepthError(f"declares {declared[0]}x{declared[1]} px, but the profile's camera is "
                             f"{size[0]}x{size[1]} px", path=path,
                             hint="pass depth of the profile's camera (or the profile of the camera that made it)")
