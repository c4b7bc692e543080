"""Unreadable images are reported in s2r's words: no libpng/libjpeg/OpenCV lines on stderr (checked at the file
descriptor, in a fresh process), truncated files refused instead of decoded half grey."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.imageio import _plain_grey_png, decode_image_file


def _bad_files(folder: Path) -> dict[str, Path]:
    img = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    png, jpg = cv2.imencode(".png", img)[1].tobytes(), cv2.imencode(".jpg", img)[1].tobytes()
    crc = bytearray(png)
    crc[60:80] = b"x" * 20  # inside the IDAT chunk: libpng reports a CRC error
    files = {"truncated.png": png[: len(png) // 2], "truncated.jpg": jpg[: len(jpg) // 2], "crc.png": bytes(crc),
             "garbage.png": b"\x89PNG\r\n\x1a\n" + b"junk" * 10, "text.png": b"hello", "empty.png": b"",
             "good.png": png}
    for name, data in files.items():
        (folder / name).write_bytes(data)
    return {name: folder / name for name in files}


def test_reasons_in_plain_words(tmp_path: Path) -> None:
    files = _bad_files(tmp_path)
    expected = {"truncated.png": "truncated PNG", "truncated.jpg": "truncated JPEG", "crc.png": "corrupt PNG",
                "garbage.png": "PNG", "text.png": "not an image", "empty.png": "empty"}
    for name, words in expected.items():
        image, reason = decode_image_file(files[name])
        assert image is None and words in reason, (name, reason)
    image, reason = decode_image_file(files["good.png"], cv2.IMREAD_GRAYSCALE)
    assert reason == "" and image is not None and image.shape == (120, 160)


@pytest.mark.parametrize("name", ["truncated.png", "crc.png", "garbage.png", "truncated.jpg"])
def test_depth_cli_stderr_is_one_s2r_line(tmp_path: Path, name: str) -> None:
    files = _bad_files(tmp_path)
    run = subprocess.run([sys.executable, "-m", "s2r", "depth", "--profile", "realsense_d435_848x480",
                          str(files[name]), str(files["good.png"]), "-o", str(tmp_path / "out")],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and name in lines[0], run.stderr
    assert "libpng" not in run.stderr and "JPEG file" not in run.stderr and "grfmt" not in run.stderr


def test_calibration_reports_a_corrupt_view_once(tmp_path: Path) -> None:
    from s2r.calib.detect.stream import DetectItem, _detect_item

    files = _bad_files(tmp_path)
    detection = _detect_item(DetectItem("crc", "0" * 64, files["crc.png"]), (9, 6))
    assert detection.status == "unreadable" and "corrupt PNG" in detection.detail


#: An EXIF block (big-endian TIFF) whose one tag is Orientation 6: the image is to be turned 90 degrees.
_EXIF_TURNED = b"MM\x00*\x00\x00\x00\x08\x00\x01" + b"\x01\x12\x00\x03\x00\x00\x00\x01\x00\x06\x00\x00" + b"\x00" * 4


def _png_with_chunk(png: bytes, kind: bytes, payload: bytes, at: int = 33) -> bytes:
    """``png`` with one more ancillary chunk at byte ``at`` (default right after IHDR; ``len - 12`` is just
    before IEND, after the image data), its CRC computed as the PNG spec says."""
    import zlib

    chunk = len(payload).to_bytes(4, "big") + kind + payload + zlib.crc32(kind + payload).to_bytes(4, "big")
    return png[:at] + chunk + png[at:]


def test_grey_decoding_equals_opencvs_for_every_png_kind(tmp_path: Path) -> None:
    """The 8-bit greyscale PNG shortcut gives IMREAD_GRAYSCALE's pixels; every other kind takes OpenCV's path."""
    rng = np.random.default_rng(3)
    grey = rng.integers(0, 256, (37, 53), np.uint8)
    colour = rng.integers(0, 256, (37, 53, 3), np.uint8)
    plain = bytes(cv2.imencode(".png", grey)[1])
    cases = {
        "grey8": plain,
        "grey8_trns": _png_with_chunk(plain, b"tRNS", (7).to_bytes(2, "big")),
        "grey8_exif": _png_with_chunk(plain, b"eXIf", b"MM\x00*\x00\x00\x00\x08\x00\x00"),
        "grey8_exif_turned": _png_with_chunk(plain, b"eXIf", _EXIF_TURNED),
        "grey8_exif_turned_after_data": _png_with_chunk(plain, b"eXIf", _EXIF_TURNED, at=len(plain) - 12),
        "grey16": bytes(cv2.imencode(".png", grey.astype(np.uint16) * 257)[1]),
        "colour": bytes(cv2.imencode(".png", colour)[1]),
        "colour_alpha": bytes(cv2.imencode(".png", np.dstack([colour, grey]))[1]),
    }
    for name, data in cases.items():
        path = tmp_path / f"{name}.png"
        path.write_bytes(data)
        got, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE)
        want = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
        assert reason == "" and got is not None, name
        assert got.dtype == np.uint8 and got.shape == want.shape, name
        assert np.array_equal(got, want), name
    assert _plain_grey_png(cases["grey8"]) and _plain_grey_png(cases["grey8_trns"])
    for name in ("grey8_exif", "grey8_exif_turned", "grey8_exif_turned_after_data", "grey16", "colour"):
        assert not _plain_grey_png(cases[name]), name
    assert not _plain_grey_png(plain[:-12]), "a chunk list without IEND is left to the decoder"
    assert not _plain_grey_png(plain[:33] + (2**31).to_bytes(4, "big") + plain[37:]), "a chunk past the end"


def test_png_chunks_past_the_end_are_refused_and_data_after_iend_is_not(tmp_path: Path) -> None:
    """An 83-byte PNG whose text chunk declares 4 GB made OpenCV allocate 4.1 GB and take 3-10 s to fail: it
    is refused from the chunk headers. Bytes after IEND (a trailer some tools append) are ignored, as OpenCV
    does (they used to read as "truncated")."""
    import struct
    import zlib

    def chunk(kind: bytes, payload: bytes, length: int | None = None) -> bytes:
        return (struct.pack(">I", len(payload) if length is None else length) + kind + payload
                + struct.pack(">I", zlib.crc32(kind + payload)))

    rows = b"".join(b"\x00" + bytes(range(i, i + 7)) for i in range(4))
    head = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 7, 4, 8, 0, 0, 0, 0))
    tail = chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    bomb = tmp_path / "bomb.png"
    bomb.write_bytes(head + chunk(b"tEXt", b"abc", 0xFFFFFFFF) + tail)
    image, reason = decode_image_file(bomb, cv2.IMREAD_GRAYSCALE)
    assert image is None and reason.startswith("truncated PNG (chunk 'tEXt' declares 4294967295 bytes")
    trailer = tmp_path / "trailer.png"
    trailer.write_bytes(head + tail + b"appended by some tool" * 4)
    image, reason = decode_image_file(trailer, cv2.IMREAD_GRAYSCALE)
    want = cv2.imdecode(np.frombuffer(trailer.read_bytes(), np.uint8), cv2.IMREAD_GRAYSCALE)
    assert reason == "" and image is not None and np.array_equal(image, want) and image[0, 6] == 6
