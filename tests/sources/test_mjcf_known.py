"""MJCF cameras against values derived by hand from MuJoCo's documentation (no MuJoCo needed): intrinsics of every
form, Euler sequences against SciPy (whose lowercase/uppercase convention is MuJoCo's the other way round), the
default-class and include rules, and what a camera without a resolution says."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.sources import load_description, load_description_profile, stereo_pair

_FLIP = np.diag([1.0, -1.0, -1.0])  # MuJoCo camera frame -> OpenCV optical frame


def _write(tmp_path: Path, text: str, name: str = "scene.xml") -> Path:
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _pair_scene(cams: str) -> str:
    return (f'<mujoco><worldbody><body name="head" pos="0 0 1">'
            f'<camera name="left" pos="0 0.05 0" xyaxes="0 -1 0 0 0 1" {cams}/>'
            f'<camera name="right" pos="0 -0.05 0" xyaxes="0 -1 0 0 0 1" {cams}/></body></worldbody></mujoco>')


@pytest.mark.parametrize(("cams", "expected"), [
    ('fovy="60" resolution="640 480"', (640, 480, 240 / math.tan(math.radians(30)), None, 319.5, 239.5)),
    ('resolution="640 480"', (640, 480, 240 / math.tan(math.radians(22.5)), None, 319.5, 239.5)),  # fovy 45
    ('fovy="90" resolution="480 640"', (480, 640, 320.0, 320.0, 239.5, 319.5)),  # portrait: fovy stays vertical
    # SO-101 (mujoco_menagerie robotstudio_so101) wrist camera: 3.6 mm lens on a 5.76 x 3.24 mm sensor
    ('resolution="1920 1080" sensorsize="0.00576 0.00324" focal="0.0036 0.0036"',
     (1920, 1080, 1200, 1200, 959.5, 539.5)),
    ('resolution="640 480" sensorsize="0.0064 0.0048" focalpixel="500 400" principalpixel="10 0"',
     (640, 480, 500, 400, 309.5, 239.5)),
    ('resolution="640 480" sensorsize="0.0064 0.0048" focalpixel="500 400" principalpixel="-20 5"',
     (640, 480, 500, 400, 339.5, 234.5)),
    ('resolution="800 600" sensorsize="0.008 0.006" focal="0.004 0.005" principal="0.0001 0.0002"',
     (800, 600, 400, 500, 399.5 - 10, 299.5 - 20)),
    # a pixel value wins over its length value, axis by axis
    ('resolution="800 600" sensorsize="0.008 0.006" focal="0.004 0.005" focalpixel="0 450" principalpixel="3 0"'
     ' principal="0.0001 0.0002"', (800, 600, 400, 450, 399.5 - 3, 299.5 - 20)),
])
def test_intrinsics_by_hand(cams: str, expected: tuple[float, ...], tmp_path: Path) -> None:
    width, height, fx, fy, cx, cy = expected
    profile = load_description_profile(_write(tmp_path, _pair_scene(cams)))
    cam = profile.left
    assert (cam.width_px, cam.height_px) == (width, height)
    got = (cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px)
    np.testing.assert_allclose(got, (fx, fx if fy is None else fy, cx, cy), rtol=1e-9)
    assert profile.right.K.tolist() == cam.K.tolist()
    np.testing.assert_allclose(profile.T, [-0.1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(profile.R, np.eye(3), atol=1e-12)
    assert profile.provenance.convention == "exact" and "from-description (mjcf)" in profile.provenance.method


def _right_rotation(tmp_path: Path, compiler: str, orientation: str) -> np.ndarray:
    """The right camera's MuJoCo frame rotation when the left camera is the world frame."""
    text = (f'<mujoco><compiler {compiler}/><worldbody><camera name="left" resolution="64 48"/>'
            f'<camera name="right" pos="0.1 0 0" {orientation} resolution="64 48"/></worldbody></mujoco>')
    pair = stereo_pair(load_description(_write(tmp_path, text)), left="left", right="right")
    return np.asarray(_FLIP @ pair.T_left_right[:3, :3] @ _FLIP)


@pytest.mark.parametrize("seq", ["xyz", "XYZ", "zyx", "ZYX", "xYz", "ZyX", "yzy"])
def test_euler_sequences_by_hand(seq: str, tmp_path: Path) -> None:
    angles = (20.0, -35.0, 50.0)
    got = _right_rotation(tmp_path, f'eulerseq="{seq}"', 'euler="20 -35 50"')
    np.testing.assert_allclose(got, _euler(seq, angles, degrees=True), atol=1e-12)
    radian = _right_rotation(tmp_path, f'angle="radian" eulerseq="{seq}"', 'euler="0.3 -0.6 0.9"')
    np.testing.assert_allclose(radian, _euler(seq, (0.3, -0.6, 0.9), degrees=False), atol=1e-12)


def _euler(seq: str, angles: tuple[float, ...], *, degrees: bool) -> np.ndarray:
    """MuJoCo's documented rule: a lowercase axis turns with the frame (intrinsic), an uppercase one is the parent's.
    For a pure sequence this is SciPy's with the case swapped (SciPy: uppercase = intrinsic)."""
    if seq.islower() or seq.isupper():
        return np.asarray(Rotation.from_euler(seq.swapcase(), angles, degrees=degrees).as_matrix())
    R = np.eye(3)
    for axis, angle in zip(seq, angles, strict=True):
        turn = Rotation.from_euler(axis.lower(), angle, degrees=degrees).as_matrix()
        R = R @ turn if axis.islower() else turn @ R
    return R


