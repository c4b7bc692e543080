"""No output is a file the command reads, even when that file was not named on the command line but found inside an
input folder, glob or bag, or through a description's include (before: ``s2r calibrate ocv -o ocv/left01.jpg --force``
replaced the input image; ``fleet check -o DIR --force`` removed the robots' recordings kept in DIR). Refused in one
line, exit 2, even with --force, nothing written and every input untouched, whatever path names the file (relative,
through ``..``, a symlinked folder, a hard link). A NEW file inside an input folder is still written."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import pytest

from s2r.cli import main
from s2r.errors import OutputExistsError
from s2r.fileio import check_output_free, protect_read_files, protecting_inputs
from tests.conftest import CAMERA_MACRO_XACRO, shared_data
from tests.depth.stream_inputs import (
    LEFT_TOPIC,
    RIGHT_TOPIC,
    known_frames,
    known_rig,
    write_folder,
    write_profile,
    write_ros2_bag,
)

BOARD = ("--pattern", "9x6", "--square", "0.025")
REFUSED = "an input of this command"


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _refused(capsys: pytest.CaptureFixture[str], words: str = REFUSED) -> str:
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture(scope="module")
def known(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("known")
    frames = known_frames(rig, distances_m=(1.0, 1.4))
    write_folder(frames, root / "rec")
    write_ros2_bag(frames, root / "bag")
    return {"profile": write_profile(profile, root / "rig.yaml"), "root": root}


@pytest.fixture
def ocv(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """OpenCV's stereo chessboard set (leftNN.jpg / rightNN.jpg in one folder), copied; the working folder is its
    parent so that outputs can be named relative to it."""
    folder = tmp_path / "ocv"
    shutil.copytree(shared_data("opencv_stereo_chessboard"), folder)
    monkeypatch.chdir(tmp_path)
    return folder


@pytest.mark.parametrize("output", ["ocv/left01.jpg", "ocv/../ocv/right03.jpg", "ABS/ocv/left02.jpg",
                                    "link/left04.jpg", "hardlink.jpg"])
def test_calibrate_never_writes_over_an_image_of_its_input_folder(ocv: Path, output: str,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    (ocv.parent / "link").symlink_to(ocv.name)
    os.link(ocv / "left05.jpg", ocv.parent / "hardlink.jpg")
    before, beside = _tree(ocv), sorted(p.name for p in ocv.parent.iterdir())
    output = output.replace("ABS", str(ocv.parent))
    assert main(["calibrate", "ocv", "-o", output, *BOARD, "--force", "--report", "rep"]) == 2
    _refused(capsys)
    assert _tree(ocv) == before  # no image replaced, no .corners cache written beside it
    assert sorted(p.name for p in ocv.parent.iterdir()) == beside  # no report folder left behind


def test_calibrate_globs_and_mono_never_write_over_an_image_they_read(ocv: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    before = _tree(ocv)
    globs = ["--left", "ocv/left*.jpg", "--right", "ocv/right*.jpg"]
    assert main(["calibrate", *globs, "-o", "ocv/right07.jpg", *BOARD, "--force"]) == 2
    _refused(capsys)
    assert main(["calibrate", "--mono", "--left", "ocv/left*.jpg", "-o", "ocv/left07.jpg", *BOARD, "--force"]) == 2
    _refused(capsys)
    assert _tree(ocv) == before


def test_calibrate_still_writes_a_new_file_into_its_input_folder(ocv: Path) -> None:
    assert main(["-q", "calibrate", "ocv", "-o", "ocv/calib.yaml", *BOARD]) == 0
    assert (ocv / "calib.yaml").is_file()
    assert main(["-q", "calibrate", "ocv", "-o", "ocv/calib.yaml", *BOARD, "--force"]) == 0  # not an input


def test_sensor_fit_replaces_its_profile_out_with_force(ocv: Path) -> None:
    """--profile-out is an output: an existing file there is replaced with --force (it was refused as an input)."""
    (ocv.parent / "p2.yaml").write_text("old")
    assert main(["-q", "calibrate", "ocv", "-o", "calib.yaml", *BOARD, "--max-frames", "6"]) == 0
    glob = ["--left", "ocv/left0[12].jpg", "--right", "ocv/right0[12].jpg"]
    assert main(["-q", "sensor", "fit", "calib.yaml", *glob, *BOARD, "-o", "s.yaml", "--profile-out", "p2.yaml",
                 "--force"]) == 0
    assert (ocv.parent / "p2.yaml").read_text() != "old"


def test_depth_check_and_sensor_fit_never_write_over_an_image_they_read(known: dict[str, Any], tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    rec = tmp_path / "rec"
    shutil.copytree(known["root"] / "rec", rec)
    before, image = _tree(rec), rec / "left" / "shot_00.png"
    prof = str(known["profile"])
    runs = [["depth", prof, str(rec), "-o", str(image), "--to", "ros1"],
            ["depth", prof, "--left", f"{rec}/left/*.png", "--right", f"{rec}/right/*.png", "-o", str(image),
             "--to", "ros1"],
            ["check", prof, str(rec), "--fix", "-o", str(rec / "right" / "shot_01.png")],
            ["sensor", "fit", prof, "--left", f"{rec}/left/*.png", "--right", f"{rec}/right/*.png", *BOARD,
             "-o", str(image)],
            ["sensor", "fit", prof, "--left", f"{rec}/left/*.png", "--right", f"{rec}/right/*.png", *BOARD,
             "-o", str(tmp_path / "sensor.yaml"), "--profile-out", str(image)]]
    for args in runs:
        assert main([*args, "--force"]) == 2, args
        _refused(capsys)
        assert _tree(rec) == before, args
    assert not (tmp_path / "sensor.yaml").exists()


def test_check_never_writes_over_a_file_of_its_bag(known: dict[str, Any], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    bag = tmp_path / "bag"
    shutil.copytree(known["root"] / "bag", bag)
    before = _tree(bag)
    storage = next(p for p in bag.iterdir() if p.name != "metadata.yaml")
    for out in (bag / "metadata.yaml", storage):
        assert main(["check", str(known["profile"]), "--bag", str(bag), "--left-topic", LEFT_TOPIC, "--right-topic",
                     RIGHT_TOPIC, "--fix", "-o", str(out), "--force"]) == 2
        _refused(capsys)
    assert _tree(bag) == before


def test_depth_never_replaces_a_folder_an_input_subfolder_links_into(known: dict[str, Any], tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """rec/left and rec/right are links into elsewhere/: ``-o elsewhere --force`` would move the images aside."""
    elsewhere, rec = tmp_path / "elsewhere", tmp_path / "rec"
    shutil.copytree(known["root"] / "rec", elsewhere)
    rec.mkdir()
    for side in ("left", "right"):
        (rec / side).symlink_to(elsewhere / side)
    before = _tree(elsewhere)
    assert main(["depth", str(known["profile"]), str(rec), "-o", str(elsewhere), "--force"]) == 2
    _refused(capsys, "holds")
    assert _tree(elsewhere) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["elsewhere", "rec"]  # nothing moved aside


def test_from_urdf_never_writes_over_an_included_xacro(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cams = tmp_path / "cams.xacro"
    cams.write_text(CAMERA_MACRO_XACRO)
    main_file = tmp_path / "rig.urdf.xacro"
    main_file.write_text("""<?xml version="1.0"?>
