"""The recording argument group, defined once, in every command that reads frames; validate's SRC takes any path."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.cli._recording import add_recording_arguments, recording_from_args
from s2r.errors import DepthError
from s2r.quality.source import parse_source
from tests.recordings.helpers import write_bag, write_cv


def _err(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    return err[0]


def test_argument_group_opens_every_form(tmp_path: Path) -> None:
    parser = argparse.ArgumentParser()
    add_recording_arguments(parser)
    pairs = [(np.full((48, 64), 10 * i, np.uint8), np.full((48, 64), 100 + i, np.uint8)) for i in range(5)]
    bag = write_bag(tmp_path / "b.bag", pairs)
    args = parser.parse_args(["--bag", str(bag), "--left-topic", "/l", "--right-topic", "/r", "--every", "2",
                              "--max-frames", "2"])
    frames = list(recording_from_args(args, expected_size=(64, 48)).frames())
    assert [f.index for f in frames] == [0, 2] and int(frames[1].left[0, 0]) == 20
    video = write_cv(tmp_path / "v.avi", [np.zeros((96, 64, 3), np.uint8)] * 3)
    args = parser.parse_args(["--video", str(video), "--layout", "tb"])
    assert [f.left.shape for f in recording_from_args(args, grey=True).frames()] == [(48, 64)] * 3
    with pytest.raises(SystemExit):
        parser.parse_args(["--video", str(video), "--every", "0"])


@pytest.mark.parametrize("command", [["check", "realsense_d435_848x480"],
                                     ["calibrate", "--pattern", "9x6", "--square", "0.025", "-o", "x.yaml"],
                                     ["depth-quality", "realsense_d435_848x480", "--pattern", "9x6", "--square",
                                      "0.025"]])
def test_commands_take_one_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str]) -> None:
    video = write_cv(tmp_path / "v.avi", [np.zeros((48, 128, 3), np.uint8)] * 2)
    err = _err(capsys, [*command, "--video", str(video), "--left-video", str(video), "--right-video", str(video)])
    assert "give one recording" in err and "got video, videos" in err
    err = _err(capsys, [*command, "--left-video", str(video)])
    assert "--left-video and --right-video go together" in err


def test_depth_quality_and_sensor_fit_check_video_sizes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = write_cv(tmp_path / "v.avi", [np.zeros((48, 128, 3), np.uint8)] * 2)
    err = _err(capsys, ["depth-quality", "realsense_d435_848x480", "--video", str(video), "--pattern", "9x6",
                        "--square", "0.025"])
    assert "left image is 64x48 px but the profile's left camera is 848x480" in err
    err = _err(capsys, ["sensor", "fit", "--profile", "realsense_d435_848x480", "--video", str(video), "--pattern",
                        "9x6", "--square", "0.025", "-o", str(tmp_path / "s.yaml")])
    assert "left image is 64x48 px but the profile's left camera is 848x480" in err


def test_recording_src_accepts_any_existing_path(tmp_path: Path) -> None:
    """Issue 37's 'Also': a folder whose name holds '=', ',' or quotes is that folder, not a key=value list."""
    odd = tmp_path / "run=1,left='a\""
    (odd / "left").mkdir(parents=True)
    (odd / "right").mkdir()
    src = parse_source(str(odd))
    assert src.folder == str(odd) and src.stereo
    quoted = parse_source("left=\"L,=1/\",right='R/'")
    assert (quoted.left, quoted.right) == ("L,=1/", "R/")
    with pytest.raises(DepthError, match="unclosed \" quote"):
        parse_source('left="L/,right=R/')


def test_validate_takes_the_real_recording_once(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = write_cv(tmp_path / "v.avi", [np.zeros((48, 128, 3), np.uint8)] * 2)
    err = _err(capsys, ["validate", "gazebo_dual_camera", "realsense_d435_848x480", "--recording", str(tmp_path),
                        "--video", str(video)])
    assert "give the real recording once" in err
