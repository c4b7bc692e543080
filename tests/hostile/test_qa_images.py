"""QA: images that do not fit the profile or each other. Every refusal names the image FILE (it used to say
only ``right:`` or ``image size:``), ``--resize`` refuses another aspect ratio (a crop, not a rescale: the
rescaled intrinsics gave silently wrong depth), and the output folder may not be an input folder."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main

PROFILE = "realsense_d435_848x480"


def _image(path: Path, width: int, height: int, seed: int = 0) -> Path:
    rng = np.random.default_rng(seed)
    cv2.imwrite(str(path), (rng.random((height, width)) * 255).astype(np.uint8))
    return path


def _last_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and "Warning" not in err
    return err.splitlines()[-1]


def test_left_right_size_mismatch_names_the_right_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left, right = _image(tmp_path / "l.png", 848, 480), _image(tmp_path / "r.png", 640, 360)
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "-o", str(tmp_path / "o")]) == 2
    assert _last_error(capsys).startswith(f"error: {right}: right: left image is 848x480 but right is 640x360")


def test_profile_size_mismatch_names_the_image(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left, right = _image(tmp_path / "l.png", 424, 240), _image(tmp_path / "r.png", 424, 240, 1)
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "-o", str(tmp_path / "o")]) == 2
    assert _last_error(capsys).startswith(f"error: {left}: image size: images are 424x240")


def test_resize_refuses_another_aspect_ratio(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left, right = _image(tmp_path / "l.png", 640, 480), _image(tmp_path / "r.png", 640, 480, 1)
    out = tmp_path / "o"
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "--resize", "-o", str(out)]) == 2
    err = _last_error(capsys)
    assert err.startswith(f"error: {left}: image size: ") and "aspect ratio" in err
    assert not out.exists()


def test_resize_same_aspect_ratio_scales_focal_length(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left, right = _image(tmp_path / "l.png", 424, 240), _image(tmp_path / "r.png", 424, 240, 1)
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "--resize", "-o", str(tmp_path / "o"),
                 "--json"]) == 0
    assert '"f_px": 212.0' in capsys.readouterr().out


def test_sequence_frame_of_another_size_names_the_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    (tmp_path / "L").mkdir()
    (tmp_path / "R").mkdir()
    _image(tmp_path / "L" / "0001.png", 848, 480)
    _image(tmp_path / "R" / "0001.png", 848, 480, 1)
    bad = _image(tmp_path / "L" / "0002.png", 424, 240)
    _image(tmp_path / "R" / "0002.png", 424, 240, 1)
    assert main(["depth", "--profile", PROFILE, "--left-dir", str(tmp_path / "L"), "--right-dir",
                 str(tmp_path / "R"), "-o", str(tmp_path / "o")]) == 2
    assert _last_error(capsys).startswith(f"error: {bad}: image size: ")


@pytest.mark.parametrize("side", ["L", "R"])
def test_sequence_output_into_an_input_folder_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                         side: str) -> None:
    for name in ("L", "R"):
        (tmp_path / name).mkdir()
        _image(tmp_path / name / "0001.png", 848, 480)
    args = ["depth", "--profile", PROFILE, "--left-dir", str(tmp_path / "L"), "--right-dir", str(tmp_path / "R"),
            "-o", str(tmp_path / side), "--force"]
    assert main(args) == 2
    assert "the output folder is an input folder" in _last_error(capsys)
    assert sorted(p.name for p in (tmp_path / side).iterdir()) == ["0001.png"]


@pytest.mark.parametrize(("extra", "words"), [
    (["--fov", "60"], "--fov: --fov sets the rectified field of fisheye"),  # was silently ignored on a pinhole
    (["--workers", "0"], "--workers: must be at least 1"),
])
def test_options_that_would_be_ignored_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   extra: list[str], words: str) -> None:
    left, right = _image(tmp_path / "l.png", 848, 480), _image(tmp_path / "r.png", 848, 480, 1)
    out = tmp_path / "o"
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "-o", str(out), *extra]) == 2
    assert words in _last_error(capsys)
    assert not out.exists()


def test_no_valid_depth_is_loudly_wrong(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two copies of one image (zero disparity everywhere, beyond max_depth_m): 0 % valid used to pass in
    silence; the depth files are still written, with a warning saying what to check."""
    left = _image(tmp_path / "l.png", 848, 480)
    right = tmp_path / "r.png"
    right.write_bytes(left.read_bytes())
    assert main(["depth", "--profile", PROFILE, str(left), str(right), "-o", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "warning: " in err and "only 0.0 % of the pixels have depth" in err
    assert (tmp_path / "o" / "depth.png").is_file()
