"""No output is ever one of the command's inputs, even with ``--force``: not a file written over a profile or an
image it reads, not a report folder equal to the recording (which --force would move aside before reading it), not
the folder of a profile found by name on ``S2R_PROFILE_PATH`` (found, not typed: the CLI did not see its path)."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

from s2r.cli import main
from tests.depth.stream_inputs import known_frames, known_rig, write_folder, write_profile


@pytest.fixture(scope="module")
def known(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("inputs")
    write_folder(known_frames(rig, distances_m=(1.0,)), root / "rec")
    return {"profile": write_profile(profile, root / "rig.yaml"), "root": root}


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_a_profile_found_by_name_keeps_its_folder(known: dict[str, Any], tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    profiles = tmp_path / "myprofiles"
    profiles.mkdir()
    shutil.copy(known["profile"], profiles / "myrig.yaml")
    before = _tree(profiles)
    monkeypatch.setenv("S2R_PROFILE_PATH", str(profiles))
    code = main(["depth", "myrig", str(known["root"] / "rec"), "-o", str(profiles), "--force"])
    assert code == 2
    err = capsys.readouterr().err
    assert "an input of this command" in err and err.count("\n") == 1
    assert _tree(profiles) == before


@pytest.mark.parametrize("to", ["ros1", "files"])
def test_an_output_file_is_never_the_profile(known: dict[str, Any], tmp_path: Path, to: str,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    profile = tmp_path / "r2.yaml"
    shutil.copy(known["profile"], profile)
    before = profile.read_bytes()
    args = ["depth", str(profile), str(known["root"] / "rec"), "-o", str(profile), "--force"]
    assert main(args if to == "files" else [*args, "--to", to]) == 2
    err = capsys.readouterr().err  # files: a folder is wanted; a bag: the file is the profile
    assert ("an input of this command" if to == "ros1" else "is a file, expected a folder") in err
    assert profile.read_bytes() == before


def test_convert_never_writes_over_its_input(known: dict[str, Any], tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    profile = tmp_path / "r5.yaml"
    shutil.copy(known["profile"], profile)
    before = profile.read_bytes()
    assert main(["profile", "convert", str(profile), "--to", "opencv", "-o", str(profile), "--force"]) == 2
    err = capsys.readouterr().err
    assert "an input of this command" in err and "Traceback" not in err
    assert profile.read_bytes() == before


def test_a_report_folder_equal_to_the_recording_is_refused_before_anything_moves(
        known: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rec = tmp_path / "rec"
    shutil.copytree(known["root"] / "rec", rec)
    before = _tree(rec)
    code = main(["check", str(known["profile"]), str(rec), "--report", str(rec), "--force"])
    assert code == 2
    assert "an input of this command" in capsys.readouterr().err
    assert _tree(rec) == before
    assert [p.name for p in tmp_path.iterdir()] == ["rec"]  # nothing moved aside, nothing left beside it


def test_a_derived_disparity_range_leaves_room_for_the_block(tmp_path: Path) -> None:
    """A rectified 450 px pair whose focal length asks for more disparities than the image holds: the derived range
    shrinks to leave OpenCV half a block (448 of 450 px raised 'too small for your window size'); exit 0."""
    import cv2
    import numpy as np

    rng = np.random.default_rng(3)
    left = (rng.random((375, 450)) * 255).astype(np.uint8)
    cv2.imwrite(str(tmp_path / "l.png"), left)
    cv2.imwrite(str(tmp_path / "r.png"), np.roll(left, -40, axis=1))
    assert main(["-q", "depth", str(tmp_path / "l.png"), str(tmp_path / "r.png"), "--rectified", "--f", "3740",
                 "--baseline", "0.16", "--cx", "224.5", "--cy", "187", "-o", str(tmp_path / "mb")]) == 0
    assert (tmp_path / "mb" / "disparity.npy").is_file()


def test_a_depth_topic_is_refused_as_a_camera_image(known: dict[str, Any], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    bag = tmp_path / "depth_bag"
    assert main(["-q", "depth", str(known["profile"]), str(known["root"] / "rec"), "-o", str(bag), "--to", "ros2",
                 "--namespace", "/stereo"]) == 0
    code = main(["depth", str(known["profile"]), "--bag", str(bag), "--left-topic", "/stereo/left/image_rect",
                 "--right-topic", "/stereo/depth/image_rect", "-o", str(tmp_path / "again")])
    assert code == 2
    err = capsys.readouterr().err
    assert "32FC1" in err and "not a camera image" in err and err.count("\n") == 1


def test_check_names_the_images_without_a_partner(known: dict[str, Any], tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    rec = tmp_path / "rec"
    shutil.copytree(known["root"] / "rec", rec)
    shutil.copy(rec / "left" / "shot_00.png", rec / "left" / "shot_07.png")
    main(["check", str(known["profile"]), str(rec)])
    err = capsys.readouterr().err
    assert "no partner" in err and "shot_07" in err
