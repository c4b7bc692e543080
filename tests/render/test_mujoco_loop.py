"""The loop closes in MuJoCo: boards rendered by MuJoCo itself (not through s2r) and calibrated by ``s2r calibrate``
give back the cameras - of a hand-written MJCF scene (bar 2) and of a real calibrated profile exported by
``s2r profile export-mujoco`` (bar 3): fx/fy within 0.1 %, cx/cy within 0.3 px, baseline within 0.2 %, stereo
rotation within 0.1 deg."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from s2r.profile import StereoProfile
from tests.conftest import shared_data
from tests.render import mujoco_direct as md

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed (pip install 's2r[mujoco]')")

pytestmark = pytest.mark.slow

#: (fx, fy, cx, cy) per camera, metres of baseline and the stereo rotation (3x3) to compare with.
Expected = tuple[tuple[float, float, float, float], tuple[float, float, float, float], float, np.ndarray]


@pytest.fixture(scope="module", autouse=True)
def _gl() -> None:
    from s2r.render.mujoco.backend import gl_unavailable_reason

    reason = gl_unavailable_reason()
    if reason is not None:
        pytest.skip(f"MuJoCo cannot create an offscreen GL context here: {reason}")


def _calibrate(tmp: Path, cameras_xml: str, left: str, right: str) -> StereoProfile:
    """Render 40 board views through the scene's cameras with MuJoCo and calibrate them with s2r's defaults."""
    size = md.board_png(tmp / "board.png")
    (tmp / "scene.xml").write_text(md.scene_xml(cameras_xml, tmp / "board.png", size, width=640, height=480))
    views = md.render_views(tmp / "scene.xml", tmp / "set", left=left, right=right, views=40, seed=1, size_m=size)
    assert views >= 30
    out = tmp / "calibrated.yaml"
    pattern = f"{md.PATTERN[0]}x{md.PATTERN[1]}"
    assert main(["calibrate", str(tmp / "set"), "--pattern", pattern, "--square", str(md.SQUARE_M), "-o", str(out),
                 "--jobs", "1"]) == 0
    return load_profile_file(out)


def _check(got: StereoProfile, expected: Expected) -> dict[str, float]:
    worst = {"focal_pct": 0.0, "principal_px": 0.0}
    for cam, (fx, fy, cx, cy) in ((got.left, expected[0]), (got.right, expected[1])):
        worst["focal_pct"] = max(worst["focal_pct"], 100 * abs(cam.fx_px / fx - 1), 100 * abs(cam.fy_px / fy - 1))
        worst["principal_px"] = max(worst["principal_px"], abs(cam.cx_px - cx), abs(cam.cy_px - cy))
    worst["baseline_pct"] = 100 * abs(got.baseline_m / expected[2] - 1)
    worst["rotation_deg"] = math.degrees(float(np.linalg.norm(Rotation.from_matrix(got.R @ expected[3].T)
                                                              .as_rotvec())))
    print("round trip:", {k: round(v, 4) for k, v in worst.items()})
    assert worst["focal_pct"] < 0.1, worst
    assert worst["principal_px"] < 0.3, worst
    assert worst["baseline_pct"] < 0.2, worst
    assert worst["rotation_deg"] < 0.1, worst
    return worst


def _optical_from_xyaxes(x: list[float], y: list[float]) -> np.ndarray:
    """Columns: the OpenCV optical axes, in the parent frame, of a camera given by MJCF ``xyaxes`` (MuJoCo's
    documentation: x normalised, y made orthogonal to x and normalised, z = x cross y; the camera looks along -z
    with +y up, so the optical frame is (x, -y, -z))."""
    ax = np.array(x, float) / np.linalg.norm(x)
    ay = np.array(y, float) - ax * (ax @ np.array(y, float))
    ay /= np.linalg.norm(ay)
    return np.column_stack([ax, -ay, -np.cross(ax, ay)])


def test_hand_written_scene_round_trip(tmp_path: Path) -> None:
    """Bar 2: nested bodies (euler in radians, quat), cameras by focal + principal (metres) and by focalpixel +
    principalpixel; the expected intrinsics and extrinsics are derived by hand from MuJoCo's documentation."""
    cameras = """  <compiler angle="radian"/>
  <worldbody>
    <body name="robot" pos="0.2 -0.1 0.5" euler="0 0 0.3">
      <body name="head" pos="0.05 0 0.3" quat="0.9961947 0 0.0871557 0">
        <camera name="L" pos="0 0.04 0" xyaxes="0 -1 0 0 0 1" resolution="640 480" sensorsize="0.00384 0.00288"
                focal="0.0033 0.00324" principal="0.00006 -0.000036"/>
        <camera name="R" pos="0.001 -0.04 0.0005" xyaxes="0 -1 0 0.01 0 1" resolution="640 480"
                sensorsize="0.00384 0.00288" focalpixel="545 538" principalpixel="-8 5"/>
      </body>
    </body>
  </worldbody>"""
    # pixel pitch 0.00384 / 640 = 6 um: fx = 3.3 mm / 6 um = 550, fy = 540, px = 10, py = -6 (both enter with a minus)
    left = (550.0, 540.0, 319.5 - 10.0, 239.5 + 6.0)
    right = (545.0, 538.0, 319.5 + 8.0, 239.5 - 5.0)
    R_hl, R_hr = _optical_from_xyaxes([0, -1, 0], [0, 0, 1]), _optical_from_xyaxes([0, -1, 0], [0.01, 0, 1])
    T = R_hr.T @ (np.array([0.0, 0.04, 0.0]) - np.array([0.001, -0.04, 0.0005]))  # X_right = R X_left + T
    got = _calibrate(tmp_path, cameras, "L", "R")
    assert got.T[0] < 0  # the right camera is on the right
    _check(got, (left, right, float(np.linalg.norm(T)), R_hr.T @ R_hl))


