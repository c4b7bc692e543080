"""``s2r profile list | show | convert``: text and --json output, round trips through the CLI."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile, load_profile_file
from s2r.registry import SHIPPED_PROFILES
from tests.conftest import make_rig, shared_data
from tests.formats.rigs import assert_same_rig, with_distortion

DATA = Path(__file__).parent / "formats" / "data"


def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict:
    capsys.readouterr()  # drop earlier output
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_list_shows_shipped_profiles(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "list"]) == 0
    text = capsys.readouterr().out
    assert "realsense_d435_848x480" in text and "realsense_d435_1280x720" in text
    listed = _json(capsys, ["profile", "list", "--json"])
    assert Path(listed["realsense_d435_848x480"]) == SHIPPED_PROFILES / "real" / "realsense_d435_848x480.yaml"


def test_list_includes_user_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    dump_profile(make_rig(name="bench_rig"), tmp_path / "bench_rig.yaml")
    monkeypatch.setenv("S2R_PROFILE_PATH", str(tmp_path))
    assert str(tmp_path / "bench_rig.yaml") == _json(capsys, ["profile", "list", "--json"])["bench_rig"]


def test_show_text_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", "realsense_d435_848x480"]) == 0
    text = capsys.readouterr().out
    assert "baseline 50.00 mm" in text and "848x480" in text and "nominal" in text
    data = _json(capsys, ["profile", "show", "realsense_d435_848x480", "--json"])
    summary = data["summary"]
    assert summary["baseline_m"] == pytest.approx(0.05) and summary["image_size"] == [848, 480]
    # Intel's model at 1 m: 1^2 * 0.08 / (424 * 0.05) m = 3.77 mm
    assert summary["depth_rms_mm"]["1m"] == pytest.approx(1000 * 0.08 / (424.0 * 0.05))
    assert data["profile"]["provenance"]["origin"] == "nominal"


def test_show_accepts_other_formats(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = _json(capsys, ["profile", "show", str(DATA / "rs_enumerate_devices_d435.txt"), "--json"])
    assert data["summary"]["image_size"] == [848, 480]
    assert data["summary"]["T_m"][0] == pytest.approx(-0.0499795265495777)


def test_convert_s2r_to_ros_and_back(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = make_rig(name="cli_rig", distortion=(-0.1, 0.02, 0.0005, -0.0003, 0.004), rotation_deg=(0.2, -0.3, 0.1))
    src = dump_profile(rig, tmp_path / "rig.yaml")
    assert main(["profile", "convert", str(src), "--to", "ros", "-o", str(tmp_path / "ros")]) == 0
    out = capsys.readouterr().out
    assert "read s2r profile YAML" in out and "left.yaml" in out and "right.yaml" in out
    right = yaml.safe_load((tmp_path / "ros" / "right.yaml").read_text())
    p = right["projection_matrix"]["data"]
    assert p[3] == pytest.approx(-p[0] * 0.1, rel=1e-12)  # Tx = -fx' * B
    report = _json(capsys, ["profile", "convert", str(tmp_path / "ros" / "left.yaml"),
                            str(tmp_path / "ros" / "right.yaml"), "--to", "s2r", "-o", str(tmp_path / "back.yaml"),
                            "--name", "cli_back", "--json"])
    assert report["input_format"] == "ros" and report["outputs"] == [str(tmp_path / "back.yaml")]
    assert report["profile"]["name"] == "cli_back"
    back = load_profile_file(tmp_path / "back.yaml")
    assert_same_rig(back, rig)
    assert back.provenance.method == "imported from ROS camera_info" and back.provenance.origin == "real"


def test_convert_through_kalibr_and_opencv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = with_distortion(make_rig(rotation_deg=(0.5, 0.1, -0.2)), "plumb_bob", (-0.1, 0.02, 0.001, 0.0, 0.0))
    src = dump_profile(rig, tmp_path / "rig.yaml")
    assert main(["profile", "convert", str(src), "--to", "kalibr", "-o", str(tmp_path / "camchain.yaml")]) == 0
    assert main(["profile", "convert", str(tmp_path / "camchain.yaml"), "--to", "opencv",
                 "-o", str(tmp_path / "stereo.xml")]) == 0
    report = _json(capsys, ["profile", "convert", str(tmp_path / "stereo.xml"), "--to", "s2r",
                            "-o", str(tmp_path / "back.yaml"), "--origin", "sim", "--json"])
    assert report["input_format"] == "opencv"
    back = load_profile_file(tmp_path / "back.yaml")
    assert_same_rig(back, rig)
    assert back.provenance.origin == "sim"


def test_convert_a_shipped_profile_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    report = _json(capsys, ["profile", "convert", "realsense_d435_1280x720", "--to", "ros", "-o", str(tmp_path),
                            "--json"])
    assert report["outputs"] == [str(tmp_path / name) for name in ("left.yaml", "right.yaml", "stereo_image_proc.yaml")]
    left = yaml.safe_load((tmp_path / "left.yaml").read_text())
    assert left["image_width"] == 1280 and left["distortion_model"] == "plumb_bob"


def test_convert_realsense_text_with_resolution(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "d435.yaml"
    report = _json(capsys, ["profile", "convert", str(DATA / "rs_enumerate_devices_d435.txt"), "--resolution",
                            "1280x720", "--to", "s2r", "-o", str(out), "--name", "my_d435", "--json"])
    assert report["input_format"] == "realsense" and report["profile"]["image_size"] == [1280, 720]
    profile = load_profile_file(out)
    assert profile.name == "my_d435" and profile.provenance.sources[0].sha256
    assert math.degrees(profile.left.hfov_rad) == pytest.approx(89.9, abs=0.2)


def test_convert_the_real_opencv_sample_with_extrinsics(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import cv2
    import numpy as np

    intrinsics = shared_data("opencv_stereo_chessboard", "intrinsics.yml")
    extrinsics = tmp_path / "extrinsics.yml"
    storage = cv2.FileStorage(str(extrinsics), cv2.FILE_STORAGE_WRITE)
    storage.write("R", np.eye(3))
    storage.write("T", np.array([[-3.344], [0.042], [0.053]]))
    storage.release()
    out = tmp_path / "sample.yaml"
    assert main(["profile", "convert", str(intrinsics), str(extrinsics), "--to", "s2r", "-o", str(out),
                 "--image-size", "640x480", "--units-m", "0.025"]) == 0
    profile = load_profile_file(out)
    assert profile.left.fx_px == pytest.approx(534.803, abs=5e-4) and profile.baseline_m == pytest.approx(0.0836,
                                                                                                          abs=2e-4)
    capsys.readouterr()


def test_convert_usage_errors_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = dump_profile(make_rig(), tmp_path / "rig.yaml")
    with pytest.raises(SystemExit) as info:
        main(["profile", "convert", str(src), "--to", "gazebo", "-o", str(tmp_path / "x")])
    assert info.value.code == 2
    with pytest.raises(SystemExit) as info:
        main(["profile", "convert", str(src), "--to", "s2r", "-o", str(tmp_path / "x"), "--resolution", "848by480"])
    assert info.value.code == 2
    assert "expected WIDTHxHEIGHT" in capsys.readouterr().err
    assert main(["profile", "convert", str(src), str(src), str(src), "--to", "s2r", "-o", str(tmp_path / "x")]) == 2
    assert "expected one or two inputs, got 3" in capsys.readouterr().err
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(tmp_path / "x"), "--name", "bad name"]) == 2
    assert "--name: invalid profile name 'bad name'" in capsys.readouterr().err
    assert main(["profile", "show", "no_such_profile"]) == 2
    assert "unknown profile name 'no_such_profile'" in capsys.readouterr().err
