"""One input given for both cameras: one message from one place (``s2r.recordings.refuse_same_sides``) for every
command and input form, before anything is opened or decoded.

The inputs are files no decoder could read (a bag, a video and PNGs of text): were any opened, the error would be
about that file instead.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main

PROFILE = "realsense_d435_848x480"

#: Each command's words and positionals (the recording comes next), and its other options.
COMMANDS = {"calibrate": (["calibrate"], ["--pattern", "9x6", "--square", "0.025", "-o", "{tmp}/cal.yaml"]),
            "check": (["check", PROFILE], []),
            "depth": (["depth", PROFILE], ["-o", "{tmp}/out"]),
            "depth-quality": (["depth-quality", PROFILE], ["--pattern", "9x6", "--square", "0.025"]),
            "sensor fit": (["sensor", "fit", PROFILE], ["--pattern", "9x6", "--square", "0.025", "-o", "{tmp}/s.yaml"]),
            "validate": (["validate", "gazebo_dual_camera", PROFILE], [])}

#: Each form: its arguments, and the one error line expected (``{tmp}`` the test's folder).
FORMS = {
    "bag topic": (["--bag", "{tmp}/run.bag", "--left-topic", "/cam/image", "--right-topic", "/cam/image"],
                  "error: {tmp}/run.bag: --left-topic/--right-topic: left and right are the same topic /cam/image "
                  "(give the two cameras' inputs)"),
    "video": (["--left-video", "{tmp}/run.mp4", "--right-video", "{tmp}/./run.mp4"],
              "error: --left-video/--right-video: left and right are the same file {tmp}/run.mp4 (give the two "
              "cameras' inputs)"),
    "folder": (["--left", "{tmp}/cam0", "--right", "{tmp}/cam0/"],
               "error: --left/--right: left and right are the same folder {tmp}/cam0 (give the two cameras' inputs)"),
    "glob": (["--left", "{tmp}/cam0/*.png", "--right", "{tmp}/cam0/*.png"],
             "error: --left/--right: left and right are the same glob {tmp}/cam0/*.png (give the two cameras' "
             "inputs)"),
    "linked FOLDER": (["{tmp}/rec"],
                      "error: FOLDER: left and right are the same folder {tmp}/rec/left (give the two cameras' "
                      "inputs)"),
}


@pytest.fixture
def inputs(tmp_path: Path) -> Path:
    """Undecodable inputs: ``run.bag``, ``run.mp4``, ``cam0/NN.png`` and ``rec/left/NN.png`` with ``rec/right`` a
    link to ``rec/left``."""
    (tmp_path / "run.bag").write_bytes(b"not a bag\n")
    (tmp_path / "run.mp4").write_bytes(b"not a video\n")
    for folder in (tmp_path / "cam0", tmp_path / "rec" / "left"):
        folder.mkdir(parents=True)
        for k in range(2):
            (folder / f"{k:02d}.png").write_bytes(b"not an image\n")
    (tmp_path / "rec" / "right").symlink_to("left")
    return tmp_path


@pytest.mark.parametrize("form", sorted(FORMS))
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_one_message_for_one_input_twice(inputs: Path, capsys: pytest.CaptureFixture[str], command: str,
                                        form: str) -> None:
    (head, tail), (args, expected) = COMMANDS[command], FORMS[form]
    if command == "validate" and form == "linked FOLDER":
        args = ["--recording", *args]  # validate's real recording FOLDER is --recording's
    argv = [a.format(tmp=inputs) for a in [*head, *args, *tail]]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [expected.format(tmp=inputs)]


@pytest.mark.parametrize(("args", "expected"), [
    (["{tmp}/cam0/00.png", "{tmp}/cam0/./00.png"],
     "error: LEFT RIGHT: left and right are the same file {tmp}/cam0/00.png (give the two cameras' inputs)"),
    (["--left-dir", "{tmp}/cam0", "--right-dir", "{tmp}/cam0"],
     "error: --left-dir/--right-dir: left and right are the same folder {tmp}/cam0 (give the two cameras' inputs)")])
def test_depth_pairs_and_sequences_too(inputs: Path, capsys: pytest.CaptureFixture[str], args: list[str],
                                       expected: str) -> None:
    assert main(["depth", PROFILE, *(a.format(tmp=inputs) for a in args), "-o", str(inputs / "out")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [expected.format(tmp=inputs)]
    assert not (inputs / "out").exists()


def test_validate_recording_source_too(inputs: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``validate --recording left=...,right=...`` (the key=value form of depth-quality's inputs)."""
    cam0 = inputs / "cam0"
    assert main(["validate", "gazebo_dual_camera", PROFILE, "--recording", f"left={cam0},right={cam0}"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: --recording: left and right are the same folder {cam0} (give the two cameras' inputs)"]
