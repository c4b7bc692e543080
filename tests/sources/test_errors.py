"""Bad descriptions: each gets ONE line naming the file, the element and the fix (exit 2 from the CLI)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.sources import load_description_profile
from tests.sources.rigs import joint, sensor, two_camera_urdf, urdf, write


def _cli_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err
    return err


def _check(path: Path, capsys: pytest.CaptureFixture[str], *needles: str) -> None:
    with pytest.raises(SourceError) as info:
        load_description_profile(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    for needle in needles:
        assert needle in message, message
    for argv in (["lint", str(path)], ["profile", "from-urdf", str(path), "-o", str(path.with_suffix(".yaml"))]):
        err = _cli_error(capsys, argv)
        assert all(n in err for n in needles)
    assert not path.with_suffix(".yaml").exists()


def test_malformed_xml(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, "bad.urdf", '<robot name="r">\n  <link name="a">\n</robot>\n')
    _check(path, capsys, "line 3", "malformed XML", "mismatched tag", "fix the XML syntax")


def test_missing_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["left_link", "right_link"], [joint("j", "left_link", "ghost")], {"left_link": sensor("a")})
    _check(write(tmp_path, "missing.urdf", text), capsys, "<joint name='j'> line 5", "'ghost'",
           "add <link name='ghost'/>")


def test_gazebo_reference_to_a_missing_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["left_link"], [], {"left_link": sensor("a"), "nowhere": sensor("b")})
    _check(write(tmp_path, "ref.urdf", text), capsys, "<gazebo reference='nowhere'>", "add <link name='nowhere'/>")


def test_joint_loop(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["a", "b"], [joint("ab", "a", "b", "0 -0.1 0"), joint("ba", "b", "a")],
                {"a": sensor("left_cam"), "b": sensor("right_cam")})
    _check(write(tmp_path, "loop.urdf", text), capsys, "joint loop", "'ab'", "'ba'", "re-parent")


def test_joint_loop_is_reported_before_the_cameras(tmp_path: Path) -> None:
    text = urdf(["a", "b"], [joint("ab", "a", "b"), joint("ba", "b", "a")], {"a": sensor("only_one")})
    with pytest.raises(SourceError, match="joint loop"):
        load_description_profile(write(tmp_path, "loop1.urdf", text))


def test_link_with_two_parents(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["a", "b", "c"], [joint("ac", "a", "c"), joint("bc", "b", "c")], {"a": sensor("x"), "c": sensor("y")})
    _check(write(tmp_path, "two.urdf", text), capsys, "joint loop", "child of both 'ac' and 'bc'")


def test_no_camera(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["a"], [], {"a": '<sensor type="imu" name="imu"/>'})
    _check(write(tmp_path, "nocam.urdf", text), capsys, "no camera sensor found", "<sensor>",
           "<sensor type='camera'>")


def test_three_cameras_without_left_right(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = urdf(["a", "b", "c"], [joint("ab", "a", "b", "0 -0.1 0"), joint("ac", "a", "c", "0 -0.2 0")],
                {"a": sensor("cam_a"), "b": sensor("cam_b"), "c": sensor("cam_c")})
    path = write(tmp_path, "three.urdf", text)
    _check(path, capsys, "found 3 camera(s): cam_a, cam_b, cam_c", "--left NAME --right NAME")
    p = load_description_profile(path, left="cam_a", right="cam_c")
    assert p.baseline_m == pytest.approx(0.2)


def test_unknown_camera_name(tmp_path: Path) -> None:
    path = write(tmp_path, "two.urdf", two_camera_urdf())
    with pytest.raises(SourceError, match="--left: no camera named 'nope'; cameras: left_cam, right_cam"):
        load_description_profile(path, left="nope", right="right_cam")


def test_unresolved_find(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    path = write(tmp_path, "find.urdf.xacro", '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                 '<xacro:include filename="$(find no_such_pkg)/urdf/cam.xacro"/></robot>\n')
    _check(path, capsys, "find.urdf.xacro: $(find no_such_pkg): package 'no_such_pkg' not found", "--package-path DIR",
           "ROS_PACKAGE_PATH")


def test_missing_file_and_bad_xacro_argument(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    err = _cli_error(capsys, ["lint", str(tmp_path / "none.urdf")])
    assert "none.urdf: file not found" in err
    assert f"{tmp_path}: is a folder, not a file" in _cli_error(capsys, ["lint", str(tmp_path)])
    path = write(tmp_path, "two.urdf", two_camera_urdf())
    err = _cli_error(capsys, ["lint", str(path), "baseline=0.1"])
    assert "NAME:=VALUE" in err and "name:=value" in err


def test_bad_numbers_name_the_element(tmp_path: Path) -> None:
    text = two_camera_urdf(right_sensor=sensor("right_cam").replace("<horizontal_fov>1.047", "<horizontal_fov>wide"))
    with pytest.raises(SourceError, match=r"<horizontal_fov> line \d+: expected a number, got 'wide'"):
        load_description_profile(write(tmp_path, "nan.urdf", text))
