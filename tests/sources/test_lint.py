"""``s2r lint``: each rule on a rig that has (only) that mistake; exit codes; JSON; camera_info fixtures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.ros_read import read_camera_info
from s2r.sources.lint.rules import Finding, lint_description
from tests.sources.rigs import DATA, FIXED_URDF, SEED_URDF, XBOT_SDF, sensor, two_camera_urdf, write


def _codes(findings: list[Finding], severity: str | None = None) -> list[str]:
    return [f.code for f in findings if severity is None or f.severity == severity]


def _lint(tmp_path: Path, text: str, name: str = "rig.urdf", **kwargs: object) -> list[Finding]:
    return lint_description(write(tmp_path, name, text), **kwargs)  # type: ignore[arg-type]


def test_seed_rig_baseline_error_with_the_corrected_origin(capsys: pytest.CaptureFixture[str]) -> None:
    findings = lint_description(SEED_URDF)
    errors = [f for f in findings if f.severity == "error"]
    assert [f.code for f in errors] == ["baseline-axis"]
    error = errors[0]
    assert "10.0 cm behind" in error.message and 'xyz="0 -0.1 0"' in error.message
    assert error.file == str(SEED_URDF) and error.line is not None
    assert 'name="left_to_right"' in SEED_URDF.read_text().splitlines()[error.line - 1]
    assert main(["lint", str(SEED_URDF)]) == 1
    out = capsys.readouterr().out
    assert f"{SEED_URDF}:{error.line}: error [baseline-axis]" in out


def test_fixed_rig_and_xbot_lint_clean(capsys: pytest.CaptureFixture[str]) -> None:
    for path in (FIXED_URDF, XBOT_SDF):
        assert _codes(lint_description(path), "error") == [] and _codes(lint_description(path), "warning") == []
        assert main(["lint", str(path)]) == 0
    capsys.readouterr()


@pytest.mark.parametrize("fixture", ["seed_camera_info_echo.txt", "seed_camera_info.yaml"])
def test_seed_camera_info_against_seed_urdf(fixture: str, capsys: pytest.CaptureFixture[str]) -> None:
    info = read_camera_info(DATA / fixture)
    found = [f for f in lint_description(FIXED_URDF, camera_info=info) if f.code == "camera-info"]
    assert len(found) == 1 and found[0].severity == "error"
    assert "80.0 deg" in found[0].message and "60.0 deg" in found[0].message
    assert "554.38" in found[0].fix
    assert main(["lint", str(SEED_URDF), "--camera-info", str(DATA / fixture)]) == 1
    assert "80.0 deg" in capsys.readouterr().out


def test_camera_info_with_other_resolution_or_centre(tmp_path: Path) -> None:
    info = read_camera_info(DATA / "seed_camera_info.yaml")
    small = type("Info", (), {"width": 320, "height": 240, "K": info.K, "camera_name": "left"})()
    assert "320x240" in next(f.message for f in lint_description(FIXED_URDF, camera_info=small))
    K = np.array([[554.3827, 0, 300.0], [0, 554.3827, 240.5], [0, 0, 1]])
    odd = type("Info", (), {"width": 640, "height": 480, "K": K, "camera_name": "left"})()
    found = [f for f in lint_description(FIXED_URDF, camera_info=odd) if f.code == "camera-info"]
    assert [f.severity for f in found] == ["warning"] and "matches no Gazebo convention" in found[0].message


def test_camera_info_tx_against_the_baseline() -> None:
    f = 554.3827128226441
    P = np.array([[f, 0, 320.5, -f * 0.12], [0, f, 240.5, 0], [0, 0, 1, 0]])
    K = P[:, :3]
    right = type("Info", (), {"width": 640, "height": 480, "K": K, "P": P, "camera_name": "right"})()
    found = [f for f in lint_description(FIXED_URDF, camera_info=right) if f.code == "camera-info"]
    assert len(found) == 1 and "0.12 m baseline" in found[0].message and "0.1 m" in found[0].message
    left = type("Info", (), {"width": 640, "height": 480, "K": K, "P": P, "camera_name": "left"})()
    found = [f for f in lint_description(FIXED_URDF, camera_info=left) if f.code == "camera-info"]
    assert len(found) == 1 and "left camera_info has P[3]" in found[0].message


def test_zero_baseline(tmp_path: Path) -> None:
    findings = _lint(tmp_path, two_camera_urdf(right_xyz="0 0 0"))
    assert _codes(findings, "error") == ["baseline-axis"] and "zero baseline" in findings[0].message


def test_vertical_baseline_component_costs_rectified_area(tmp_path: Path) -> None:
    # 3 cm up over a 10 cm baseline: 16.7 deg off the image x axis
    findings = _lint(tmp_path, two_camera_urdf(right_xyz="0 -0.1 0.03"))
    offset = [f for f in findings if f.code == "baseline-offset"]
    assert len(offset) == 1 and offset[0].severity == "warning"
    assert "vertical component of -30.0 mm" in offset[0].message and "16.7 deg" in offset[0].message
    assert 'xyz="0 -0.104403 0"' in offset[0].fix  # same 104.4 mm baseline, straight sideways
    tiny = _lint(tmp_path, two_camera_urdf(right_xyz="0 -0.1 0.00001"), name="tiny.urdf")
    assert "baseline-offset" not in _codes(tiny)


def test_right_camera_on_the_left(tmp_path: Path) -> None:
    findings = _lint(tmp_path, two_camera_urdf(right_xyz="0 0.1 0"), left="left_cam", right="right_cam")
    assert _codes(findings, "error") == ["baseline-side"] and "swap --left and --right" in findings[0].fix


def test_pair_resolution_fov_and_rate(tmp_path: Path) -> None:
    text = two_camera_urdf(right_sensor=sensor("right_cam", width=320, height=240))
    assert "pair-resolution" in _codes(_lint(tmp_path, text, "a.urdf"), "error")
    text = two_camera_urdf(right_sensor=sensor("right_cam", hfov=1.2))
    fov = next(f for f in _lint(tmp_path, text, "b.urdf") if f.code == "pair-fov")
    assert fov.severity == "warning" and "60.0 deg" in fov.message and "68.8 deg" in fov.message
    text = two_camera_urdf(right_sensor=sensor("right_cam", rate=15))
    rate = next(f for f in _lint(tmp_path, text, "c.urdf") if f.code == "pair-rate")
    assert rate.severity == "warning" and "30.0 Hz vs 15.0 Hz" in rate.message


def test_focal_length_and_lens_intrinsics_disagreeing_with_hfov(tmp_path: Path) -> None:
    plugin = ('<plugin name="p" filename="libgazebo_ros_camera.so"><focalLength>400</focalLength></plugin>')
    text = two_camera_urdf(right_sensor=sensor("right_cam", plugin=plugin))
    focal = next(f for f in _lint(tmp_path, text, "f.urdf") if f.code == "focal-length")
    assert focal.severity == "error" and "554.383" in focal.fix and "<focalLength> 400" in focal.message
    assert focal.line == 7  # line 7 of the written file: the right camera's <gazebo> block (one element a line)
    lens = "<lens><intrinsics><fx>500</fx><fy>500</fy><cx>320</cx><cy>240</cy><s>0</s></intrinsics></lens>"
    text = two_camera_urdf(left_sensor=sensor("left_cam", extra=lens))
    found = next(f for f in _lint(tmp_path, text, "l.urdf") if f.code == "lens-intrinsics")
    assert found.severity == "warning" and "fx = 554.383" in found.message


def test_hack_baseline_rules(tmp_path: Path) -> None:
    xbot = XBOT_SDF.read_text()
    missing = _lint(tmp_path, xbot.replace("<hackBaseline>0.06</hackBaseline>", ""), "m.sdf")
    assert [(f.severity, f.code) for f in missing] == [("warning", "hack-baseline")]
    wrong_sign = _lint(tmp_path, xbot.replace("<hackBaseline>0.06", "<hackBaseline>-0.06"), "s.sdf")
    assert ("error", "hack-baseline") in [(f.severity, f.code) for f in wrong_sign]
    size = _lint(tmp_path, xbot.replace("<hackBaseline>0.06", "<hackBaseline>0.07"), "z.sdf")
    assert [(f.severity, f.code) for f in size] == [("warning", "hack-baseline")]
    ros2 = _lint(tmp_path, xbot.replace("hackBaseline", "hack_baseline"), "r2.sdf")
    assert [(f.severity, f.code) for f in ros2] == [("warning", "hack-baseline")]
    assert "EVERY camera" in ros2[0].message
    renamed = _lint(tmp_path, xbot.replace('name="left"', 'name="cam_a"').replace('name="right"', 'name="cam_b"'),
                    "n.sdf", left="cam_a", right="cam_b")
    assert any(f.code == "hack-baseline" and "named 'cam_b'" in f.message for f in renamed)
    plugin = ('<plugin name="p" filename="libgazebo_ros_camera.so"><hackBaseline>0.1</hackBaseline></plugin>')
    on_left = _lint(tmp_path, two_camera_urdf(left_sensor=sensor("left_cam", plugin=plugin)), "h.urdf")
    assert any(f.severity == "error" and "on the LEFT camera" in f.message for f in on_left)


def test_near_clip_farther_than_the_matcher_sees(tmp_path: Path) -> None:
    text = two_camera_urdf(right_sensor=sensor("right_cam", near=0.8), left_sensor=sensor("left_cam", near=0.8))
    found = [f for f in _lint(tmp_path, text) if f.code == "near-clip"]
    # fx B / 111 = 554.38 * 0.1 / 111 = 0.4994 m -> the matcher is set to see from 0.5 m
    assert len(found) == 2 and "0.5 m" in found[0].message and found[0].severity == "warning"


def test_optical_link_and_movable_joint_warnings(tmp_path: Path) -> None:
    text = two_camera_urdf().replace('type="fixed"', 'type="continuous"')
    assert "movable-joint" in _codes(_lint(tmp_path, text, "j.urdf"), "warning")
    text = two_camera_urdf().replace("right_link", "right_optical").replace("left_link", "left_optical")
    assert "optical-link" in _codes(_lint(tmp_path, text, "o.urdf"), "warning")


def test_json_output(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lint", str(SEED_URDF), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["errors"] == 1
    first = data["findings"][0]
    assert set(first) == {"severity", "code", "message", "file", "line", "fix"}
    assert first["severity"] == "error" and first["code"] == "baseline-axis"


def test_xacro_arguments_on_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lint", str(SEED_URDF), "baseline_xyz:=0 -0.1 0"]) == 0
    capsys.readouterr()
