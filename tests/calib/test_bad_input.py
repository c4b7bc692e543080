"""Bad input to `s2r calibrate`: each case is skipped and listed, or fails with a one-line error (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.profile import StereoProfile
from tests.calib.conftest import copy_pairs


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["calibrate", "--pattern", "9x6", "--square", "0.025", *args, "--jobs", "1"])
    out, err = capsys.readouterr()
    return code, out, err


def _blank(path: Path) -> None:
    cv2.imwrite(str(path), np.full((480, 640), 128, np.uint8))


def test_corrupt_and_empty_files_are_skipped_and_listed(small_set: Path, tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    (small_set / "left" / "03.png").write_bytes(b"this is not a PNG file")
    (small_set / "right" / "05.png").write_bytes(b"")
    code, out, _ = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"), "--json")
    assert code == 0
    dropped = {d["name"]: d["reason"] for d in json.loads(out)["dropped"]}
    assert dropped["left/03.png"].startswith("unreadable") and dropped["right/05.png"].startswith("unreadable")
    assert json.loads(out)["quality"]["views_used"] <= 6


def test_images_without_board_are_listed(small_set: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _blank(small_set / "left" / "02.png")
    code, out, _ = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"), "--json")
    assert code == 0
    figures = json.loads(out)
    dropped = {d["name"]: d["reason"] for d in figures["dropped"]}
    assert dropped["left/02.png"] == ("no board: no 9x6 chessboard found; its partner right/02.png shows the board, "
                                      "so the pair is dropped")
    assert any("with a board found were dropped: left/02.png" in w for w in figures["warnings"])


def test_left_without_partner_is_named(small_set: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (small_set / "left" / "00.png").rename(small_set / "left" / "42.png")
    code, out, err = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"), "--json")
    assert code == 0
    assert "42.png has no partner image" in err and "00.png has no partner image" in err
    names = {d["name"] for d in json.loads(out)["dropped"]}
    assert {"left/42.png", "right/00.png"} <= names


def test_mixed_image_sizes_name_the_files(small_set: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    img = cv2.imread(str(small_set / "right" / "04.png"))
    cv2.imwrite(str(small_set / "right" / "04.png"), cv2.resize(img, (800, 600)))
    code, _, err = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"))
    assert code == 2
    assert err.count("\n") == 1 and "images differ in size" in err
    assert "left/00.png is 640x480" in err and "right/04.png is 800x600" in err
    assert not (tmp_path / "out.yaml").exists()


def test_too_few_pairs_says_how_many_and_why(small_set: Path, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    for i in range(3, 8):
        _blank(small_set / "right" / f"{i:02d}.png")
    (small_set / "left" / "02.png").write_bytes(b"")
    code, _, err = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"))
    assert code == 2 and err.count("\n") == 1
    assert "only 2 usable pairs found, at least 5 needed" in err
    assert "5 no board" in err and "1 unreadable" in err
    assert "check --pattern" in err  # most images showed no board: maybe the wrong inner-corner count


def test_wrong_pattern_names_the_board_size_that_is_there(synthetic_set: tuple[Path, StereoProfile],
                                                         tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = copy_pairs(synthetic_set[0], tmp_path / "set", range(3))  # the rendered board has 9x6 inner corners
    code = main(["calibrate", str(folder), "-o", str(tmp_path / "out.yaml"), "--pattern", "10x7", "--square", "0.025",
                 "--jobs", "2"])
    assert code == 2 and capsys.readouterr().err == (
        "error: --pattern: no 10x7 chessboard found; the images hold a 9x6 board (inner corners): use --pattern 9x6\n")


@pytest.mark.parametrize("pattern", ["9-6", "x6", "1x6"])
def test_unreadable_pattern_is_a_usage_error(small_set: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                             pattern: str) -> None:
    code, _, err = _run(capsys, str(small_set), "-o", str(tmp_path / "out.yaml"), "--pattern", pattern)
    assert code == 2 and "--pattern" in err and "COLSxROWS" in err


def test_existing_output_is_not_overwritten(small_set: Path, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out.yaml"
    out.write_text("keep me")
    code, _, err = _run(capsys, str(small_set), "-o", str(out))
    assert code == 2 and "--force" in err and out.read_text() == "keep me"


def test_missing_input_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, str(tmp_path / "nope"), "-o", str(tmp_path / "out.yaml"))
    assert code == 2 and "nope" in err and "input folder not found" in err


def test_glob_matching_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, "--left", str(tmp_path / "*.png"), "--right", str(tmp_path / "r*.png"),
                        "-o", str(tmp_path / "out.yaml"))
    assert code == 2 and "--left glob matches no image files" in err


@pytest.mark.parametrize(("args", "named"), [(["--pattern", "9x6"], "--square"), ([], "--square"),
                                             (["--square", "0.025"], "--pattern")])
def test_no_silent_board(small_set: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
                         named: str) -> None:
    out = tmp_path / "out.yaml"
    code = main(["calibrate", str(small_set), "-o", str(out), *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and named in err and len(err.splitlines()) == 1 and not out.exists()