<robot name="rig" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:include filename="cams.xacro"/>
  <link name="base"/>
  <xacro:cam side="left" y="0.05"/>
  <xacro:cam side="right" y="-0.05"/>
</robot>
""")
    before = cams.read_bytes()
    assert main(["profile", "from-urdf", str(main_file), "-o", str(cams), "--force"]) == 2
    _refused(capsys)
    assert cams.read_bytes() == before
    assert main(["-q", "profile", "from-urdf", str(main_file), "-o", str(tmp_path / "rig.yaml")]) == 0


def test_fleet_never_replaces_the_folder_holding_its_recordings(known: dict[str, Any], tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    robots = tmp_path / "robots"
    shutil.copytree(known["root"] / "rec", robots / "rec")
    shutil.copy(known["profile"], robots / "r.yaml")
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text("robots:\n  - {name: r01, profile: robots/r.yaml, recording: robots/rec}\n")
    before = _tree(robots)
    for out in (robots, robots / "rec"):
        assert main(["fleet", "check", str(fleet), "-o", str(out), "--force", "--jobs", "1"]) == 2
        _refused(capsys, "holds")
    assert _tree(robots) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fleet.yaml", "robots"]


def test_the_first_of_an_output_and_an_input_to_be_known_refuses_the_second(tmp_path: Path) -> None:
    image = tmp_path / "left01.png"
    image.write_bytes(b"an image")
    with protecting_inputs([]):
        protect_read_files([image])
        with pytest.raises(OutputExistsError, match=REFUSED):
            check_output_free(tmp_path / "." / "left01.png", force=True)
    with protecting_inputs([]):
        check_output_free(image, force=True)
        with pytest.raises(OutputExistsError, match=REFUSED):
            protect_read_files([tmp_path / "left01.png"])
    protect_read_files([image])  # outside a command nothing is remembered
    assert check_output_free(image, force=True) == image
