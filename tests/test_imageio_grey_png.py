"""The grey PNG shortcut (ISA-L inflate + numpy unfiltering) gives the pixels libpng gives, and leaves every file
it does not handle, or that is damaged, to libpng with the same outcome as before.

The PNGs are written here by a small encoder that shares no code with s2r (zlib + the PNG spec's filters,
chosen per row), so every filter kind and mix of them is exercised, not only OpenCV's writer's choice.
"""

from __future__ import annotations

import itertools
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.imageio import _grey_png_rows, _png_chunks, decode_image_file


def _filtered_row(kind: int, row: np.ndarray, above: np.ndarray) -> bytes:
    """One 8-bit grey row filtered as PNG's filter ``kind`` says (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth)."""
    x, b = row.astype(np.int32), above.astype(np.int32)
    a = np.concatenate([[0], x[:-1]])  # the pixel to the left (0 before the first)
    c = np.concatenate([[0], b[:-1]])  # the pixel above-left
    if kind == 0:
        pred = np.zeros_like(x)
    elif kind == 1:
        pred = a
    elif kind == 2:
        pred = b
    elif kind == 3:
        pred = (a + b) // 2
    else:
        p = a + b - c
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
        pred = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
    return bytes([kind]) + ((x - pred) % 256).astype(np.uint8).tobytes()


def _chunk(kind: bytes, payload: bytes) -> bytes:
    return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))


def _png(img: np.ndarray, kinds: list[int], *, extra: bytes = b"", idat_parts: int = 1) -> bytes:
    """An 8-bit grey PNG of ``img`` with row i filtered by ``kinds[i]``, the stream split over ``idat_parts``
    IDAT chunks, ``extra`` (whole chunks) after IHDR."""
    h, w = img.shape
    above = np.zeros(w, np.uint8)
    raw = b""
    for row, kind in zip(img, kinds, strict=True):
        raw += _filtered_row(kind, row, above)
        above = row
    stream = zlib.compress(raw, 6)
    cuts = np.linspace(0, len(stream), idat_parts + 1).astype(int)
    idat = b"".join(_chunk(b"IDAT", stream[a:b]) for a, b in itertools.pairwise(cuts))
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) + extra + idat
            + _chunk(b"IEND", b""))


def _image(seed: int, shape: tuple[int, int] = (23, 31)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, shape).astype(np.uint8)
    img[: shape[0] // 3] = (np.arange(shape[1]) * 9 % 256).astype(np.uint8)  # smooth rows too
    return img


@pytest.mark.parametrize("kinds", [
    "all None", "all Sub", "all Up", "Up first then mixed", "runs of Up between Sub and None", "alternating",
])
def test_none_sub_up_rows_decode_to_the_written_pixels(tmp_path: Path, kinds: str) -> None:
    img = _image(len(kinds))
    h = img.shape[0]
    rows = {"all None": [0] * h, "all Sub": [1] * h, "all Up": [2] * h,
            "Up first then mixed": [2, 2, 1, 0, 2, 1, 2, 2, 2] + [1] * (h - 9),
            "runs of Up between Sub and None": ([1, 2, 2, 2, 0, 2, 2] * 4)[:h],
            "alternating": [i % 3 for i in range(h)]}[kinds]
    data = _png(img, rows, idat_parts=3)
    chunks, problem = _png_chunks(data)
    assert problem == ""
    fast = _grey_png_rows(data, chunks)
    assert fast is not None and fast.dtype == np.uint8 and np.array_equal(fast, img)
    path = tmp_path / "x.png"
    path.write_bytes(data)
    got, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE)
    assert reason == "" and got is not None and np.array_equal(got, img)
    assert np.array_equal(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE), img)


@pytest.mark.parametrize("kinds", [[3], [4], [1, 3], [2, 4, 0]])
def test_average_and_paeth_rows_are_left_to_libpng(tmp_path: Path, kinds: list[int]) -> None:
    img = _image(7)
    rows = (kinds * img.shape[0])[: img.shape[0]]
    data = _png(img, rows)
    assert _grey_png_rows(data, _png_chunks(data)[0]) is None
    path = tmp_path / "x.png"
    path.write_bytes(data)
    got, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE)
    assert reason == "" and got is not None and np.array_equal(got, img)


