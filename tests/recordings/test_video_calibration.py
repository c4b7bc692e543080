"""Calibration from a video of a board session equals the stills' within sigma: the shared OpenCV set (13 pairs) as a
side-by-side MJPG video (OpenCV's writer) and as two H.264 files (Debian's ffmpeg), each still held for 3 frames and
one blurred frame among them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from s2r.calib import calibrate_stereo, find_stereo_pairs
from s2r.calib.solve.pipelines.stereo_stream import calibrate_stereo_stream
from s2r.cli import main
from s2r.recordings import open_recording
from tests.recordings.helpers import OPENCV_SET, stills, write_cv, write_h264

HOLD = 3


def _session() -> list[tuple[np.ndarray, np.ndarray]]:
    """Each still pair held for HOLD frames; frame 4 a Gaussian blur (sigma 3 px) of the first pair."""
    frames = [pair for pair in stills() for _ in range(HOLD)]
    a, b = frames[0]
    frames.insert(4, (cv2.GaussianBlur(a, (0, 0), 3), cv2.GaussianBlur(b, (0, 0), 3)))
    return frames


@pytest.fixture(scope="module")
def reference() -> Any:
    pairs = find_stereo_pairs(OPENCV_SET) if OPENCV_SET.is_dir() else pytest.skip("no shared OpenCV set")
    return calibrate_stereo(pairs.left, pairs.right, pattern=(9, 6), square_m=0.025, jobs=1, compare=False)


def _assert_within_sigma(result: Any, reference: Any) -> None:
    got, ref = result.figures(), reference.figures()
    for side in ("left", "right"):
        for name in ("fx_px", "fy_px", "cx_px", "cy_px"):
            assert abs(got[side][name] - ref[side][name]) < 0.25 * ref[side]["std"][name], (side, name)  # 0.07 seen
    assert abs(got["baseline_m"] - ref["baseline_m"]) < 0.25 * ref["baseline_std_m"]
    frames = result.frames
    assert frames["read"] == 13 * HOLD + 1 and frames["views_used"] == 13
    assert frames["not_kept"] == {"blurred": 1, "repeat": 13 * (HOLD - 1)}


def test_sbs_mjpg_video_equals_the_stills(tmp_path: Path, reference: Any) -> None:
    video = write_cv(tmp_path / "sbs.avi", [np.hstack(p) for p in _session()])
    source = open_recording(video=video, layout="sbs", grey=True, expected_size=(640, 480))
    _assert_within_sigma(calibrate_stereo_stream(source, pattern=(9, 6), square_m=0.025, jobs=1), reference)


def test_two_h264_videos_equal_the_stills(tmp_path: Path, reference: Any) -> None:
    session = _session()
    left = write_h264(tmp_path / "left.mp4", [a for a, _ in session])
    right = write_h264(tmp_path / "right.mp4", [b for _, b in session])
    source = open_recording(left_video=left, right_video=right, grey=True)
    _assert_within_sigma(calibrate_stereo_stream(source, pattern=(9, 6), square_m=0.025, jobs=1), reference)


def test_cli_calibrate_video_summary_and_bad_video(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = write_cv(tmp_path / "sbs.avi", [np.hstack(p) for p in _session()])
    out = tmp_path / "rig.yaml"
    assert main(["calibrate", "--video", str(video), "--pattern", "9x6", "--square", "0.025", "-o", str(out),
                 "--jobs", "1", "--no-cache"]) == 0
    text = capsys.readouterr().out
    assert "frames: 40 read, 13 used as views; not kept: 1 blurred, 26 repeat" in text
    assert "skipped frame_000004: blurred: variance of the Laplacian" in text
    cut = tmp_path / "cut.avi"
    cut.write_bytes(video.read_bytes()[:5000])
    assert main(["calibrate", "--video", str(cut), "--pattern", "9x6", "--square", "0.025", "-o",
                 str(tmp_path / "x.yaml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "cut.avi" in err[0]
    assert not (tmp_path / "x.yaml").exists()
