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


@pytest.mark.parametrize("command", [["depth-quality", "realsense_d435_848x480", "--right", "RIGHT"],
                                     ["sensor", "fit", "realsense_d435_848x480", "-o", "OUT"]])
def test_depth_quality_and_sensor_fit_name_the_board_size_too(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                              command: list[str]) -> None:
    for i in range(3):
        _board(tmp_path / "left" / f"{i}.png")
        _board(tmp_path / "right" / f"{i}.png")
    argv = [str(tmp_path / "right") if a == "RIGHT" else str(tmp_path / "s.yaml") if a == "OUT" else a
            for a in command]
    assert _error(capsys, [*argv, "--left", str(tmp_path / "left"), "--pattern", "10x7", "--square", "0.025"]) == (
        "error: --pattern: no 10x7 chessboard found; the images hold a 9x6 board (inner corners): use --pattern 9x6")


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


_MJCF_RIG = """<mujoco model="rig">
  <worldbody>
    <body name="head" pos="0 0 1">
      <camera name="rgb" pos="0 0.03 0" xyaxes="0 -1 0 0 0 1" fovy="58" resolution="640 480"/>
      <camera name="ir_left" pos="0 0 0" xyaxes="0 -1 0 0 0 1" fovy="58" resolution="640 480"/>
      <camera name="ir_right" pos="0 -0.06 0" xyaxes="0 -1 0 0 0 1" fovy="58" resolution="640 480"/>
    </body>
  </worldbody>
</mujoco>
"""


def _real_file(tmp_path: Path) -> Path:
    """The nominal D435 as a user's own file under another name (which no registry knows)."""
    text = (Path(__file__).resolve().parents[1] / "profiles" / "real" / "realsense_d435_848x480.yaml").read_text()
    path = tmp_path / "my real.yaml"
    path.write_text(text.replace("name: realsense_d435_848x480", "name: my_d435"))
    return path


def test_a_mujoco_sim_gets_mjcf_edits_not_gazebo_ones(tmp_path: Path) -> None:
    from s2r.sources.profile_builder import load_description_profile
    from s2r.validate.advice.mujoco import suggest_mujoco_edits
    from s2r.validate.measures.params import parameter_table
    from s2r.validate.tolerances import Tolerances

    (tmp_path / "rig.xml").write_text(_MJCF_RIG)
    sim = load_description_profile(tmp_path / "rig.xml", left="ir_left", right="ir_right").in_opencv_pixels()
    real = load_profile(_real_file(tmp_path)).in_opencv_pixels()
    edits = {e.parameter: e for e in suggest_mujoco_edits(sim, real, parameter_table(sim, real, Tolerances()))}
    assert list(edits) == ["resolution", "intrinsics", "right camera pos", "MJCF cameras"]
    assert edits["resolution"].where.startswith('resolution="848 480" on both <camera> elements of the MJCF')
    # D435: fx 424, cx 422.5, cy 235 at 848x480: principalpixel = ((848 - 1) / 2 - 422.5, (480 - 1) / 2 - 235)
    assert edits["intrinsics"].target == 'focalpixel="424 424" principalpixel="1 4.5" (both)'
    assert 'left <camera>: sensorsize="0.002544 0.00144" focalpixel="424 424" principalpixel="1 4.5"' in \
        edits["intrinsics"].where
    assert edits["right camera pos"].where.startswith("move the right <camera> pos by (-0.01 0 0) m along the left "
                                                      "camera's own axes")
    assert edits["MJCF cameras"].where.startswith("s2r profile export-mujoco my_d435 -o my_d435_cameras.xml")
    assert not any("horizontal_fov" in e.where or "hackBaseline" in e.where for e in edits.values())


def test_validate_chooses_mjcf_cameras_and_says_mjcf_things(tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "rig.xml").write_text(_MJCF_RIG)
    assert _error(capsys, ["validate", str(tmp_path / "rig.xml"), "realsense_d435_848x480", "--quick"]) == (
        f"error: {tmp_path / 'rig.xml'}: <camera>: cannot choose the stereo pair by itself; found 3 camera(s): rgb, "
        "ir_left, ir_right (pass --sim-left NAME --sim-right NAME with two of the listed cameras)")
    assert _error(capsys, ["validate", str(tmp_path / "rig.xml"), "realsense_d435_848x480", "--sim-left",
                           "ir_left"]) == (
        "error: --sim-left/--sim-right: --sim-left and --sim-right name the pair together (pass both, e.g. "
        "--sim-left left_cam --sim-right right_cam)")
    assert _error(capsys, ["validate", "gazebo_dual_camera", "realsense_d435_848x480", "--sim-left", "a",
                           "--sim-right", "b"]).startswith("error: --sim-left/--sim-right: --sim-left/--sim-right "
                                                           "choose the cameras of a robot description, and SIM is a "
                                                           "profile")
    (tmp_path / "none.xml").write_text('<mujoco model="none"><worldbody><body name="b"><geom type="box" '
                                       'size=".1 .1 .1"/></body></worldbody></mujoco>\n')
    assert _error(capsys, ["validate", str(tmp_path / "none.xml"), "realsense_d435_848x480"]) == (
        f"error: {tmp_path / 'none.xml'}: <camera>: no <camera> found in the MJCF (add two <camera name='...' "
        "pos='...' fovy='...' resolution='W H'/> inside the <body> of the camera link (or write the pair with s2r "
        "profile export-mujoco PROFILE and <include> it))")


