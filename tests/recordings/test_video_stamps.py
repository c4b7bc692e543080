"""Video frames are stamped with the video's start (``--start-stamp``, else the file's modification time) plus
their presentation time in the container, never from 0 (ROS reads a stamp of 0 as "unset").

Videos with uneven frame times are made by Debian's ffmpeg (skipped when absent); the depth bag is read back by
rosbags."""

from __future__ import annotations

import csv
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.errors import RecordingError
from s2r.recordings import open_recording
from tests.recordings.helpers import write_cv

#: Presentation times (ms) of the uneven video: 0, 20, 80, 180, 320 (t = 20 ms * N^2).
UNEVEN_MS = (0, 20, 80, 180, 320)
START = "2024-05-01T12:00:00Z"
START_NS = 1_714_564_800 * 10**9


def _uneven_h264(path: Path, frames: list[np.ndarray]) -> Path:
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test-recordings installs it)")
    h, w = frames[0].shape[:2]
    cmd = ["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "bgr24", "-s", f"{w}x{h}", "-r", "10",
           "-i", "-", "-vf", "settb=1/1000,setpts=N*N*20", "-fps_mode", "passthrough", "-enc_time_base", "1/1000",
           "-c:v", "libx264", "-pix_fmt", "yuv420p", str(path)]
    subprocess.run(cmd, input=b"".join(np.ascontiguousarray(f).tobytes() for f in frames), check=True)
    return path


def _sbs(n: int) -> list[np.ndarray]:
    return [np.hstack([np.full((48, 64, 3), 20 + 10 * i, np.uint8), np.full((48, 64, 3), 200 - 10 * i, np.uint8)])
            for i in range(n)]


def test_stamps_follow_the_container_times_from_the_start_given(tmp_path: Path) -> None:
    video = _uneven_h264(tmp_path / "uneven.mkv", _sbs(5))
    frames = list(open_recording(video=video, start_ns=START_NS).frames())
    assert [f.stamp_ns for f in frames] == [START_NS + ms * 10**6 for ms in UNEVEN_MS]
    mtime = video.stat().st_mtime_ns
    assert [f.stamp_ns for f in open_recording(video=video).frames()] == [mtime + ms * 10**6 for ms in UNEVEN_MS]


def test_two_videos_take_the_left_ones_times(tmp_path: Path) -> None:
    left = write_cv(tmp_path / "l.avi", [f[:, :64].copy() for f in _sbs(3)], fps=25.0)
    right = write_cv(tmp_path / "r.avi", [f[:, 64:].copy() for f in _sbs(3)], fps=25.0)
    frames = list(open_recording(left_video=left, right_video=right, start_ns=START_NS, every=2).frames())
    assert [f.stamp_ns for f in frames] == [START_NS, START_NS + 80_000_000]


def test_start_stamp_applies_to_videos_only(tmp_path: Path) -> None:
    (tmp_path / "left").mkdir()
    with pytest.raises(RecordingError, match="--start-stamp: applies to videos only"):
        open_recording(folder=tmp_path, start_ns=START_NS)


@pytest.mark.parametrize("bad", ["2024-05-01T12:00:00", "yesterday", "-5", "nan"])
def test_bad_start_stamps_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], bad: str) -> None:
    video = write_cv(tmp_path / "v.avi", _sbs(2))
    with pytest.raises(SystemExit) as stop:
        main(["depth", "realsense_d435_848x480", "--video", str(video), "-o", str(tmp_path / "o"),
              f"--start-stamp={bad}"])
    assert stop.value.code == 2 and "--start-stamp" in capsys.readouterr().err


