"""Wide fisheye lenses rendered through the cube map: seams, exact depth, black outside the lens field."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from s2r.cli import main
from s2r.errors import S2RError
from s2r.profile import Distortion
from s2r.rectification import DEFAULT_FISHEYE_FOV_DEG, stereo_rectification
from s2r.render.cubemap import lens_rays
from s2r.render.rig import stereo_setups
from s2r.render.scenes import render_boards_at, render_scene
from s2r.render.sensor import prepared
from tests.conftest import make_rig
from tests.render._helpers import SUBPIX, t265_rig

F64 = NDArray[np.float64]
PATTERN = (9, 6)
SQUARE_M = 0.02


def _board_pose(direction: F64, distance: float, spin: float) -> F64:
    """T_left_board of a board facing the camera with its centre on ``direction`` at ``distance`` metres."""
    z = np.asarray(direction, np.float64) / np.linalg.norm(direction)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z]) @ cv2.Rodrigues(np.array([0.0, 0.0, spin]))[0]
    centre = np.array([(PATTERN[0] - 1) * SQUARE_M / 2, (PATTERN[1] - 1) * SQUARE_M / 2, 0.0])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, z * distance - R @ centre
    return T


def test_only_lenses_too_wide_for_one_pinhole_take_the_cube_map() -> None:
    wide = prepared(stereo_setups(t265_rig(), supersample=1)[0])
    assert wide.cube is not None and len(wide.cube.faces) == 5  # front and four sides, no back face
    moderate = make_rig(name="fish_moderate", hfov_rad=2 * math.atan(0.8))  # fx 400 px, ~100 deg diagonal
    d = Distortion(model="equidistant", coefficients=(-0.01, 0.02, -0.01, 0.002))
    moderate = moderate.model_copy(update={"left": moderate.left.model_copy(update={"distortion": d})})
    assert prepared(stereo_setups(moderate, supersample=1)[0]).cube is None  # one wide pinhole, as before


def test_lens_rays_invert_opencv_fisheye_projection() -> None:
    cam = t265_rig().left
    rng = np.random.default_rng(3)
    pix = np.column_stack([rng.uniform(0, 847, 500), rng.uniform(0, 799, 500)])
    rays, ok = lens_rays(cam, pix)
    assert 0.5 < ok.mean() < 1.0  # the image corners lie beyond the model's 90 degrees
    back, _ = cv2.fisheye.projectPoints(rays[ok].reshape(-1, 1, 3), np.zeros(3), np.zeros(3), cam.K, cam.D)
    np.testing.assert_allclose(back.reshape(-1, 2), pix[ok], atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, atol=1e-12)


def test_corners_across_face_seams_match_the_known_projection() -> None:
    """Boards straddling the front/right seam and a cube corner (three faces): every face's corners land on
    OpenCV's fisheye projection of the true pose, no shift between faces."""
    profile = t265_rig()
    cam = profile.left
    cube = prepared(stereo_setups(profile, supersample=2)[0]).cube
    assert cube is not None
    poses = [_board_pose(np.array([1.0, 0.0, 1.0]), 0.35, 0.3), _board_pose(np.array([1.0, 1.0, 1.2]), 0.35, 0.1)]
    obj = np.zeros((PATTERN[0] * PATTERN[1], 3))
    obj[:, :2] = np.mgrid[0:PATTERN[0], 0:PATTERN[1]].T.reshape(-1, 2) * SQUARE_M
    images = render_boards_at(profile, poses, pattern=PATTERN, square_m=SQUARE_M, supersample=2, jobs=1)
    for T, (left, _right) in zip(poses, images, strict=True):
        grey = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY)
        found, corners = cv2.findChessboardCorners(grey, PATTERN, flags=cv2.CALIB_CB_ADAPTIVE_THRESH
                                                   | cv2.CALIB_CB_NORMALIZE_IMAGE)
        assert found
        corners = cv2.cornerSubPix(grey, corners, (4, 4), (-1, -1), SUBPIX).reshape(-1, 2)
        X = obj @ T[:3, :3].T + T[:3, 3]
        truth, _ = cv2.fisheye.projectPoints(X.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), cam.K, cam.D)
        truth = truth.reshape(-1, 2)
        if np.linalg.norm(corners[0] - truth[0]) > np.linalg.norm(corners[-1] - truth[0]):
            corners = corners[::-1]
        err = corners - truth
        face = np.argmax(X @ cube.axes.T, axis=1)
        assert len(set(face.tolist())) >= 2  # the board really crosses a seam
        assert float(np.sqrt(np.mean(np.sum(err**2, axis=1)))) < 0.15
        for k in set(face.tolist()):
            shift = err[face == k].mean(axis=0)
            assert np.all(np.abs(shift) < 0.06), (k, shift)  # no half-pixel offsets between faces


