"""MuJoCo as a renderer: its camera convention pinned by rendering, s2r's MuJoCo backend (boards, ChArUco and
AprilGrid, depth), ``--world`` scenes, ``export-mujoco`` and the one-line refusals."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from s2r.lens.distortion import project_points
from s2r.profile import Camera, Distortion, Extrinsics, Provenance, SimulationSettings, StereoProfile
from s2r.render import render_board_set, render_scene
from s2r.render.backend import RendererChoice
from s2r.targets import target_from_mapping
from tests.render import mujoco_direct as md
from tests.render._helpers import detect
from tests.render.test_target_boards import APRILGRID, CHARUCO

mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed (pip install 's2r[mujoco]')")


@pytest.fixture(scope="module", autouse=True)
def _gl() -> None:
    from s2r.render.mujoco.backend import gl_unavailable_reason

    reason = gl_unavailable_reason()
    if reason is not None:
        pytest.skip(f"MuJoCo cannot create an offscreen GL context here: {reason}")


def _rig(width: int = 320, height: int = 240) -> StereoProfile:
    """A small rig with fx != fy, off-centre principal points and a slightly turned right camera."""
    left = Camera(width_px=width, height_px=height, fx_px=271.3, fy_px=266.8, cx_px=width / 2 + 7.3,
                  cy_px=height / 2 - 5.6)
    right = Camera(width_px=width, height_px=height, fx_px=268.9, fy_px=265.1, cx_px=width / 2 - 4.2,
                   cy_px=height / 2 + 3.9)
    R = Rotation.from_rotvec(np.radians([0.4, -0.6, 0.3])).as_matrix()
    T = -R @ np.array([0.06, 0.001, -0.002])
    return StereoProfile(
        name="mj_rig", left=left, right=right,
        extrinsics=Extrinsics(rotation=tuple(map(tuple, R.tolist())), translation_m=tuple(T.tolist())),
        simulation=SimulationSettings(clip_near_m=0.05, clip_far_m=50.0),
        provenance=Provenance(origin="sim", method="tests.render.test_mujoco", convention="opencv"))


def test_principal_pixel_convention_by_rendering(tmp_path: Path) -> None:
    """A hand-written camera (focalpixel 300 250, principalpixel 12.5 -7.25 at 320x240) images a board's corners
    where K = [[300, 0, 159.5 - 12.5], [0, 250, 119.5 + 7.25]] puts them: both principal offsets enter with a minus."""
    size = md.board_png(tmp_path / "board.png")
    cams = ('  <worldbody><camera name="c" pos="0 0 0" quat="1 0 0 0" resolution="320 240" sensorsize="0.0032 0.0024"'
            ' focalpixel="300 250" principalpixel="12.5 -7.25"/></worldbody>')
    (tmp_path / "s.xml").write_text(md.scene_xml(cams, tmp_path / "board.png", size, width=320, height=240))
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "s.xml"))
    data = mujoco.MjData(model)
    renderer = mujoco.Renderer(model, 240, 320)
    K = np.array([[300.0, 0.0, 159.5 - 12.5], [0.0, 250.0, 119.5 + 7.25], [0.0, 0.0, 1.0]])
    cols, rows = md.PATTERN  # the board's centre is the centre of its inner-corner grid
    grid = np.array([[(i - (cols - 1) / 2) * md.SQUARE_M, (j - (rows - 1) / 2) * md.SQUARE_M, 0.0]
                     for j in range(rows) for i in range(cols)])
    errors = []
    for k, euler in enumerate(([0, 0, 0], [20, -15, 5], [-25, 20, -5])):
        R_opt = Rotation.from_euler("xyz", euler, degrees=True).as_matrix()
        pos_opt = np.array([0.03 * k - 0.03, 0.02, 0.45])
        flip = np.diag([1.0, -1.0, -1.0])  # optical frame -> MuJoCo camera frame (= world here)
        data.mocap_pos[0] = flip @ pos_opt
        q = Rotation.from_matrix(flip @ R_opt).as_quat()
        data.mocap_quat[0] = [q[3], q[0], q[1], q[2]]
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera="c")
        path = tmp_path / f"{k}.png"
        cv2.imwrite(str(path), renderer.render()[:, :, ::-1])
        found = detect(path, md.PATTERN)
        assert found is not None
        X = grid @ R_opt.T + pos_opt
        uv = X[:, :2] / X[:, 2:] @ K[:2, :2].T + K[:2, 2]
        _, idx = cKDTree(found).query(uv)
        errors.append(found[idx] - uv)
    e = np.concatenate(errors)
    assert np.abs(e.mean(axis=0)).max() < 0.03 and float(np.sqrt((e ** 2).sum(1).mean())) < 0.12
    renderer.close()


@pytest.mark.parametrize("renderer", ["mujoco", "pybullet"])
def test_backend_boards_land_on_the_profile_projection(tmp_path: Path, renderer: str) -> None:
    rig = _rig()
    result = render_board_set(rig, tmp_path, views=4, seed=5, jobs=1, renderer=RendererChoice(renderer))
    truth = yaml.safe_load(result.truth_path.read_text())
    assert truth["renderer"] == renderer
    grid = np.array([[i * 0.025, j * 0.025, 0.0] for j in range(6) for i in range(9)])
    errors = []
    for k, T in enumerate(result.poses):
        for cam, R, t, paths in ((rig.left, np.eye(3), np.zeros(3), result.left_paths),
                                 (rig.right, rig.R, rig.T, result.right_paths)):
            found = detect(paths[k], (9, 6))
            if found is None:
                continue
            uv = project_points(cam, (grid @ T[:3, :3].T + T[:3, 3]) @ R.T + t)
            _, idx = cKDTree(found).query(uv)
            errors.append(found[idx] - uv)
    e = np.concatenate(errors)
    assert len(errors) >= 6
    assert np.abs(e.mean(axis=0)).max() < 0.05 and float(np.sqrt((e ** 2).sum(1).mean())) < 0.2


@pytest.mark.parametrize("spec", [CHARUCO, APRILGRID], ids=["charuco", "aprilgrid"])
def test_mujoco_renders_marker_targets_unmirrored(tmp_path: Path, spec: dict[str, object]) -> None:
    from s2r.calib.detect.markers import detect_target

    rig = _rig(480, 360)
    target = target_from_mapping(spec)
    result = render_board_set(rig, tmp_path, views=3, seed=2, jobs=1, target=target, cut_share=0.0,
                              renderer=RendererChoice("mujoco"))
    seen = 0
    for k, T in enumerate(result.poses):
        found, _ = detect_target(cv2.imread(str(result.left_paths[k]), cv2.IMREAD_GRAYSCALE), target)
        if found is None:
            continue
        ids, pts = found
        expected = project_points(rig.left, target.points_of(ids) @ T[:3, :3].T + T[:3, 3])
        assert float(np.median(np.linalg.norm(pts - expected, axis=1))) < 0.3  # ids decode where they should
        seen += 1
    assert seen >= 2


def test_depth_is_metric_z_along_the_optical_axis() -> None:
    """Fronto-parallel planes at known distances: MuJoCo's depth is z (not the ray length), within 1 mm at 1 m."""
    rig = _rig(160, 120)
    frames = render_scene(rig, scene="planes", distances_m=(0.8, 1.0, 2.0), supersample=1, jobs=1,
                          renderer=RendererChoice("mujoco"))
    for frame, d in zip(frames, (0.8, 1.0, 2.0), strict=True):
        depth = frame.depth_m[np.isfinite(frame.depth_m)]
        assert depth.size > 0.9 * frame.depth_m.size
        assert float(np.abs(depth - d).max()) < 1e-3 * d  # corner pixels are 35 deg off axis: ray length is 1.2 z
        assert frame.description["renderer"] == "mujoco"