def test_depth_bag_of_a_video_carries_the_start_stamp(tmp_path: Path) -> None:
    """The whole path: a rig's video through ``s2r depth --to ros2`` and ``--to files``, read back by rosbags."""
    from rosbags.highlevel import AnyReader

    from tests.depth.stream_inputs import known_frames, known_rig, write_profile

    rig, profile = known_rig()
    pairs = known_frames(rig, distances_m=(0.9, 1.3))
    sbs = [np.hstack([np.dstack([f.left] * 3), np.dstack([f.right] * 3)]) for f in pairs]
    video = write_cv(tmp_path / "rig.avi", sbs, fps=5.0)
    prof = write_profile(profile, tmp_path / "rig.yaml")
    bag = tmp_path / "bag"
    assert main(["-q", "depth", str(prof), "--video", str(video), "-o", str(bag), "--to", "ros2",
                 "--start-stamp", "1714564800.5"]) == 0
    expected = [START_NS + 500_000_000, START_NS + 700_000_000]
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/stereo/depth/image_rect"]
        stamps = [(t, reader.deserialize(raw, c.msgtype).header.stamp) for c, t, raw in reader.messages(conns)]
    assert [t for t, _ in stamps] == expected
    assert [s.sec * 10**9 + s.nanosec for _, s in stamps] == expected
    files = tmp_path / "files"
    assert main(["-q", "depth", str(prof), "--video", str(video), "-o", str(files)]) == 0
    rows = list(csv.DictReader((files / "frames.csv").open()))
    mtime = video.stat().st_mtime_ns
    assert [int(r["stamp_ns"]) for r in rows] == [mtime, mtime + 200_000_000]


def test_summary_says_when_video_stamps_come_from_the_file_time(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """Without --start-stamp the absolute times are the file's modification time: the summary says 'file time'
    and a warning names --start-stamp; with it they are 'recorded'. (An MJPG AVI made by OpenCV: no ffmpeg.)"""
    import json

    from tests.depth.stream_inputs import known_frames, known_rig, write_profile

    rig, profile = known_rig()
    pairs = known_frames(rig, distances_m=(1.1,))
    video = write_cv(tmp_path / "rig.avi", [np.hstack([np.dstack([f.left] * 3), np.dstack([f.right] * 3)])
                                            for f in pairs], fps=5.0)
    prof = write_profile(profile, tmp_path / "rig.yaml")
    assert main(["depth", str(prof), "--video", str(video), "-o", str(tmp_path / "a"), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["stamps"] == "file time"
    assert "modification time" in err and "--start-stamp" in err
    assert main(["depth", str(prof), "--video", str(video), "-o", str(tmp_path / "b"), "--json",
                 "--start-stamp", START]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["stamps"] == "recorded"
    assert "modification time" not in err


def test_frames_csv_says_per_row_where_the_stamps_come_from(tmp_path: Path) -> None:
    """frames.csv's stamp_source agrees with the summary: 'file time' for a video without --start-stamp (stamped
    from its modification time), 'recorded' with it, 'synthesized' for still files (the column names unchanged)."""
    from s2r.depth.writers.files import INDEX_COLUMNS
    from tests.depth.stream_inputs import known_frames, known_rig, write_folder, write_profile

    rig, profile = known_rig()
    pairs = known_frames(rig, distances_m=(1.1, 1.3))
    video = write_cv(tmp_path / "rig.avi", [np.hstack([np.dstack([f.left] * 3), np.dstack([f.right] * 3)])
                                            for f in pairs], fps=5.0)
    prof = write_profile(profile, tmp_path / "rig.yaml")
    write_folder(pairs, tmp_path / "stills")
    runs = {"file time": ["--video", str(video)], "recorded": ["--video", str(video), "--start-stamp", START],
            "synthesized": [str(tmp_path / "stills")]}
    for expected, given in runs.items():
        out = tmp_path / expected.replace(" ", "_")
        assert main(["-q", "depth", str(prof), *given, "-o", str(out)]) == 0
        with (out / "frames.csv").open() as handle:
            table = csv.DictReader(handle)
            rows = list(table)
        assert tuple(table.fieldnames or ()) == INDEX_COLUMNS
        assert [r["stamp_source"] for r in rows] == [expected] * 2