def test_other_chunks_and_interlacing_are_left_to_libpng() -> None:
    img = _image(3)
    text = _chunk(b"tEXt", b"Software\x00test")
    data = _png(img, [1] * len(img), extra=text)
    assert _grey_png_rows(data, _png_chunks(data)[0]) is not None
    for extra in (_chunk(b"tRNS", b"\x00\x07"), _chunk(b"gAMA", struct.pack(">I", 45455)),
                  _chunk(b"sBIT", b"\x05")):
        data = _png(img, [1] * len(img), extra=extra)
        assert _grey_png_rows(data, _png_chunks(data)[0]) is None, extra[4:8]
    data = bytearray(_png(img, [1] * len(img)))
    data[28] = 1  # interlace method: Adam7
    data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])))
    assert _grey_png_rows(bytes(data), _png_chunks(bytes(data))[0]) is None


def _outcome(path: Path) -> tuple[str, bytes | None]:
    image, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE)
    return reason, None if image is None else image.tobytes()


def test_damaged_files_get_libpngs_outcome(tmp_path: Path) -> None:
    """A wrong CRC, a stream cut short (CRC recomputed), too much or too little data, and bytes after the
    stream's end: the shortcut declines each, so the result is libpng's (OpenCV's decode of the same bytes)."""
    img = _image(11, (40, 50))
    good = _png(img, [1] * 40)
    start = good.index(b"IDAT") - 4
    length = struct.unpack(">I", good[start:start + 4])[0]
    stream = good[start + 8:start + 8 + length]

    def with_idat(payload: bytes) -> bytes:
        return good[:start] + _chunk(b"IDAT", payload) + good[start + 12 + length:]

    raw_short = zlib.compress(zlib.decompress(stream)[:-50])
    raw_long = zlib.compress(zlib.decompress(stream) + b"\x01" * 51)
    bad_crc = bytearray(good)
    bad_crc[start + 20] ^= 0xFF
    cases = {"crc": bytes(bad_crc), "cut": with_idat(stream[: len(stream) // 2]), "short": with_idat(raw_short),
             "long": with_idat(raw_long), "trailing": with_idat(stream + b"\x00junk"),
             "bad filter": with_idat(zlib.compress(b"\x07" + zlib.decompress(stream)[1:]))}
    for name, data in cases.items():
        assert _grey_png_rows(data, _png_chunks(data)[0]) is None, name
        path = tmp_path / f"{name}.png"
        path.write_bytes(data)
        want = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
        reason, pixels = _outcome(path)
        assert (pixels is None) == (want is None), name
        if want is not None:
            assert pixels == want.tobytes(), name
        else:
            assert reason == "corrupt PNG image data", name


def test_running_sums_are_exact_where_the_integral_image_would_pass_2_to_the_31() -> None:
    """All-255 rows, 9000 x 1000: one integral image over them would sum to 2.3e9 (past int32); taken in
    bands it gives numpy's running sums mod 256 exactly."""
    from s2r.imageio import _running_sums

    rows = np.full((9000, 1000), 255, np.uint8)
    rows[::7, ::3] = 1
    assert np.array_equal(_running_sums(rows), np.cumsum(rows, axis=1, dtype=np.uint8))


def test_a_malformed_header_is_left_to_libpng() -> None:
    """An IHDR of the wrong length, a zero side, or an unknown compression or filter method: libpng refuses
    each, so the shortcut must not read pixels from them."""
    img = _image(5)
    good = _png(img, [1] * len(img))

    def with_ihdr(payload: bytes) -> bytes:
        ihdr = _chunk(b"IHDR", payload)
        return good[:8] + ihdr + good[33:]

    w, h = img.shape[1], img.shape[0]
    for name, payload in {"zero width": struct.pack(">IIBBBBB", 0, h, 8, 0, 0, 0, 0),
                          "compression 1": struct.pack(">IIBBBBB", w, h, 8, 0, 1, 0, 0),
                          "filter method 1": struct.pack(">IIBBBBB", w, h, 8, 0, 0, 1, 0),
                          "IHDR of 14 bytes": struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0) + b"\x00"}.items():
        data = with_ihdr(payload)
        assert _grey_png_rows(data, _png_chunks(data)[0]) is None, name
    assert _grey_png_rows(good, _png_chunks(good)[0]) is not None


def test_a_stream_inflating_past_the_rows_stops_at_them() -> None:
    """A 60 kB stream of 60 MB (a deflate bomb behind a 50x40 header): inflated no further than the rows need
    plus one byte, then left to libpng."""
    import tracemalloc

    img = _image(2, (40, 50))
    good = _png(img, [1] * 40)
    start = good.index(b"IDAT") - 4
    length = struct.unpack(">I", good[start:start + 4])[0]
    bomb = zlib.compress(b"\x01" + bytes(50) + b"\x00" * 60_000_000, 9)
    data = good[:start] + _chunk(b"IDAT", bomb) + good[start + 12 + length:]
    tracemalloc.start()
    try:
        assert _grey_png_rows(data, _png_chunks(data)[0]) is None
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5_000_000