def test_world_scene_with_camera_pose_and_its_own_objects(tmp_path: Path) -> None:
    """Boards inserted into a user's MJCF world render from the named camera's pose, among the world's objects."""
    world = tmp_path / "world.xml"
    world.write_text("""<mujoco><compiler angle="degree"/><visual><headlight ambient="0.5 0.5 0.5"/></visual>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom type="plane" size="5 5 0.1" rgba="0.2 0.6 0.2 1"/>
    <body pos="1 2 0.8" euler="0 0 90"><camera name="head" xyaxes="0 -1 0 0 0 1"/></body>
  </worldbody></mujoco>""")
    rig = _rig()
    result = render_board_set(rig, tmp_path / "o", views=2, seed=1, jobs=1,
                              renderer=RendererChoice("mujoco", str(world), "head"))
    found = [detect(p, (9, 6)) for p in result.left_paths]
    assert all(f is not None for f in found)  # the camera looks along the body's +y (world -x): boards in front
    image = cv2.imread(str(result.left_paths[0]))
    bottom = image[-10:, :, :].reshape(-1, 3).mean(axis=0)
    assert bottom[1] > bottom[0] + 10 and bottom[1] > bottom[2] + 10  # the world's green floor below the horizon


def test_export_mujoco_loads_and_holds_the_profile(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = _rig().model_copy(update={"left": _rig().left.model_copy(
        update={"distortion": Distortion(model="plumb_bob", coefficients=(-0.2, 0.05, 0.0, 0.0, 0.0))})})
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(rig.model_dump(mode="json")))
    out = tmp_path / "cams.xml"
    assert main(["profile", "export-mujoco", str(tmp_path / "rig.yaml"), "--body", "head_cam", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "left: MJCF has no lens model" in err and "px" in err and "remap" in err and "right:" not in err
    assert main(["profile", "export-mujoco", str(tmp_path / "rig.yaml"), "-o", str(out)]) == 2  # no --force
    # include-able from a user's scene that has its own <visual>, and loadable alone
    (tmp_path / "scene.xml").write_text('<mujoco><visual><headlight ambient="0.5 0.5 0.5"/></visual>'
                                        '<include file="cams.xml"/><worldbody><geom size="0.1"/></worldbody>'
                                        '</mujoco>')
    for model in (mujoco.MjModel.from_xml_path(str(out)), mujoco.MjModel.from_xml_path(str(tmp_path / "scene.xml"))):
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        poses = {}
        for side, cam in (("left", rig.left), ("right", rig.right)):
            K, R_wo, p_w = md._camera(model, data, f"head_cam_{side}")
            assert np.allclose(K, cam.K, rtol=1e-6, atol=0.0)  # MuJoCo keeps camera intrinsics in float32
            poses[side] = (R_wo, p_w)
        (R_l, p_l), (R_r, p_r) = poses["left"], poses["right"]
        R = R_r.T @ R_l  # X_right = R X_left + T
        T = R_r.T @ (p_l - p_r)
        assert np.allclose(R, rig.R, atol=1e-9) and np.allclose(T, rig.T, atol=1e-9)
        assert np.allclose(R_l, [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-12)  # looks along the body's +x
    assert model.vis.global_.offwidth >= rig.left.width_px


def test_export_mujoco_residual_figures() -> None:
    from s2r.sources.export.mujoco import distortion_residual_px

    cam = Camera(width_px=640, height_px=480, fx_px=500.0, fy_px=500.0, cx_px=319.5, cy_px=239.5,
                 distortion=Distortion(model="plumb_bob", coefficients=(-0.1, 0.0, 0.0, 0.0, 0.0)))
    worst, p95 = distortion_residual_px(cam)
    r = math.hypot(319.5, 239.5) / 500.0  # the image corner, by hand: k1 r^3 f
    assert worst == pytest.approx(0.1 * r ** 3 * 500.0, rel=1e-9) and 0 < p95 < worst
    assert max(distortion_residual_px(cam.model_copy(update={"distortion": Distortion()}))) < 1e-9


@pytest.mark.parametrize(("args", "needle"), [
    (["--renderer", "mujoco", "--world", "nope.xml"], "no such MJCF scene file"),
    (["--world", "W.xml"], "needs the MuJoCo renderer"),
    (["--renderer", "mujoco", "--world", "W.xml", "--world-camera", "nope"], "no camera named 'nope'"),
    (["--renderer", "mujoco", "--world", "BAD.xml"], "MuJoCo cannot"),
])
def test_render_refuses_bad_worlds_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               args: list[str], needle: str) -> None:
    (tmp_path / "W.xml").write_text("<mujoco><worldbody><camera name='head'/></worldbody></mujoco>")
    (tmp_path / "BAD.xml").write_text("<mujoco><worldbody><geom type='nonsense'/></worldbody></mujoco>")
    args = [str(tmp_path / a) if a in ("W.xml", "BAD.xml", "nope.xml") else a for a in args]
    code = main(["render", "boards", "gazebo_dual_camera", "-o", str(tmp_path / "o"), "--views", "1", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and needle in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_unreadable_world_writes_no_mujoco_log(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """MuJoCo writes its warnings to MUJOCO_LOG.TXT in the working directory unless told otherwise."""
    (tmp_path / "world").write_text("<mujoco><bogus/></mujoco>")  # MuJoCo refuses it (s2r reads the file itself now)
    monkeypatch.chdir(tmp_path)
    code = main(["render", "boards", "gazebo_dual_camera", "--renderer", "mujoco", "--world", "world", "-o", "o"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "world: --world: MuJoCo cannot load the scene" in err and len(err.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["world"]


def test_render_cli_mujoco(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = _rig(160, 120)
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(rig.model_dump(mode="json")))
    code = main(["render", "scene", str(tmp_path / "rig.yaml"), "--renderer", "mujoco", "--distances", "1.5",
                 "--supersample", "1", "-o", str(tmp_path / "s"), "--json"])
    assert code == 0 and "s" in capsys.readouterr().out
    depth = np.load(tmp_path / "s" / "depth" / "00.npy")
    assert abs(float(np.nanmedian(depth)) - 1.5) < 1e-3
    assert load_profile_file(tmp_path / "rig.yaml").left.fx_px == rig.left.fx_px


def test_validate_names_the_mujoco_export_and_its_lens_residual() -> None:
    import dataclasses

    from s2r.registry import load_profile
    from s2r.validate.run import QUICK, ValidationResult, _static_stages
    from s2r.validate.summary import summary_lines
    from s2r.validate.tolerances import Tolerances

    small = _rig()
    sim = load_profile("gazebo_dual_camera")
    real = small.model_copy(update={"left": small.left.scaled(640, 480), "right": small.right.scaled(640, 480)})
    real = real.model_copy(update={"left": real.left.model_copy(
        update={"distortion": Distortion(model="plumb_bob", coefficients=(-0.1, 0.0, 0.0, 0.0, 0.0))})})
    for renderer, expected in (("mujoco", 1), ("pybullet", 0)):
        result = ValidationResult(roles={"sim": sim, "real": real},
                                  settings=dataclasses.replace(QUICK, renderer=renderer), tolerances=Tolerances())
        _static_stages(result, sim, real)
        edits = [e for e in result.edits if e.parameter == "MJCF cameras"]
        assert len(edits) == expected
        assert sum("MuJoCo: s2r profile export-mujoco" in line for line in summary_lines(result)) == expected
        if edits:
            where = edits[0].where
            assert "s2r profile export-mujoco mj_rig" in where and "px left by the distortion" in where


def test_missing_mujoco_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "mujoco", None)  # what a machine without the extra sees
    code = main(["render", "boards", "gazebo_dual_camera", "--renderer", "mujoco", "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "MuJoCo is not installed" in err and "s2r[mujoco]" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_gl_probe_names_the_platform_that_fails() -> None:
    """The probe runs in a child process; a platform that cannot render here is named in the reason."""
    from s2r.render.mujoco.backend import _probe

    reason = _probe("no-such-platform")
    assert reason is not None and reason.startswith("MUJOCO_GL=no-such-platform:") and "\n" not in reason
