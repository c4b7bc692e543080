"""Reading image files through OpenCV in s2r's own words (the one place image files are decoded).

OpenCV's own log (``[ WARN:0@0.04] global grfmt_png.cpp ...``) is silenced when this module is imported, and
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

try:  # ISA-L's inflate: 4x zlib's on camera images (the PNG shortcut below); without it libpng decodes them
    from isal import isal_zlib as _inflate
except ImportError:  # pragma: no cover - a platform without an isal wheel
    _inflate = None  # type: ignore[assignment]

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


def silence_opencv_log() -> None:
    """Silence OpenCV's own logging (its C++ warnings and errors); s2r reports failures itself."""
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


#: Chunks a plain grey PNG may carry for :func:`_grey_png_rows`: the image's own and metadata libpng leaves
#: out of the pixels OpenCV returns (text, time, pixel size); any other takes libpng's path.
_SHORTCUT_CHUNKS = frozenset({b"IHDR", b"IDAT", b"IEND", b"tEXt", b"zTXt", b"iTXt", b"tIME", b"pHYs"})


def _grey_png_rows(data: bytes, chunks: Sequence[bytes]) -> NDArray[np.uint8] | None:
    """The (H, W) uint8 pixels of a plain grey PNG (:func:`_plain_grey_png`) decoded without libpng, or None to
    leave it to libpng: same pixels, half the time of a 1280x720 camera image (8 ms -> 4 ms).

    libpng's time goes to zlib's inflate (7 of 8 ms on a noisy image); ISA-L inflates the same stream 4x
    faster. Rows filtered None, Sub or Up (OpenCV's writer: Sub throughout) are undone with numpy (a running
    sum mod 256 along the row or down the column). Anything else goes to libpng, which decides as before: a
    malformed or interlaced header, Average or Paeth rows, another chunk, a critical chunk whose CRC does not
    match, a stream that is damaged, cut short, or inflates to more or fewer bytes than the rows need."""
    if _inflate is None or data[8:12] != b"\x00\x00\x00\x0d" or data[26:29] != b"\x00\x00\x00" \
            or not _SHORTCUT_CHUNKS.issuperset(chunks):  # IHDR of 13 bytes; deflate, adaptive filters, no interlace
        return None
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    if width == 0 or height == 0:
        return None
    view, parts, pos = memoryview(data), [], 8
    while True:
        length, kind = _CHUNK_HEADER.unpack_from(data, pos)
        end = pos + 8 + length
        if kind in (b"IHDR", b"IDAT", b"IEND") and _inflate.crc32(view[pos + 4:end]) != int.from_bytes(
                data[end:end + 4], "big"):
            return None
        if kind == b"IDAT":
            parts.append(view[pos + 8:end])
        if kind == b"IEND":
            break
        pos = end + 4
    stream, size = _inflate.decompressobj(), height * (width + 1)
    try:  # never more than the rows need, plus one byte to tell a stream that holds more (a bomb)
        raw = stream.decompress(b"".join(parts), size + 1)
    except Exception:  # isal_zlib.error: a damaged stream (libpng then reports it)
        return None
    if not stream.eof or stream.unused_data or stream.unconsumed_tail or len(raw) != size:
        return None
    return _unfilter(np.frombuffer(raw, np.uint8).reshape(height, width + 1))


def _unfilter(rows: NDArray[np.uint8]) -> NDArray[np.uint8] | None:
    """Pixels (H, W) of 8-bit one-channel PNG rows (H, 1 + W: each row's filter byte, then its filtered bytes);
    None when a row uses a filter other than None (0), Sub (1) or Up (2)."""
    kinds = rows[:, 0]
    if int(kinds.max(initial=0)) > 2:
        return None
    if bool(np.all(kinds == 1)):
        return _running_sums(rows[:, 1:])
    out = np.ascontiguousarray(rows[:, 1:])
    sub = kinds == 1
    out[sub] = _running_sums(out[sub])
    up = np.flatnonzero(kinds == 2)
    for run in np.split(up, np.flatnonzero(np.diff(up) != 1) + 1) if up.size else []:
        a, b = int(run[0]), int(run[-1]) + 1  # rows a..b-1 each add the (decoded) row above
        np.cumsum(out[a:b], axis=0, dtype=np.uint8, out=out[a:b])
        if a > 0:
            out[a:b] += out[a - 1]
    return out


def _running_sums(rows: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """Running sums mod 256 along each row of ``rows`` (H, W) uint8, exactly (PNG's Sub filter undone).

    From OpenCV's integral image (int32, vectorised: 0.8 ms for 1280x720 against numpy's cumsum's 2.9 ms):
    a row's running sum is the difference of two of its rows. Taken over bands of rows small enough that
    no sum reaches 2^31."""
    out = np.empty(rows.shape, np.uint8)
    band = max(1, (2**31 - 1) // (255 * max(rows.shape[1], 1)))
    for a in range(0, rows.shape[0], band):
        sums = cv2.integral(rows[a:a + band])
        np.subtract(sums[1:, 1:], sums[:-1, 1:], out=out[a:a + band], casting="unsafe")  # mod 256
    return out


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
            image = _grey_png_rows(data, chunks)
            if image is None:
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
