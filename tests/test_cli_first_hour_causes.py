"""The first hour, causes named right: each mistake a newcomer makes gets the one-line error that names it
(pairing, board size, missing options), checked through the CLI with the exact message."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from s2r.cli import main
from s2r.registry import load_profile

OPENCV_SET = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "opencv_stereo_chessboard"


def _board(path: Path, *, squares: tuple[int, int] = (10, 7), side_px: int = 36) -> None:
    """A flat chessboard of ``squares`` (cols, rows) drawn with numpy alone, on a white margin: its inner corners
    are (cols - 1) x (rows - 1)."""
    cols, rows = squares
    cells = (np.add.outer(np.arange(rows), np.arange(cols)) % 2 == 0).astype(np.uint8)
    board = np.kron(cells, np.ones((side_px, side_px), np.uint8)) * 200 + 30
    image = np.full((480, 640), 255, np.uint8)
    y0, x0 = (480 - board.shape[0]) // 2, (640 - board.shape[1]) // 2
    image[y0:y0 + board.shape[0], x0:x0 + board.shape[1]] = board
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)


def _error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err.strip()


def test_left_only_images_are_a_pairing_problem(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for i in (1, 2, 3):
        _board(tmp_path / "set" / f"left{i:02d}.png")
    assert _error(capsys, ["calibrate", str(tmp_path / "set"), "--pattern", "9x6", "--square", "0.025",
                           "-o", str(tmp_path / "out.yaml")]) == (
        f"error: {tmp_path / 'set'}: 3 left images and no right images: stereo calibration pairs each left image "
        "with a right one (add the right camera's images as right/ beside left/ or rightNN.png beside leftNN.png; "
        "for one camera: s2r calibrate --mono)")


def test_a_left_folder_without_its_right_folder_is_a_pairing_problem(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    for i in (1, 2):
        _board(tmp_path / "set" / "left" / f"{i:02d}.png")
    err = _error(capsys, ["calibrate", str(tmp_path / "set"), "--pattern", "9x6", "--square", "0.025",
                          "-o", str(tmp_path / "out.yaml")])
    assert err.startswith(f"error: {tmp_path / 'set' / 'left'}: 2 left images and no right images")


def test_folders_without_common_numbers_are_a_pairing_problem(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    for i in (1, 2, 3):
        _board(tmp_path / "set" / "left" / f"{i:02d}.png")
        _board(tmp_path / "set" / "right" / f"{10 + i}.png")
    assert _error(capsys, ["calibrate", str(tmp_path / "set"), "--pattern", "9x6", "--square", "0.025",
                           "-o", str(tmp_path / "out.yaml")]) == (
        f"error: {tmp_path / 'set' / 'left'}: no left image shares a pairing number with a right image (3 left: "
        "01.png .. 03.png; 3 right: 11.png .. 13.png) (a pair is two files with one number in their names, e.g. "
        "left/07.png and right/07.png)")


def test_two_images_with_one_pairing_number_are_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for name in ("left01.png", "left1.png", "right01.png"):
        _board(tmp_path / "set" / name)
    assert _error(capsys, ["calibrate", str(tmp_path / "set"), "--pattern", "9x6", "--square", "0.025",
                           "-o", str(tmp_path / "out.yaml")]) == (
        f"error: {tmp_path / 'set'}: two images share one pairing number (1): left01.png and left1.png (give each "
        "left/right pair a unique number in its file names)")


def test_a_wrong_board_size_is_named_with_the_size_that_is_there(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    for i in range(6):  # a board of 10x7 squares: 9x6 inner corners; 10x7 given (the squares counted)
        _board(tmp_path / "set" / "left" / f"{i}.png")
        _board(tmp_path / "set" / "right" / f"{i}.png")
    argv = ["calibrate", str(tmp_path / "set"), "--square", "0.025", "-o", str(tmp_path / "out.yaml")]
    assert _error(capsys, [*argv, "--pattern", "10x7"]) == (
        "error: --pattern: no 10x7 chessboard found; the images hold a 9x6 board (inner corners): use --pattern 9x6")
    assert _error(capsys, [*argv, "--pattern", "5x4"]) == (
        "error: --pattern: no 5x4 chessboard found; the images hold a 9x6 board (inner corners): use --pattern 9x6")


def test_opencv_sample_set_with_squares_counted_is_told_its_inner_corners(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    if not OPENCV_SET.is_dir():
        pytest.skip(f"real data absent: {OPENCV_SET}")
    assert _error(capsys, ["calibrate", str(OPENCV_SET), "--pattern", "10x7", "--square", "0.025", "--no-cache",
                           "-o", str(tmp_path / "out.yaml")]) == (
        "error: --pattern: no 10x7 chessboard found; the images hold a 9x6 board (inner corners): use --pattern 9x6")


def test_every_missing_required_option_in_one_message(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _error(capsys, ["calibrate", str(tmp_path)]) == (
        "error: missing required options: --pattern COLSxROWS (the chessboard's INNER corners, e.g. 9x6 for a board "
        "of 10x7 squares), --square METRES (one square's edge: every length scales with it, e.g. 0.025 for 25 mm), "
        "-o FILE (the profile YAML to write) (or describe the board with --target FILE)")
    assert _error(capsys, ["calibrate", str(tmp_path), "--pattern", "9x6", "--square", "0.025"]) == (
        "error: missing required option: -o FILE (the profile YAML to write)")


def test_calibrate_report_prints_where_the_report_is(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    if not OPENCV_SET.is_dir():
        pytest.skip(f"real data absent: {OPENCV_SET}")
    shutil.copytree(OPENCV_SET, tmp_path / "set", ignore=shutil.ignore_patterns("*.yml", "*.xml", "*.txt"))
    assert main(["calibrate", str(tmp_path / "set"), "--pattern", "9x6", "--square", "0.025", "-q", "--no-cache",
                 "-o", str(tmp_path / "real.yaml"), "--report", str(tmp_path / "report")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1] == f"report: {tmp_path / 'report' / 'index.html'}"
    assert (tmp_path / "report" / "index.html").is_file()


def test_a_misspelt_xacro_argument_names_the_declared_ones(tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    rig = Path(__file__).resolve().parents[1] / "urdf" / "dual_camera_fixed.urdf.xacro"
    assert _error(capsys, ["profile", "from-urdf", str(rig), "widht:=848", "-o", str(tmp_path / "p.yaml")]) == (
        f"error: {rig}: unknown xacro argument widht:=848 (did you mean width?); the file declares: baseline_xyz, "
        "clip_far, clip_near, height, hfov, update_rate, width (spell it as declared: xacro ignores an argument it "
        "does not know, silently)")
    assert not (tmp_path / "p.yaml").exists()
    assert main(["profile", "from-urdf", str(rig), "width:=848", "-q", "-o", str(tmp_path / "p.yaml")]) == 0
    assert "848x480" in capsys.readouterr().out


def _opencv_stereo(path: Path, size_lines: str) -> Path:
    """OpenCV's sample intrinsics.yml with R, T and the size lines given, written by hand."""
    intrinsics = (OPENCV_SET / "intrinsics.yml").read_text()
    path.write_text(intrinsics + "R: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 1., 0., 0., 0., 1., "
                    "0., 0., 0., 1. ]\nT: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ -0.0836, 0., "
                    "0. ]\n" + size_lines)
    return path