def test_cube_map_depth_is_exact_and_black_outside_the_lens_field() -> None:
    profile = t265_rig()
    frame = render_scene(profile, scene="planes", distances_m=(1.2,), supersample=1, jobs=1)[0]
    depth = frame.depth_m
    seen = np.isfinite(depth)
    assert seen.mean() > 0.4  # the plane fills the central ~62 degrees of the circle
    np.testing.assert_allclose(depth[seen], 1.2, rtol=1e-5)  # z along the left axis, side faces included
    assert np.all(frame.left[:3, :3] == 0) and np.all(np.isnan(depth[:3, :3]))  # corner beyond 90 degrees: black
    # Rectified ground truth (90 deg rectified field): Z_rect of the plane z_left = 1.2 along each rectified ray.
    rect = stereo_rectification(profile, alpha=0.0)
    h, w = frame.depth_rect_m.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    rays = rect.R1.T @ np.linalg.inv(rect.P1[:3, :3]) @ np.vstack([u.ravel(), v.ravel(), np.ones(u.size)])
    z_rect = (rect.R1 @ (rays * (1.2 / rays[2])))[2].reshape(h, w)
    assert np.isfinite(frame.depth_rect_m).mean() > 0.99
    np.testing.assert_allclose(frame.depth_rect_m, z_rect, rtol=1e-4)


def test_fisheye_rectification_caps_the_field_of_view() -> None:
    profile = t265_rig()
    rect = stereo_rectification(profile)
    fov = 2 * math.degrees(math.atan(0.5 * 848 / rect.fx_px))
    assert fov == pytest.approx(DEFAULT_FISHEYE_FOV_DEG)
    assert rect.P1[0, 2] == pytest.approx(423.5) and rect.P1[1, 2] == pytest.approx(399.5)
    assert rect.baseline_m == pytest.approx(np.linalg.norm(profile.T), rel=1e-9)
    point = np.array([0.1, -0.05, 1.5, 1.0])  # the rectified pair triangulates through Q
    xl = rect.R1 @ point[:3]
    ul, ur = (P @ np.append(xl, 1.0) for P in (rect.P1, rect.P2))
    q = rect.Q @ np.array([ul[0] / ul[2], ul[1] / ul[2], ul[0] / ul[2] - ur[0] / ur[2], 1.0])
    np.testing.assert_allclose(q[:3] / q[3], xl, atol=1e-9)
    wider = stereo_rectification(profile, fov_deg=120.0)
    assert 2 * math.degrees(math.atan(0.5 * 848 / wider.fx_px)) == pytest.approx(120.0)
    with pytest.raises(S2RError, match="field of view"):
        stereo_rectification(profile, fov_deg=179.0)


def test_depth_fov_out_of_range_is_a_one_line_refusal(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["depth", str(tmp_path / "l.png"), str(tmp_path / "r.png"), "--profile", "gazebo_dual_camera",
                 "--fov", "200", "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "--fov" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