@pytest.mark.slow
def test_validate_of_a_mujoco_sim_ends_with_the_export_of_the_users_real_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "rig.xml").write_text(_MJCF_RIG)
    real = _real_file(tmp_path)
    assert main(["validate", str(tmp_path / "rig.xml"), str(real), "--sim-left", "ir_left", "--sim-right", "ir_right",
                 "--quick", "-q"]) == 1
    out = capsys.readouterr().out
    assert "export-gazebo" not in out and "horizontal_fov" not in out and "hackBaseline" not in out
    assert "     fix: resolution 640 480 -> 848 480" in out
    assert ('fix: intrinsics focalpixel="432.971 432.971" principalpixel="0 0" (both) -> focalpixel="424 424" '
            'principalpixel="1 4.5" (both)') in " ".join(out.split())  # the summary wraps long lines
    assert (f"  where to write each edit: --report, --json; every edit at once: s2r profile export-mujoco '{real}' "
            "-o my_d435_cameras.xml") in out


def test_a_pair_with_two_problems_names_both(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    camera = ("<sensor name='{0}' type='camera'><camera><horizontal_fov>1.0</horizontal_fov><image><width>{1}</width>"
              "<height>{2}</height></image></camera></sensor>")
    (tmp_path / "rig.sdf").write_text(
        "<?xml version='1.0'?>\n<sdf version='1.9'><model name='rig'><link name='base'/>\n"
        f"<link name='left_cam'><pose>0 0 0 0 0 0</pose>{camera.format('left', 640, 480)}</link>\n"
        f"<link name='right_cam'><pose>0 0.06 0 0 0 0</pose>{camera.format('right', 1280, 720)}</link>\n"
        "</model></sdf>\n")
    assert _error(capsys, ["profile", "from-description", str(tmp_path / "rig.sdf"), "-o",
                           str(tmp_path / "p.yaml")]) == (
        f"error: {tmp_path / 'rig.sdf'}: line 4: [baseline-side] the 'right' camera is 6.0 cm to the LEFT of the left "
        "camera (disparities would be negative); and the cameras differ in image size: 640x480 vs 1280x720 "
        "(rectification needs one size) (swap --left and --right (or the camera names), or set joint '<link "
        "rig::right_cam pose>' <origin xyz=\"0 -0.06 0\" rpy=\"0 0 0\"/>; give both cameras one image size; or pass "
        "--allow-bad-baseline to write it anyway (s2r lint says the same))")


def test_a_camera_on_a_link_of_a_missing_include_names_the_include(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    camera = ("<sensor name='{0}' type='camera'><camera><horizontal_fov>1.0</horizontal_fov><image><width>640</width>"
              "<height>480</height></image></camera></sensor>")
    (tmp_path / "robot.sdf").write_text(
        "<?xml version='1.0'?>\n<sdf version='1.9'><model name='robot'><link name='base'/>\n"
        "<include><uri>model://sensor_mount</uri><name>mount</name></include>\n"
        "<link name='left_cam'>" + camera.format("left") + "</link>\n"
        "<link name='right_cam'><pose>0 -0.06 0 0 0 0</pose>" + camera.format("right") + "</link>\n"
        "<joint name='j1' type='fixed'><parent>mount::plate</parent><child>left_cam</child></joint>\n"
        "</model></sdf>\n")
    assert _error(capsys, ["profile", "from-description", str(tmp_path / "robot.sdf"), "-o",
                           str(tmp_path / "p.yaml")]) == (
        f"error: {tmp_path / 'robot.sdf'}: <include> line 3: link 'mount::plate' (<joint name='j1'> line 6) belongs "
        "to a model of <include> model://sensor_mount, which is not available here: model 'sensor_mount' "
        "(model://sensor_mount) not found in any model folder (pass --package-path DIR with the folder holding "
        "sensor_mount/, or set one of GZ_SIM_RESOURCE_PATH, IGN_GAZEBO_RESOURCE_PATH, GAZEBO_MODEL_PATH)")
