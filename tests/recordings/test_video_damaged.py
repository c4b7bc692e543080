"""A damaged H.264 stream gives s2r's one-line error and nothing else on stderr: FFmpeg's own lines ("[h264 @
0x...] error while decoding MB ...", printed by its decoder threads) are silenced through OpenCV's
``OPENCV_FFMPEG_LOGLEVEL``. The video is made by Debian's ffmpeg (skipped when absent) and damaged here; s2r runs
in its own process so its real file descriptor 2 is what is checked."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PROFILE = "realsense_d435_848x480"


def _damaged_h264(folder: Path, *, cut: bool) -> Path:
    """12 frames of noise (1696x480, the profile's pair side by side), bits flipped from a quarter to half the
    file; ``cut``: then cut at 60 % (the moov atom is at the front, so the video opens and ends early)."""
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test-recordings installs it)")
    rng = np.random.default_rng(1)
    frames = [rng.integers(0, 255, (480, 1696, 3), np.uint8) for _ in range(12)]
    whole = folder / "whole.mp4"
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "bgr24", "-s", "1696x480",
                    "-r", "10", "-i", "-", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-movflags", "+faststart",
                    str(whole)], input=b"".join(f.tobytes() for f in frames), check=True)
    data = bytearray(whole.read_bytes())
    for k in range(len(data) // 4, len(data) // 2, 997):
        data[k] ^= 0xFF
    damaged = folder / ("cut.mp4" if cut else "flipped.mp4")
    damaged.write_bytes(bytes(data[: int(len(data) * 0.6)] if cut else data))
    return damaged


def _s2r(*args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENCV_")}
    return subprocess.run([sys.executable, "-m", "s2r", *args], capture_output=True, text=True, env=env, timeout=600,
                          check=False)


def test_damaged_and_cut_h264_is_one_line_of_s2r(tmp_path: Path) -> None:
    video = _damaged_h264(tmp_path, cut=True)
    for _ in range(3):  # FFmpeg's threads print when they get to it: one run could miss them
        run = _s2r("depth", PROFILE, "--video", str(video), "-o", str(tmp_path / "out"), "-q")
        assert run.returncode == 2
        assert run.stderr.splitlines() == [f"error: {video}: --video: the video ends after 5 of the 12 frames it "
                                           "declares: truncated (copy the whole file again)"]
        assert not (tmp_path / "out").exists()


def test_ffmpeg_is_silent_once_s2r_reads_videos(tmp_path: Path) -> None:
    """Deterministic: OpenCV decodes the damaged video straight after s2r's video reader was imported, with no
    stderr redirection around the calls; FFmpeg would print its decoding errors there."""
    video = _damaged_h264(tmp_path, cut=False)
    script = ("import cv2, s2r.recordings.video\n"
              f"cap = cv2.VideoCapture({str(video)!r}, cv2.CAP_FFMPEG)\n"
              "while cap.grab():\n    cap.retrieve()\ncap.release()\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENCV_")}
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=600,
                         check=False)
    assert run.returncode == 0 and run.stderr == ""


def test_damaged_h264_that_still_decodes_prints_no_ffmpeg_lines(tmp_path: Path) -> None:
    video = _damaged_h264(tmp_path, cut=False)
    run = _s2r("depth", PROFILE, "--video", str(video), "-o", str(tmp_path / "out"), "-q", "--max-frames", "6")
    assert run.returncode == 0, run.stderr
    assert "h264" not in run.stderr and "error while decoding" not in run.stderr
