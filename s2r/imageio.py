"""Reading image files through OpenCV in s2r's own words (the one place image files are decoded).

OpenCV's own log (``[ WARN:0@0.04] global grfmt_png.cpp ...``) and FFmpeg's inside it (``[h264 @ 0x...] error
while decoding MB ...``) are silenced when this module is imported, and
the messages libpng and libjpeg print straight to the process's stderr ("libpng error: IDAT: CRC error",
"Premature end of JPEG file") are kept off the terminal while a file decodes. Instead the caller gets a
reason in plain words: not an image, truncated, or corrupt. A truncated JPEG that OpenCV would decode into
a half-grey image is refused.
"""

from __future__ import annotations

import contextlib
import os
import struct
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.fileio import NotARegularFile, read_regular_file
from s2r.limits import MAX_IMAGE_PX

__all__ = ["MAX_SIDE_PX", "declared_size", "decode_image_file", "native_stderr_silenced", "oversize_reason",
           "silence_opencv_log", "size_mismatch_reason"]

_PNG_MAGIC, _JPEG_MAGIC = b"\x89PNG\r\n\x1a\n", b"\xff\xd8"
#: A PNG chunk's length (big-endian, bytes of data) and type.
_CHUNK_HEADER = struct.Struct(">I4s")
#: Largest image side decoded (px): the profile's bound on camera sides. A PNG of a few hundred kB can
#: declare 30000x30000 px, which OpenCV would allocate (2.7 GB in colour) before finding the data short.
MAX_SIDE_PX = MAX_IMAGE_PX
#: Largest image file read (bytes): a 16384x16384 colour PNG of camera content is well below it.
MAX_IMAGE_FILE_BYTES = 512 << 20
_LOCK = threading.Lock()
_STATE = {"depth": 0, "saved_fd": -1}


#: FFmpeg's log level inside OpenCV (``AV_LOG_QUIET``), unless the user set ``OPENCV_FFMPEG_LOGLEVEL`` to debug.
_FFMPEG_QUIET = "-8"


def silence_opencv_log() -> None:
    """Silence OpenCV's own logging (its C++ warnings and errors) and FFmpeg's inside it; s2r reports failures
    itself, in one line.

    FFmpeg's lines ("[h264 @ 0x...] error while decoding MB ...") come from its decoder threads, also after a
    frame was returned, so redirecting stderr around each call cannot catch them. OpenCV reads
    ``OPENCV_FFMPEG_LOGLEVEL`` once, when its FFmpeg backend first opens a file: set here, at import, before any
    video is opened (a value the user set, to debug, is kept)."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", _FFMPEG_QUIET)
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)


silence_opencv_log()


@contextlib.contextmanager
def _native_stderr_silenced() -> Iterator[None]:
    """Point file descriptor 2 at /dev/null while native decoders run (nested and thread-safe, per process)."""
    with _LOCK:
        if _STATE["depth"] == 0:
            with contextlib.suppress(AttributeError, ValueError, OSError):
                sys.stderr.flush()
            _STATE["saved_fd"] = os.dup(2)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, 2)
            os.close(null)
        _STATE["depth"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _STATE["depth"] -= 1
            if _STATE["depth"] == 0:
                os.dup2(_STATE["saved_fd"], 2)
                os.close(_STATE["saved_fd"])


def _png_chunks(data: bytes) -> tuple[list[bytes], str]:
    """The chunk types of a PNG up to IEND, from their headers alone (a few dozen: microseconds), and why the
    chunk list is cut short or damaged ('' when it reaches IEND whole).

    A chunk declaring more bytes than the file holds is refused here: OpenCV would first allocate what it
    declares (4 GB for an 83-byte file) and take seconds to fail."""
    types: list[bytes] = []
    pos, end = 8, len(data)
    while pos + 12 <= end:
        length, kind = _CHUNK_HEADER.unpack_from(data, pos)
        if pos + 12 + length > end:
            return types, (f"truncated PNG (chunk {kind.decode('latin-1')!r} declares {length} bytes but "
                           f"{max(0, end - pos - 12)} remain: the file was cut short or is damaged)")
        types.append(kind)
        if kind == b"IEND":
            return types, ""
        pos += 12 + length
    return types, "truncated PNG (no IEND chunk at the end: the file was cut short)"


def _truncated_jpeg(data: bytes) -> str:
    """Why ``data`` is a truncated JPEG ('' when complete or another format; PNGs: :func:`_png_chunks`)."""
    if data.startswith(_JPEG_MAGIC) and b"\xff\xd9" not in data[-64:]:
        return "truncated JPEG (no end-of-image marker: the file was cut short)"
    return ""


def _plain_grey_png(data: bytes, chunks: Sequence[bytes] | None = None) -> bool:
    """Whether ``data`` is a whole 8-bit greyscale PNG (IHDR bit depth 8, colour type 0) without an eXIf chunk:
    its pixels decoded as they are equal ``IMREAD_GRAYSCALE``'s (which would also turn an image by its EXIF
    orientation), and cost ~7 % less to decode. Judged from the chunk headers (searching the whole file for
    ``eXIf`` cost 0.2 ms per 1280x720 image); a chunk list cut short or damaged is not plain. ``chunks``: the
    chunk types of this whole PNG when :func:`_png_chunks` already walked them."""
    if not (data.startswith(_PNG_MAGIC) and len(data) >= 26 and data[12:16] == b"IHDR" and data[24] == 8
            and data[25] == 0):
        return False
    if chunks is None:
        chunks, problem = _png_chunks(data)
        if problem:
            return False
    return b"eXIf" not in chunks


def declared_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) a PNG or JPEG header declares, before anything is decoded; None for other formats or a
    header too short to tell (OpenCV then judges the file)."""
    if data.startswith(_PNG_MAGIC) and len(data) >= 24 and data[12:16] == b"IHDR":
        return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    if not data.startswith(_JPEG_MAGIC):
        return None
    pos = 2
    while pos + 9 <= len(data):  # walk the marker segments up to the first start-of-frame (SOF0..SOF15)
        if data[pos] != 0xFF:
            return None
        marker = data[pos + 1]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
            pos += 2
            continue
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            return int.from_bytes(data[pos + 7:pos + 9], "big"), int.from_bytes(data[pos + 5:pos + 7], "big")
        pos += 2 + int.from_bytes(data[pos + 2:pos + 4], "big")
    return None


