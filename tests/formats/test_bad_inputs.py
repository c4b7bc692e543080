"""Bad inputs through ``s2r profile convert``: each exits 2 with ONE line naming the file and the field.

``CASES`` maps a case name to a builder that writes the bad input(s) into a folder and returns the CLI
sources, the file the message must name, and fragments the message must hold (field, what is wrong).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
import yaml

from s2r.cli import main
from s2r.formats.kalibr import dump_kalibr
from s2r.formats.opencv import dump_opencv
from s2r.formats.ros import dump_ros_pair
from s2r.formats.s2r_yaml import dump_profile
from tests.conftest import make_rig
from tests.formats.rigs import distorted_rotated_rig, with_distortion

DATA = Path(__file__).parent / "data"
Case = tuple[list[str], Path | None, list[str]]


def _rig() -> Any:
    return with_distortion(distorted_rotated_rig(), "plumb_bob", (-0.12, 0.05, 0.001, -0.002, 0.0))


def _edit_yaml(path: Path, edit: Callable[[Any], None]) -> Path:
    data = yaml.safe_load(path.read_text())
    edit(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _s2r(tmp: Path, edit: Callable[[Any], None]) -> Path:
    return _edit_yaml(dump_profile(_rig(), tmp / "profile.yaml"), edit)


def _ros(tmp: Path, edit: Callable[[Any], None]) -> tuple[Path, Path]:
    left, right = dump_ros_pair(_rig(), tmp / "ros")
    return _edit_yaml(left, edit), right


def _kalibr(tmp: Path, edit: Callable[[Any], None]) -> Path:
    return _edit_yaml(dump_kalibr(_rig(), tmp / "camchain.yaml"), edit)


def _opencv(tmp: Path, old: str, new: str) -> Path:
    path = dump_opencv(_rig(), tmp / "stereo.yml")
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    return path


def _set(keys: list[Any], value: Any) -> Callable[[Any], None]:
    def edit(data: Any) -> None:
        node = data
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value
    return edit


def _delete(keys: list[Any]) -> Callable[[Any], None]:
    def edit(data: Any) -> None:
        node = data
        for key in keys[:-1]:
            node = node[key]
        del node[keys[-1]]
    return edit


def _ros_case(edit: Callable[[Any], None], fragments: list[str]) -> Callable[[Path], Case]:
    def build(tmp: Path) -> Case:
        left, right = _ros(tmp, edit)
        return [str(left), str(right)], left, fragments
    return build


def _one(make: Callable[[Path], Path], fragments: list[str]) -> Callable[[Path], Case]:
    def build(tmp: Path) -> Case:
        path = make(tmp)
        return [str(path)], path, fragments
    return build


def _truncated(tmp: Path) -> Case:
    path = dump_opencv(_rig(), tmp / "stereo.yml")
    path.write_bytes(path.read_bytes()[:300])
    return [str(path)], path, ["malformed or truncated OpenCV FileStorage", "line"]


def _ros_sizes(tmp: Path) -> Case:
    left, _ = dump_ros_pair(_rig(), tmp / "a")
    _, right = dump_ros_pair(make_rig(width=1280, height=720), tmp / "b")
    return [str(left), str(right)], right, ["image_width/image_height", "1280x720 differs from 640x480"]


def _intrinsics_only(tmp: Path) -> Case:
    path = tmp / "intrinsics.yml"
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in (("M1", make_rig().left.K), ("D1", np.zeros((1, 5))), ("M2", make_rig().left.K),
                       ("D2", np.zeros((1, 5)))):
        storage.write(key, value)
    storage.release()
    return [str(path), "--image-size", "640x480"], path, ["R: not in the file: the extrinsics R and T",
                                                           "extrinsics.yml"]


def _missing_file(tmp: Path) -> Case:
    return [str(tmp / "nope.yaml")], tmp / "nope.yaml", ["file not found"]


def _missing_second_file(tmp: Path) -> Case:
    left, _ = dump_ros_pair(_rig(), tmp / "ros")
    return [str(left), str(tmp / "right_missing.yaml")], tmp / "right_missing.yaml", ["file not found"]


def _realsense_missing(tmp: Path) -> Case:
    path = tmp / "rs.txt"
    path.write_text((DATA / "rs_enumerate_devices_d435.txt").read_text().replace(
        "  Fx:         \t424.691284179688\n", "", 2))  # the Depth and the Infrared 1 block
    return [str(path)], path, ['"Infrared 1" 848x480: Fx', "field is missing"]


def _realsense_nan(tmp: Path) -> Case:
    path = tmp / "rs.txt"
    text = (DATA / "rs_enumerate_devices_d435.txt").read_text()
    path.write_text(text.replace("PPX:        \t422.885070800781", "PPX:        \tnan", 2))
    return [str(path)], path, ['"Infrared 1" 848x480: PPX', "must be a finite number, got nan"]


def _single_camera_info(tmp: Path) -> Case:
    return [str(DATA / "gazebo_left_camera_info.txt")], DATA / "gazebo_left_camera_info.txt", \
        ["a camera_info file holds one camera"]


def _unrecognised(tmp: Path) -> Case:
    path = tmp / "notes.yaml"
    path.write_text("title: my camera\nnotes: [a, b]\n")
    return [str(path)], path, ["unrecognised format (top-level keys: notes, title)"]


def _s2r_text(tmp: Path, old: str, new: str) -> Path:
    path = dump_profile(_rig(), tmp / "profile.yaml")
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    return path


def _ros_malformed(tmp: Path) -> Case:
    left, right = dump_ros_pair(_rig(), tmp / "ros")
    left.write_text(left.read_text().replace("rows: 3", "rows: [3", 1))
    return [str(left), str(right)], left, ["malformed YAML", "line 6"]


CASES: dict[str, Callable[[Path], Case]] = {
    "s2r malformed YAML": _one(lambda t: _s2r_text(t, "fx_px: 554.3827128226441", "fx_px: [554.38"),
                               ["malformed YAML", "line"]),
    "ROS malformed YAML": _ros_malformed,
    "s2r unknown field": _one(lambda t: _s2r(t, _set(["left", "focal_mm"], 4.0)),
                              ["left.focal_mm", "unknown field"]),
    "s2r missing field": _one(lambda t: _s2r(t, _delete(["left", "fx_px"])), ["left.fx_px", "required field"]),
    "ROS missing field": _ros_case(_delete(["projection_matrix"]), ["projection_matrix", "required field"]),
    "ROS unknown distortion model": _ros_case(_set(["distortion_model"], "fisheye62"),
                                              ["distortion_coefficients", "unsupported distortion model"]),
    "Kalibr missing field": _one(lambda t: _kalibr(t, _delete(["cam1", "T_cn_cnm1"])),
                                 ["cam1.T_cn_cnm1", "no extrinsics between cam0 and cam1"]),
    "Kalibr unknown camera model": _one(lambda t: _kalibr(t, _set(["cam0", "camera_model"], "omni")),
                                        ["cam0.camera_model", "'omni' is not supported"]),
    "ROS negative focal length": _ros_case(_set(["camera_matrix", "data", 0], -554.0),
                                           ["camera_matrix", "focal length must be positive"]),
    "Kalibr zero focal length": _one(lambda t: _kalibr(t, _set(["cam0", "intrinsics", 1], 0.0)),
                                     ["cam0.intrinsics", "focal length must be positive"]),
    "s2r negative focal length": _one(lambda t: _s2r(t, _set(["right", "fy_px"], -1.0)),
                                      ["right.fy_px", "focal length must be positive"]),
    "OpenCV negative focal length": _one(lambda t: _opencv(t, "554.38271282264407", "-554.0"),
                                         ["M1", "focal length must be positive"]),
    "ROS principal point outside": _ros_case(_set(["camera_matrix", "data", 2], 900.0),
                                             ["camera_matrix", "principal point (900, 238.5) lies outside"]),
    "Kalibr principal point outside": _one(lambda t: _kalibr(t, _set(["cam1", "intrinsics", 3], -5.0)),
                                           ["cam1.intrinsics", "lies outside the 640x480 image"]),
    "ROS non-orthonormal R": _ros_case(_set(["rectification_matrix", "data", 1], 0.3),
                                       ["rectification_matrix", "not a rotation"]),
    "Kalibr non-orthonormal R": _one(lambda t: _kalibr(t, _set(["cam1", "T_cn_cnm1", 0, 0], 1.2)),
                                     ["cam1.T_cn_cnm1", "not a rotation"]),
    "s2r reflection R": _one(lambda t: _s2r(t, _set(["extrinsics", "rotation"], [[1, 0, 0], [0, 1, 0], [0, 0, -1]])),
                             ["extrinsics", "determinant +1"]),
    "OpenCV non-orthonormal R": _one(lambda t: _opencv(t, "0.99995583095393936", "0.7"), ["R", "not a rotation"]),
    "ROS NaN": _ros_case(_set(["camera_matrix", "data", 4], float("nan")), ["camera_matrix", "finite number"]),
    "Kalibr inf": _one(lambda t: _kalibr(t, _set(["cam0", "intrinsics", 0], float("inf"))),
                       ["cam0.intrinsics", "finite number, got inf"]),
    "s2r NaN": _one(lambda t: _s2r(t, _set(["left", "cx_px"], float("nan"))), ["left.cx_px", "finite number"]),
    "OpenCV NaN": _one(lambda t: _opencv(t, "554.38271282264407", ".Nan"), ["M1", "finite numbers only"]),
    "RealSense NaN": _realsense_nan,
    "ROS wrong coefficient count": _ros_case(_set(["distortion_coefficients", "data"], [0.1, 0.0, 0.0, 0.0]),
                                             ["distortion_coefficients", "plumb_bob needs 5 coefficients, got 4"]),
    "Kalibr wrong coefficient count": _one(lambda t: _kalibr(t, _set(["cam1", "distortion_coeffs"], [0.1] * 5)),
                                           ["cam1.distortion_coeffs", "radtan needs 4 coefficients"]),
    "s2r wrong coefficient count": _one(lambda t: _s2r(t, _set(["left", "distortion", "coefficients"], [0.1, 0.2])),
                                        ["left.distortion", "needs 5 coefficients, got 2"]),
    "OpenCV wrong coefficient count": _one(
        lambda t: _opencv(t, "cols: 5\n   dt: d\n   data: [ -0.12, 0.050000000000000003, 0.001, -0.002, 0. ]",
                          "cols: 6\n   dt: d\n   data: [ -0.12, 0.05, 0.001, -0.002, 0., 0.3 ]"),
        ["D1", "expected 4, 5 or 8 distortion coefficients, got 6"]),
    "missing file": _missing_file,
    "missing second file of a ROS pair": _missing_second_file,
    "ROS pair with different image sizes": _ros_sizes,
    "truncated FileStorage": _truncated,
    "OpenCV intrinsics without extrinsics": _intrinsics_only,
    "RealSense missing field": _realsense_missing,
    "single camera_info": _single_camera_info,
    "unrecognised file": _unrecognised,
}


def run_case(name: str, tmp: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str, Path | None, list[str]]:
    """Run one case through the CLI; returns (exit code, stderr, file to name, fragments)."""
    sources, named, fragments = CASES[name](tmp)
    out = tmp / "out.yaml"
    code = main(["profile", "convert", *sources, "--to", "s2r", "-o", str(out)])
    assert not out.exists()
    return code, capsys.readouterr().err, named, fragments


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_exits_2_with_one_line_naming_file_and_field(name: str, tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    code, err, named, fragments = run_case(name, tmp_path, capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    if named is not None:
        assert str(named) in lines[0], lines[0]
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])


def test_existing_output_is_not_overwritten(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = dump_profile(make_rig(), tmp_path / "in.yaml")
    out = tmp_path / "out.yaml"
    out.write_text("keep me\n")
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(out)]) == 2
    assert "already exists; nothing was overwritten (pass --force" in capsys.readouterr().err
    assert out.read_text() == "keep me\n"
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(out), "--force"]) == 0


def test_kalibr_export_of_k3_is_refused_naming_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = dump_profile(distorted_rotated_rig(), tmp_path / "in.yaml")
    out = tmp_path / "camchain.yaml"
    assert main(["profile", "convert", str(src), "--to", "kalibr", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"error: {out}: left.distortion: k3 = 0.01 cannot be written: Kalibr radtan has only k1 k2 r1 r2 "
                   "(pass --drop-k3 to write it without k3 (lossy))")
    assert not out.exists()