def test_exported_real_profile_round_trip(tmp_path: Path) -> None:
    """Bar 3: OpenCV's real stereo sample calibrated by s2r (fx != fy, principal points 22 and 10 px off centre),
    exported with export-mujoco, included in a scene, rendered by MuJoCo, calibrated again: its pinhole part back."""
    data = shared_data("opencv_stereo_chessboard")
    real_path = tmp_path / "real.yaml"
    assert main(["calibrate", str(data), "--pattern", "9x6", "--square", "0.025", "-o", str(real_path),
                 "--jobs", "1"]) == 0
    real = load_profile_file(real_path).in_opencv_pixels()
    assert real.right.fx_px != real.right.fy_px and abs(real.left.cx_px - 319.5) > 10
    cams = tmp_path / "cams.xml"
    assert main(["profile", "export-mujoco", str(real_path), "-o", str(cams)]) == 0
    got = _calibrate(tmp_path, '  <include file="cams.xml"/>', "s2r_stereo_left", "s2r_stereo_right")
    expected = tuple((c.fx_px, c.fy_px, c.cx_px, c.cy_px) for c in (real.left, real.right))
    _check(got, (expected[0], expected[1], real.baseline_m, real.R))


def test_validate_takes_the_exported_mjcf_and_fails_only_the_lens(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 20's loop: ``s2r validate cameras.xml real.yaml --renderer mujoco`` reads the MJCF as the sim (as
    from-description would) and fails only on what MJCF cannot hold, naming the export and its residual."""
    import json

    from s2r.formats.s2r_yaml import dump_profile
    from tests.conftest import make_rig

    real = make_rig(name="lensed", width=320, height=240, hfov_rad=1.1, baseline_m=0.06, cx=171.3, cy=113.8,
                    distortion=(-0.12, 0.03, 0.0, 0.0, 0.0), origin="real")
    real_path = dump_profile(real, tmp_path / "real.yaml")
    cameras = tmp_path / "cameras.xml"
    assert main(["-q", "profile", "export-mujoco", str(real_path), "-o", str(cameras)]) == 0
    capsys.readouterr()
    code = main(["-q", "validate", str(cameras), str(real_path), "--quick", "--renderer", "mujoco", "--json",
                 "--jobs", "1"])
    result = json.loads(capsys.readouterr().out)
    failed = [c["name"] for c in result["checks"] if not c["passed"]]
    assert code == 1 and {"left distortion", "right distortion"} <= set(failed), failed
    # one root cause explains every failure (the depth gaps too: rectifying a distorted image rescales it)
    assert [cause["title"] for cause in result["root_causes"]] == ["Lens distortion"]
    assert set(failed) == set(result["root_causes"][0]["checks"])
    assert "export-mujoco" in json.dumps(result)  # the export that writes the pair, and its lens residual
