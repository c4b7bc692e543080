"""Mono profiles (``s2r calibrate --mono``) can be shown and converted like stereo ones."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest
import yaml

from s2r.cli import main
from s2r.formats.ros_read import read_camera_info
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import Camera, Distortion, MonoProfile, Provenance


@pytest.fixture
def mono_path(tmp_path: Path) -> Path:
    cam = Camera(width_px=640, height_px=480, fx_px=536.07, fy_px=536.01, cx_px=342.37, cy_px=235.53,
                 distortion=Distortion(coefficients=(-0.265, -0.047, 0.0018, -0.0003, 0.0)))
    profile = MonoProfile(name="cam0", camera=cam, provenance=Provenance(origin="real", method="s2r calibrate --mono"))
    return dump_profile(profile, tmp_path / "cam0.yaml")


def test_show_a_mono_profile(mono_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", str(mono_path)]) == 0
    out = capsys.readouterr().out
    assert "cam0  (mono" in out and "fx 536.070" in out and "cx 342.37" in out


@pytest.mark.parametrize("fmt", ["ros", "kalibr", "opencv", "s2r"])
def test_convert_a_mono_profile(mono_path: Path, fmt: str, tmp_path: Path) -> None:
    out = tmp_path / f"out_{fmt}.yaml"
    assert main(["profile", "convert", str(mono_path), "--to", fmt, "-o", str(out)]) == 0
    if fmt == "ros":
        info = read_camera_info(out)
        assert info.K[0, 0] == 536.07 and info.P[0, 2] == 342.37 and info.P[0, 3] == 0.0
    elif fmt == "kalibr":
        cam0 = yaml.safe_load(out.read_text())["cam0"]
        assert cam0["intrinsics"] == [536.07, 536.01, 342.37, 235.53] and cam0["distortion_model"] == "radtan"
    elif fmt == "opencv":
        fs = cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ)
        assert fs.getNode("camera_matrix").mat()[1, 2] == 235.53 and fs.getNode("image_width").real() == 640
    else:
        assert "camera:" in out.read_text()
    assert main(["profile", "convert", str(mono_path), "--to", fmt, "-o", str(out)]) == 2  # no overwrite