@pytest.mark.parametrize("size_lines", ["size: [ 640, 480 ]\n", "image_width: 640\nimage_height: 480\n"])
def test_an_opencv_stereo_file_that_states_its_size_needs_no_image_size(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], size_lines: str) -> None:
    if not OPENCV_SET.is_dir():
        pytest.skip(f"real data absent: {OPENCV_SET}")
    source = _opencv_stereo(tmp_path / "stereo.yml", size_lines)
    assert main(["profile", "convert", str(source), "--to", "s2r", "-o", str(tmp_path / "p.yaml")]) == 0
    assert "profile stereo (640x480, baseline 83.60 mm)" in capsys.readouterr().out
    bare = _opencv_stereo(tmp_path / "bare.yml", "")
    assert _error(capsys, ["profile", "convert", str(bare), "--to", "s2r", "-o", str(tmp_path / "q.yaml")]) == (
        f"error: {bare}: image_width/image_height: not in the file: the image size (pass --image-size WIDTHxHEIGHT "
        "(or state it in the file: size: [W, H], or image_width and image_height))")


@pytest.mark.parametrize("text", ["[left]\nfx = 500\nfy = 500\n[right]\nfx = 500\n[stereo]\nbaseline = 0.1\n",
                                  "# mine\n[left]\nfx = 500\n[STEREO]\nbaseline = 0.1\n[LEFT_CAM_x]\nfx 500\n"])
def test_a_home_made_ini_calibration_is_refused_as_what_it_is(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                              text: str) -> None:
    (tmp_path / "calib.ini").write_text(text)
    err = _error(capsys, ["profile", "convert", str(tmp_path / "calib.ini"), "--to", "s2r", "-o",
                          str(tmp_path / "p.yaml")])
    assert err.startswith(f"error: {tmp_path / 'calib.ini'}: an INI file (sections [left], ")
    assert err.endswith("that is not a ZED SN*.conf ([LEFT_CAM_HD], [RIGHT_CAM_HD], [STEREO] ...): s2r reads no "
                        "home-made INI calibration (write the numbers as an s2r profile YAML or an OpenCV FileStorage "
                        "(M1 D1 M2 D2 R T, size: [W, H]))")
    assert "malformed ZED" not in err


def test_the_d435_profile_states_the_range_it_gives(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", "realsense_d435_848x480"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "  matcher sgbm, 80 disparities: depth 0.30-5.0 m (matcher.min_depth_m..max_depth_m 0.3-5 m; the " \
           "disparities alone reach 0.27-21.2 m)" in lines
    # REFERENCE.md: RMS(Z) = Z^2 s / (f B), s = 0.08 px; f 424 px, B 50 mm: 2 % at Z = 0.02 f B / s = 5.3 m, so the
    # 5 m cut keeps the depth the datasheet's accuracy covers; at 21.2 m (1 px of disparity) the model gives 8 %
    assert "  stays under 2 % depth error up to 5.30 m" in lines
    d435 = load_profile("realsense_d435_848x480")
    assert d435.matcher.max_depth_m <= d435.max_depth_within_m(0.02) == pytest.approx(0.02 * 424 * 0.05 / 0.08)
    assert float(d435.depth_rms_m(21.2)) / 21.2 == pytest.approx(21.2 * 0.08 / (424 * 0.05))
