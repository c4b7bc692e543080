"""A PROFILE positional beside ``--profile``: one rule for every command that takes both (check, depth,
depth-quality, sensor fit/apply). The same profile twice is one profile; another profile is refused in one line
naming both (exit 2), never read as an image or a recording; anything else is the command's input."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from tests.conftest import make_rig

PROFILE = "realsense_d435_848x480"
OTHER = Path(__file__).resolve().parents[1] / "profiles" / "sim" / "gazebo_dual_camera.yaml"

#: Each command's arguments besides the profile and the recording.
COMMANDS = {"check": ["check"], "depth": ["depth", "-o", "{tmp}/out"],
            "depth-quality": ["depth-quality", "--pattern", "9x6", "--square", "0.02"],
            "sensor fit": ["sensor", "fit", "--pattern", "9x6", "--square", "0.02", "-o", "{tmp}/s.yaml"]}


def _one_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    return err[0]


def _folder(root: Path, size: tuple[int, int] = (64, 48)) -> Path:
    """``root/left`` and ``root/right`` with two grey pairs of ``size`` (w, h)."""
    for side in ("left", "right"):
        (root / side).mkdir(parents=True)
        for k in range(2):
            cv2.imwrite(str(root / side / f"{k:02d}.png"), np.full(size[::-1], 40 * k + 10, np.uint8))
    return root


def _argv(command: str, tmp: Path, *args: str) -> list[str]:
    return [a.format(tmp=tmp) for a in COMMANDS[command]] + list(args)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_another_profile_beside_profile_is_refused_naming_both(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                              command: str) -> None:
    rec = _folder(tmp_path / "rec")
    for other in (str(OTHER), "gazebo_dual_camera"):  # a YAML file, a profile name
        err = _one_error(capsys, _argv(command, tmp_path, "--profile", PROFILE, other, str(rec)))
        assert "two profiles given" in err and other in err and PROFILE in err, err
    err = _one_error(capsys, _argv(command, tmp_path, "--profile", PROFILE, str(OTHER)))  # and no recording
    assert "two profiles given" in err and str(OTHER) in err, err


def test_depth_never_reads_a_profile_as_an_image(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left = tmp_path / "l.png"
    cv2.imwrite(str(left), np.zeros((480, 848), np.uint8))
    err = _one_error(capsys, ["depth", "--profile", PROFILE, str(OTHER), str(left), "-o", str(tmp_path / "o")])
    assert "two profiles given" in err and "image" not in err.split("(")[0], err


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_profile_option_then_folder_reads_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                     command: str) -> None:
    """``--profile P FOLDER`` (as check always took it): the folder is the recording, read with P (its 64x48
    images are refused against P's 848x480 from their headers: the profile was loaded, the folder opened)."""
    rec = _folder(tmp_path / "rec")
    err = _one_error(capsys, _argv(command, tmp_path, "--profile", PROFILE, str(rec)))
    assert "the header declares 64x48 px but 848x480 px are expected" in err, err


def test_the_same_profile_twice_is_one_profile(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The same file by two paths, or a name and the shipped file it names: depth runs (exit 0)."""
    profile = make_rig(width=64, height=48, hfov_rad=1.0, baseline_m=0.05)
    path = tmp_path / "rig.yaml"
    dump_profile(profile, path)
    rng = np.random.default_rng(0)
    image = (rng.random((48, 96)) * 255).astype(np.uint8)
    cv2.imwrite(str(tmp_path / "l.png"), image[:, 16:80])
    cv2.imwrite(str(tmp_path / "r.png"), image[:, 12:76])
    twin = tmp_path / "sub" / ".." / "rig.yaml"
    (tmp_path / "sub").mkdir()
    assert main(["-q", "depth", "--profile", str(path), str(twin), str(tmp_path / "l.png"), str(tmp_path / "r.png"),
                 "-o", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "depth.png").is_file()
    shipped = Path(__file__).resolve().parents[1] / "profiles" / "real" / f"{PROFILE}.yaml"
    rec = _folder(tmp_path / "rec")
    err = _one_error(capsys, ["check", "--profile", PROFILE, str(shipped), str(rec)])
    assert "848x480 px are expected" in err, err  # one profile: the recording was opened against it


def test_sensor_apply_refuses_a_second_profile(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    depth = tmp_path / "depth"
    depth.mkdir()
    shutil.copy(OTHER, tmp_path / "sensor.yaml")
    err = _one_error(capsys, ["sensor", "apply", "--profile", PROFILE, str(OTHER), str(tmp_path / "sensor.yaml"),
                              str(depth), "-o", str(tmp_path / "out")])
    assert "two profiles given" in err and str(OTHER) in err, err