def oversize_reason(data: bytes) -> str:
    """Why the image's declared size is refused ('' when acceptable or unknown)."""
    size = declared_size(data)
    if size is None:
        return ""
    w, h = size
    if w > MAX_SIDE_PX or h > MAX_SIDE_PX:
        return (f"the header declares {w}x{h} px, larger than s2r reads ({MAX_SIDE_PX} px a side): a "
                "decompression bomb or a wrong file")
    return ""


def size_mismatch_reason(data: bytes, expected_size: tuple[int, int] | None) -> str:
    """Why the image's declared (PNG/JPEG header) size is not ``expected_size`` (width, height) px; '' when it is,
    when nothing is expected, or when the header does not tell (the decoded image is then checked instead)."""
    size = declared_size(data)
    if expected_size is None or size is None or tuple(size) == tuple(expected_size):
        return ""
    return f"the header declares {size[0]}x{size[1]} px but {expected_size[0]}x{expected_size[1]} px are expected"


def decode_image_file(path: str | Path, flags: int = cv2.IMREAD_UNCHANGED, *,
                      expected_size: tuple[int, int] | None = None) -> tuple[NDArray[Any] | None, str]:
    """``(image, "")`` for a readable image file, else ``(None, reason in plain words)``.

    ``flags`` as ``cv2.imdecode`` (``cv2.IMREAD_GRAYSCALE`` for (H, W) uint8). ``expected_size`` (width, height)
    px: a PNG/JPEG whose header declares another size is refused before anything is decoded (the caller checks
    the decoded size of other formats). Nothing is printed.
    """
    path = Path(path)
    try:
        data = read_regular_file(path, limit=MAX_IMAGE_FILE_BYTES)
    except NotARegularFile as exc:
        return None, str(exc)
    except OSError as exc:
        return None, f"cannot read the file ({exc.strerror or exc})"
    if not data:
        return None, "the file is empty"
    chunks, reason = _png_chunks(data) if data.startswith(_PNG_MAGIC) else ([], _truncated_jpeg(data))
    reason = reason or oversize_reason(data) or size_mismatch_reason(data, expected_size)
    if reason:
        return None, reason
    with _native_stderr_silenced():
        image: NDArray[Any] | None = None
        if flags == cv2.IMREAD_GRAYSCALE and _plain_grey_png(data, chunks):  # as is: skips a converter copy
            image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
            image = image if image is not None and image.ndim == 2 and image.dtype == np.uint8 else None
        if image is None:
            image = cv2.imdecode(np.frombuffer(data, np.uint8), flags)
    if image is None:
        kind = "PNG" if data.startswith(_PNG_MAGIC) else "JPEG" if data.startswith(_JPEG_MAGIC) else ""
        return None, f"corrupt {kind} image data" if kind else "not an image file OpenCV can read"
    return np.asarray(image), ""


#: The public name of the stderr guard: video decoders (FFmpeg through OpenCV) print to file descriptor 2 as well.
native_stderr_silenced = _native_stderr_silenced
