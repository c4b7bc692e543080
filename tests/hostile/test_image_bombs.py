"""Decompression bombs: a small PNG or JPEG whose header declares 30000x30000 px is refused from its header, before
OpenCV allocates the 2.7 GB it would decode into (s2r/imageio.py), in every command that reads images."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.imageio import declared_size, decode_image_file


def _chunk(kind: bytes, payload: bytes) -> bytes:
    return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))


def png_bomb(path: Path, side: int = 30000) -> Path:
    """A 1-kB PNG whose IHDR declares ``side`` x ``side`` 8-bit RGB (its IDAT is one short zero row)."""
    header = struct.pack(">IIBBBBB", side, side, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header)
                     + _chunk(b"IDAT", zlib.compress(b"\0" * 1024)) + _chunk(b"IEND", b""))
    return path


def jpeg_bomb(path: Path, side: int = 30000) -> Path:
    """A real 64x48 JPEG with its start-of-frame dimensions patched to ``side`` x ``side``."""
    ok, buf = cv2.imencode(".jpg", np.full((48, 64, 3), 128, np.uint8))
    assert ok
    data = bytearray(buf.tobytes())
    sof = data.index(b"\xff\xc0")
    data[sof + 5:sof + 9] = struct.pack(">HH", side, side)
    path.write_bytes(bytes(data))
    return path


def test_declared_size_reads_png_and_jpeg_headers(tmp_path: Path) -> None:
    real = tmp_path / "real.png"
    cv2.imwrite(str(real), np.zeros((48, 64), np.uint8))
    cv2.imwrite(str(tmp_path / "real.jpg"), np.zeros((48, 64, 3), np.uint8))
    assert declared_size(real.read_bytes()) == (64, 48)
    assert declared_size((tmp_path / "real.jpg").read_bytes()) == (64, 48)
    assert declared_size(png_bomb(tmp_path / "b.png").read_bytes()) == (30000, 30000)
    assert declared_size(jpeg_bomb(tmp_path / "b.jpg").read_bytes()) == (30000, 30000)
    assert declared_size(b"BM....") is None


@pytest.mark.parametrize("make", [png_bomb, jpeg_bomb])
def test_bombs_are_refused_before_decoding(tmp_path: Path, make: object) -> None:
    path = make(tmp_path / ("bomb.png" if make is png_bomb else "bomb.jpg"))  # type: ignore[operator]
    image, reason = decode_image_file(path)
    assert image is None and "30000x30000" in reason and "16384" in reason


def test_bomb_in_a_calibration_folder_and_depth_input_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    right = tmp_path / "right.png"
    cv2.imwrite(str(right), np.zeros((480, 640), np.uint8))
    code = main(["depth", "--profile", "realsense_d435_848x480", str(png_bomb(tmp_path / "left.png")), str(right),
                 "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "30000x30000" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    # a calibration folder: the bomb is skipped as unreadable (never decoded); with no other view the run refuses
    folder = tmp_path / "calib"
    folder.mkdir()
    jpeg_bomb(folder / "left01.jpg")
    cv2.imwrite(str(folder / "right01.jpg"), np.zeros((480, 640), np.uint8))
    code = main(["calibrate", str(folder), "--pattern", "9x6", "--square", "0.025", "-o", str(tmp_path / "p.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "1 readable images" in err and "Traceback" not in err