@pytest.mark.parametrize(("orientation", "expected"), [
    ('quat="2 0 0 2"', Rotation.from_rotvec([0, 0, math.pi / 2])),
    ('axisangle="0 0 3 -90"', Rotation.from_rotvec([0, 0, -math.pi / 2])),
    ('xyaxes="0 1 0 -1 0.3 0"', Rotation.from_rotvec([0, 0, math.pi / 2])),  # y made orthogonal to x
    ('zaxis="1 0 0"', Rotation.from_rotvec([0, math.pi / 2, 0])),  # the minimal turn taking z onto x
    ('zaxis="0 0 -1"', Rotation.from_rotvec([math.pi, 0, 0])),  # opposite: MuJoCo turns about x
])
def test_orientation_forms_by_hand(orientation: str, expected: Rotation, tmp_path: Path) -> None:
    np.testing.assert_allclose(_right_rotation(tmp_path, 'angle="degree"', orientation), expected.as_matrix(),
                               atol=1e-12)


def test_class_orientation_yields_to_the_element(tmp_path: Path) -> None:
    """A class's orientation is used only when the element writes none (any of the five forms)."""
    text = ('<mujoco><default><camera euler="0 0 90" resolution="64 48"/></default><worldbody>'
            '<camera name="left" quat="1 0 0 0"/><camera name="right" pos="0.1 0 0"/></worldbody></mujoco>')
    pair = stereo_pair(load_description(_write(tmp_path, text)), left="left", right="right")
    np.testing.assert_allclose(_FLIP @ pair.T_left_right[:3, :3] @ _FLIP,
                               Rotation.from_rotvec([0, 0, math.pi / 2]).as_matrix(), atol=1e-12)


def test_include_relative_to_the_scene_then_the_including_file(tmp_path: Path) -> None:
    _write(tmp_path, '<mujoco><include file="b.xml"/></mujoco>', "parts/a.xml")  # b.xml next to a.xml
    _write(tmp_path, '<mujoco><camera name="right" pos="0.2 0 0" resolution="64 48"/></mujoco>', "parts/b.xml")
    scene = _write(tmp_path, '<mujoco><worldbody><camera name="left" resolution="64 48"/>'
                   '<include file="parts/a.xml"/></worldbody></mujoco>')
    description = load_description(scene)
    pair = stereo_pair(description, left="left", right="right")
    np.testing.assert_allclose(pair.T_left_right[:3, 3], [0.2, 0, 0], atol=1e-12)
    assert [p.name for p in description.included_files] == ["a.xml", "b.xml"]  # in the provenance's sources


def test_offscreen_size_and_its_remark(tmp_path: Path) -> None:
    text = ('<mujoco><visual><global offheight="720"/></visual><worldbody><camera name="left" fovy="50"/>'
            '<camera name="right" pos="0.1 0 0" fovy="50"/></worldbody></mujoco>')
    camera = load_description(_write(tmp_path, text)).cameras[0]
    assert (camera.width, camera.height) == (640, 720)
    assert camera.remarks and "offscreen buffer size 640x720" in camera.remarks[0]
    assert camera.lens is not None
    assert math.isclose(camera.lens.fy, 360 / math.tan(math.radians(25)), rel_tol=1e-12)


def test_attach_is_named_and_the_rest_read(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    text = _pair_scene('resolution="640 480"').replace(
        "</body>", '<attach model="gripper" body="hand" prefix="g_"/></body>')
    with caplog.at_level("WARNING", logger="s2r"):
        description = load_description(_write(tmp_path, text))
    assert [c.name for c in description.cameras] == ["left", "right"]
    assert "<attach> line 1: the cameras of an attached model are not read" in caplog.text


def test_included_camera_has_no_scene_line(tmp_path: Path) -> None:
    _write(tmp_path, '<mujoco><camera name="right" pos="0.1 0 0" resolution="64 48"/>\n</mujoco>', "eyes.xml")
    scene = _write(tmp_path, '<mujoco><worldbody><camera name="left" resolution="64 48"/>\n\n\n'
                   '<include file="eyes.xml"/></worldbody></mujoco>')
    left, right = load_description(scene).cameras
    assert left.lines["camera"] == 1 and right.lines["camera"] is None


def test_clip_planes_from_a_written_extent(tmp_path: Path) -> None:
    """MuJoCo's clip planes are <map znear zfar> (defaults 0.01 and 50) times the model's extent."""
    text = _pair_scene('resolution="640 480"').replace(
        "<worldbody>", '<statistic extent="2"/><visual><map znear="0.05"/></visual><worldbody>')
    profile = load_description_profile(_write(tmp_path, text))
    assert (profile.simulation.clip_near_m, profile.simulation.clip_far_m) == pytest.approx((0.1, 100.0))
    unknown = load_description_profile(_write(tmp_path, _pair_scene('resolution="640 480"')))
    assert "clip planes not read" in unknown.provenance.notes
