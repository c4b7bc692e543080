"""PyBullet camera conventions (REFERENCE.md, PyBullet section): projection, offset, view, depth, speckle."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.profile import StereoProfile
from s2r.render.camera import (
    PIXEL_OFFSET,
    PinholeView,
    depth_buffer_to_z,
    projection_matrix,
    render_pinhole,
    view_matrix,
)
from s2r.render.rig import stereo_setups
from s2r.render.sensor import prepared
from s2r.render.textures import checkerboard_texture, speckle_texture, write_png
from s2r.render.world import Surface, set_world, write_mesh

K = np.array([[554.256, 0.0, 319.5], [0.0, 554.256, 239.5], [0.0, 0.0, 1.0]])


def test_projection_matrix_hand_values() -> None:
    P = projection_matrix(K, 640, 480, 0.05, 50.0)
    assert PIXEL_OFFSET == (0.0, 1.0)
    assert P[0, 0] == pytest.approx(2 * 554.256 / 640)
    assert P[1, 1] == pytest.approx(2 * 554.256 / 480)
    assert P[0, 2] == pytest.approx(1 - 2 * 319.5 / 640)  # ox = 0
    assert P[1, 2] == pytest.approx(2 * (239.5 + 1) / 480 - 1)  # oy = +1
    assert P[2, 2] == pytest.approx(-50.05 / 49.95)
    assert P[2, 3] == pytest.approx(-2 * 50 * 0.05 / 49.95)
    assert P[3, 2] == -1.0 and P[3, 3] == 0.0


def test_view_matrix_flips_y_and_z() -> None:
    T = np.eye(4)
    T[:3, 3] = (0.1, 0.2, 0.3)
    V = view_matrix(T)
    np.testing.assert_allclose(V[:3, 3], (0.1, -0.2, -0.3))
    np.testing.assert_allclose(np.diag(V), (1.0, -1.0, -1.0, 1.0))


def test_depth_buffer_conversion_hand_values() -> None:
    near, far = 0.05, 50.0
    d_at_1m = (far - far * near / 1.0) / (far - near)
    z = depth_buffer_to_z(np.array([0.0, d_at_1m, 1.0]), near, far)
    assert z[0] == pytest.approx(near)
    assert z[1] == pytest.approx(1.0, abs=1e-12)
    assert np.isnan(z[2])  # the far plane means nothing was hit


def _dark_quad(tmp_path: Path, u0: float, v0: float, u1: float, v1: float, z: float) -> Surface:
    """A dark quad whose edges project to the pixel coordinates u0..u1, v0..v1 at depth z."""
    x0, x1 = (u0 - K[0, 2]) * z / K[0, 0], (u1 - K[0, 2]) * z / K[0, 0]
    y0, y1 = (v0 - K[1, 2]) * z / K[1, 1], (v1 - K[1, 2]) * z / K[1, 1]
    corners = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])
    mesh = write_mesh(tmp_path / "quad.obj", [(corners, (0.0, 0.0, 1.0, 1.0))])
    texture = write_png(tmp_path / "dark.png", np.zeros((4, 4, 3), np.uint8))
    T = np.eye(4)
    T[2, 3] = z
    return Surface(mesh, texture, T)


def test_pixel_offset_makes_renders_obey_opencv_k(tmp_path: Path) -> None:
    """TinyRenderer samples pixel centres only with (ox, oy) = (0, +1): a quad spanning u 200.3-300.3 and
    v 150.3-250.3 covers exactly columns 201..300 and rows 151..250 (a wrong offset shifts them by one)."""
    set_world([_dark_quad(tmp_path, 200.3, 150.3, 300.3, 250.3, 1.5)])
    rgb, buffer = render_pinhole(PinholeView(K, 640, 480, np.eye(4), 0.05, 50.0))
    z = depth_buffer_to_z(buffer, 0.05, 50.0)
    dark = rgb[..., 0] < 128
    cols = np.nonzero(dark.any(axis=0))[0]
    rows = np.nonzero(dark.any(axis=1))[0]
    assert (cols[0], cols[-1], rows[0], rows[-1]) == (201, 300, 151, 250)
    assert dark.sum() == 100 * 100
    assert np.nanmax(np.abs(z[dark] - 1.5)) < 1e-5  # depth buffer -> metric z (REFERENCE: < 0.01 mm)
    assert np.isnan(z[~dark]).all()


def test_checkerboard_texture_layout() -> None:
    tex = checkerboard_texture((9, 6), texels_per_square=8, border_squares=1.0)
    assert tex.shape == ((6 + 1 + 2) * 8, (9 + 1 + 2) * 8, 3)
    grey = tex[..., 0]
    assert grey[0, 0] > 128  # light margin
    assert grey[8, 8] < 128  # top-left square dark
    assert grey[8, 16] > 128 and grey[16, 8] > 128


def test_speckle_is_seeded_and_not_repeating() -> None:
    a, b = speckle_texture(256, seed=1), speckle_texture(256, seed=1)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, speckle_texture(256, seed=2))
    grey = a[..., 0].astype(np.float64)
    tiles = [grey[i:i + 64, j:j + 64] for i in range(0, 256, 64) for j in range(0, 256, 64)]
    corr = np.corrcoef([t.ravel() for t in tiles])
    assert np.max(np.abs(corr - np.eye(len(tiles)))) < 0.9  # no tile repeats another
    assert grey.std() > 25  # contrast to match on


def test_supersampling_scales_k_about_pixel_edges(rig: StereoProfile) -> None:
    """S = 2: f_hi = 2 f, c_hi = 2 (c + 0.5) - 0.5; output pixel u samples the wide render at 2 (u + 0.5) - 0.5."""
    left, right = stereo_setups(rig, supersample=2)
    prep = prepared(left)
    K = prep.wide.K
    assert (prep.wide.width, prep.wide.height) == (1280, 960) and prep.map_hi is None
    assert K[0, 0] == pytest.approx(2 * rig.left.fx_px) and K[1, 1] == pytest.approx(2 * rig.left.fy_px)
    assert K[0, 2] == pytest.approx(2 * (rig.left.cx_px + 0.5) - 0.5)
    assert K[1, 2] == pytest.approx(2 * (rig.left.cy_px + 0.5) - 0.5)
    assert prep.map_lo[0][0, :3] == pytest.approx([0.5, 2.5, 4.5], abs=1e-4)
    assert prep.map_lo[1][:3, 0] == pytest.approx([0.5, 2.5, 4.5], abs=1e-4)
    np.testing.assert_allclose(right.T_cam_world[:3, :3], rig.R)
    np.testing.assert_allclose(right.T_cam_world[:3, 3], rig.T)  # X_right = R X_left + T
