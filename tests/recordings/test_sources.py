"""Every recording form yields the frames it holds, in order, named and stamped, thinned by every/max_frames, with
the declared size checked before decoding (videos made by OpenCV's writer and ffmpeg, bags by rosbags)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.errors import RecordingError
from s2r.recordings import RecordingSpec, open_recording
from tests.recordings.helpers import write_bag, write_cv, write_h264


def _flat_pairs(n: int, h: int = 48, w: int = 64) -> list[tuple[np.ndarray, np.ndarray]]:
    """Pair i: left flat grey 20 + 10 i, right flat grey 200 - 10 i (BGR)."""
    return [(np.full((h, w, 3), 20 + 10 * i, np.uint8), np.full((h, w, 3), 200 - 10 * i, np.uint8)) for i in range(n)]


def _folder(tmp_path: Path, n: int = 5) -> Path:
    for side in ("left", "right"):
        (tmp_path / side).mkdir(parents=True)
    for i, (a, b) in enumerate(_flat_pairs(n)):
        cv2.imwrite(str(tmp_path / "left" / f"{i:02d}.png"), a)
        cv2.imwrite(str(tmp_path / "right" / f"{i:02d}.png"), b)
    return tmp_path


def test_folder_and_two_folders_every_and_max_frames(tmp_path: Path) -> None:
    folder = _folder(tmp_path)
    src = open_recording(folder=folder, every=2, max_frames=2, grey=True, expected_size=(64, 48))
    frames = list(src.frames())
    assert [(f.index, f.name, f.stamp_ns) for f in frames] == [(0, "00", None), (2, "02", None)]
    assert frames[1].left.shape == (48, 64) and int(frames[1].left[0, 0]) == 40 and int(frames[1].right[0, 0]) == 180
    again = open_recording(left_glob=str(folder / "left"), right_glob=str(folder / "right"))  # --left DIR --right DIR
    assert [f.name for f in again.frames()] == ["00", "01", "02", "03", "04"]
    assert next(iter(again.frames())).left.shape == (48, 64, 3)


def test_header_size_refused_before_decoding(tmp_path: Path) -> None:
    folder = _folder(tmp_path, 2)
    big = np.zeros((4000, 4000), np.uint8)  # 16 MB of pixels in a few kB of PNG
    cv2.imwrite(str(folder / "left" / "01.png"), big)
    frames = open_recording(folder=folder, expected_size=(64, 48)).frames()
    next(frames)
    with pytest.raises(RecordingError, match=r"01\.png: image size: left image: the header declares 4000x4000 px"):
        next(frames)


@pytest.mark.parametrize(("layout", "codec"), [("sbs", "mjpg"), ("tb", "mp4v")])
def test_single_video_layouts(tmp_path: Path, layout: str, codec: str) -> None:
    axis = 1 if layout == "sbs" else 0
    suffix = ".avi" if codec == "mjpg" else ".mp4"
    video = write_cv(tmp_path / f"v{suffix}", [np.concatenate(p, axis=axis) for p in _flat_pairs(6)], codec=codec)
    src = open_recording(video=video, layout=layout, every=2, max_frames=2, expected_size=(64, 48), grey=True)
    frames = list(src.frames())
    start = video.stat().st_mtime_ns  # no --start-stamp: the file's modification time (never 0, ROS's "unset")
    assert [(f.index, f.name, f.stamp_ns) for f in frames] == [(0, "frame_000000", start),
                                                              (2, "frame_000002", start + 200_000_000)]
    assert frames[1].left.shape == frames[1].right.shape == (48, 64)
    assert abs(float(frames[1].left.mean()) - 40) < 3 and abs(float(frames[1].right.mean()) - 180) < 3


def test_two_h264_videos_pair_by_index(tmp_path: Path) -> None:
    pairs = _flat_pairs(5)
    left = write_h264(tmp_path / "l.mp4", [a for a, _ in pairs])
    right = write_h264(tmp_path / "r.mp4", [b for _, b in pairs])
    frames = list(open_recording(left_video=left, right_video=right, grey=True).frames())
    assert [f.index for f in frames] == [0, 1, 2, 3, 4]
    assert abs(float(frames[4].left.mean()) - 60) < 3 and abs(float(frames[4].right.mean()) - 160) < 3
    short = write_h264(tmp_path / "short.mp4", [b for _, b in pairs[:3]])
    with pytest.raises(RecordingError, match="the left video has 5 frames but the right one 3: they cannot be paired"):
        open_recording(left_video=left, right_video=short)


def test_video_size_checked_before_the_first_frame(tmp_path: Path) -> None:
    video = write_cv(tmp_path / "v.avi", [np.hstack(p) for p in _flat_pairs(2)])
    with pytest.raises(RecordingError, match="left image is 64x48 px but the profile's left camera is 640x480"):
        open_recording(video=video, layout="sbs", expected_size=(640, 480))


def test_truncated_empty_and_missing_videos(tmp_path: Path) -> None:
    whole = write_cv(tmp_path / "v.avi", [np.hstack(p) for p in _flat_pairs(12)]).read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(RecordingError, match=r"cut\.avi: --video: (the video ends after \d+ of the 12 frames it "
                                             r"declares: truncated|cannot open the video)"):
        list(open_recording(video=cut).frames())
    empty = tmp_path / "empty.avi"
    empty.write_bytes(b"")
    with pytest.raises(RecordingError, match="the video file is empty"):
        open_recording(video=empty)
    noframes = write_cv(tmp_path / "none.avi", [])
    with pytest.raises(RecordingError, match=r"empty|no frames|cannot open|no frame size"):
        list(open_recording(video=noframes).frames())
    with pytest.raises(RecordingError, match="video not found"):
        open_recording(video=tmp_path / "nope.mp4")
    with pytest.raises(RecordingError, match="not a regular file"):
        open_recording(video=tmp_path)


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_bag_frames_named_by_stamp(tmp_path: Path, kind: str) -> None:
    pairs = [(a[:, :, 0], b[:, :, 0]) for a, b in _flat_pairs(4)]
    bag = write_bag(tmp_path / ("b.bag" if kind == "ros1" else "b"), pairs, kind=kind)
    src = open_recording(bag=bag, left_topic="/l", right_topic="/r", every=2, expected_size=(64, 48))
    frames = list(src.frames())
    assert [(f.index, f.name, f.stamp_ns, f.frame_id) for f in frames] == [
        (0, "1000000000", 1_000_000_000, "cam_optical"), (2, "1200000000", 1_200_000_000, "cam_optical")]
    assert int(frames[1].left[0, 0]) == 40 and int(frames[1].right[0, 0]) == 180


def test_bag_sizes_refused_before_decoding(tmp_path: Path) -> None:
    png = cv2.imencode(".png", np.zeros((3000, 3000), np.uint8))[1].tobytes()
    bag = write_bag(tmp_path / "c.bag", [(png, png)] * 3)
    with pytest.raises(RecordingError, match="left image is 3000x3000 px but the profile's left camera is 848x480"):
        list(open_recording(bag=bag, left_topic="/l", right_topic="/r", expected_size=(848, 480)).frames())
    with pytest.raises(RecordingError, match="no image topic '/x' in the bag; its image topics: /l, /r"):
        open_recording(bag=bag, left_topic="/x", right_topic="/r")


def test_corrupt_and_cut_bags(tmp_path: Path) -> None:
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 8)
    with pytest.raises(RecordingError, match=r"junk\.bag: cannot read the bag"):
        open_recording(bag=junk, left_topic="/l", right_topic="/r")
    pairs = [(a[:, :, 0], b[:, :, 0]) for a, b in _flat_pairs(4)]
    whole = write_bag(tmp_path / "w.bag", pairs).read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(RecordingError, match=r"cut\.bag: cannot read the bag"):
        list(open_recording(bag=cut, left_topic="/l", right_topic="/r").frames())


def test_spec_needs_exactly_one_form() -> None:
    with pytest.raises(RecordingError, match="give one recording"):
        RecordingSpec().check()
    with pytest.raises(RecordingError, match="got folder, video"):
        RecordingSpec(folder=Path("."), video=Path("v.mp4")).check()
    with pytest.raises(RecordingError, match="--left-video and --right-video go together"):
        RecordingSpec(left_video=Path("l.mp4")).check()
    with pytest.raises(RecordingError, match="--every: must be at least 1"):
        RecordingSpec(folder=Path("."), every=0).check()


def test_truncated_streamable_mp4_stops_with_one_line(tmp_path: Path) -> None:
    """An H.264 .mp4 with its index first (``-movflags +faststart``, as streamed recordings are) opens when cut, and
    ends early: refused as truncated, not taken as a shorter recording."""

    rng = np.random.default_rng(3)  # noise: the frames' data, not the index, fill the file
    whole = write_h264(tmp_path / "w.mp4", [rng.integers(0, 255, (48, 128, 3), dtype=np.uint8) for _ in range(24)])
    fast = tmp_path / "fast.mp4"
    subprocess.run([shutil.which("ffmpeg") or "ffmpeg", "-y", "-loglevel", "error", "-i", str(whole), "-c", "copy",
                    "-movflags", "+faststart", str(fast)], check=True)
    data = fast.read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(data[: len(data) * 6 // 10])
    with pytest.raises(RecordingError, match=r"cut.mp4: --video: the video ends after \d+ of the 24 frames it "
                                             "declares: truncated"):
        list(open_recording(video=cut).frames())


def test_an_estimated_frame_count_is_no_truncation(tmp_path: Path) -> None:
    """Matroska has no frame index: OpenCV estimates the count from the duration (an audio track longer than the
    video inflates it). The frames that decode are the recording; only indexed containers are held to their count."""
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test-recordings installs it)")
    frames = [np.full((48, 128, 3), 40 * i, np.uint8) for i in range(5)]
    video = write_cv(tmp_path / "v.avi", frames)
    mkv = tmp_path / "v.mkv"
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-i", str(video), "-f", "lavfi", "-t", "3", "-i",
                    "anullsrc=r=8000:cl=mono", "-map", "0:v", "-map", "1:a", "-c:v", "copy", "-c:a", "pcm_s16le",
                    str(mkv)], check=True)
    cap = cv2.VideoCapture(str(mkv))
    declared = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    cap.release()
    got = list(open_recording(video=mkv, layout="sbs").frames())
    assert len(got) == 5, f"OpenCV declared {declared}"
