"""``s2r lint`` on MJCF pairs: the same geometry rules as for URDF (baseline sideways, right camera on the right),
MJCF pair rules (same resolution and field), camera modes; the proposed pose fix, applied, lints clean."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.sources import lint_description


def _scene(left: str, right: str, *, body: str = "", joint: str = "") -> str:
    return (f'<mujoco><worldbody><body name="head" pos="0 0 1">{joint}'
            f'<camera name="left" {left}/><camera name="right" {right}/>{body}</body></worldbody></mujoco>')


_L = 'pos="0 0.05 0" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"'
_R = 'pos="0 -0.05 0" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"'


def _codes(path: Path, **kwargs: str) -> dict[str, str]:
    return {f.code: f.severity for f in lint_description(path, **kwargs)}  # type: ignore[arg-type]


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.xml"
    path.write_text(text, encoding="utf-8")
    return path


def test_clean_pair(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, _scene(_L, _R))
    assert lint_description(path) == []
    assert main(["lint", str(path)]) == 0
    assert "0 error(s), 0 warning(s)" in capsys.readouterr().out


def test_swapped_pair_and_its_fix(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The right camera on the left: baseline-side, with the camera pose that fixes it; that pose lints clean."""
    wrong = _L.replace("0.05", "0.15").replace(' xyaxes="0 -1 0 0 0 1"', ' euler="90 -90 0"')
    path = _write(tmp_path, _scene(_L, wrong))
    findings = lint_description(path)
    side = next(f for f in findings if f.code == "baseline-side")
    assert side.severity == "error" and side.line == 1
    fix = re.search(r'set camera \'right\' pos="([^"]+)" quat="([^"]+)"', side.fix)
    assert fix, side.fix
    assert main(["lint", str(path)]) == 1
    assert "baseline-side" in capsys.readouterr().out
    fixed = _write(tmp_path, _scene(_L, f'pos="{fix.group(1)}" quat="{fix.group(2)}" fovy="60" resolution="640 480"'))
    assert lint_description(fixed) == []


def test_baseline_along_the_optical_axis(tmp_path: Path) -> None:
    path = _write(tmp_path, _scene(_L, _L.replace('pos="0 0.05 0"', 'pos="0.1 0.05 0"')))
    assert _codes(path)["baseline-axis"] == "error"


def test_pair_rules(tmp_path: Path) -> None:
    assert _codes(_write(tmp_path, _scene(_L, _R.replace("640 480", "1280 720"))))["pair-resolution"] == "error"
    assert _codes(_write(tmp_path, _scene(_L, _R.replace('fovy="60"', 'fovy="61"')))) == {"pair-fov": "warning"}
    sensor = 'sensorsize="0.0064 0.0048" focalpixel="500 500" principalpixel="{p} 0"'
    left = _L.replace('fovy="60"', sensor.format(p=0))
    right = _R.replace('fovy="60"', sensor.format(p=4))
    assert _codes(_write(tmp_path, _scene(left, right))) == {"pair-fov": "warning"}


def test_stretched_pixels(tmp_path: Path) -> None:
    """A 16:9 sensor behind a 4:3 image (a wrist camera's frustum rendered into a 640x480 buffer) stretches it."""
    cams = 'sensorsize="0.00576 0.00324" focal="0.0036 0.0036"'
    path = _write(tmp_path, _scene(_L.replace('fovy="60"', cams), _R.replace('fovy="60"', cams)))
    findings = [f for f in lint_description(path) if f.code == "pixel-aspect"]
    assert len(findings) == 2 and "fx 400.000 and fy 533.333 px differ by 25.0 %" in findings[0].message
    square = _write(tmp_path, _scene(_L.replace('640 480', '1280 720').replace('fovy="60"', cams),
                                     _R.replace('640 480', '1280 720').replace('fovy="60"', cams)))
    assert lint_description(square) == []


def test_modes_offscreen_and_joints(tmp_path: Path) -> None:
    left = _L + ' mode="track"'
    right = _R.replace(' resolution="640 480"', "")
    codes = lint_description(_write(tmp_path, _scene(left, right)))
    messages = [f.message for f in codes if f.code == "mjcf-camera"]
    assert any("'track' moves with the simulation state" in m for m in messages)
    assert any("offscreen buffer size 640x480" in m for m in messages)
    moving = _scene(_L, _R.replace('pos="0 -0.05 0"', 'pos="0 0 0"'),
                    body='<body name="eye" pos="0 -0.05 0"><joint type="hinge"/><geom size="0.01"/>'
                         '<camera name="third" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"/></body>')
    findings = lint_description(_write(tmp_path, moving), left="left", right="third")
    joint = next(f for f in findings if f.code == "movable-joint")
    assert "'<body eye>' (hinge)" in joint.message
