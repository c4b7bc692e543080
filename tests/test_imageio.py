"""Unreadable images are reported in s2r's words: no libpng/libjpeg/OpenCV lines on stderr (checked at the file
descriptor, in a fresh process), truncated files refused instead of decoded half grey."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.imageio import decode_image_file


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
