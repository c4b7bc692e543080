"""Lens models of the renderer agree with OpenCV's, and rendered corners obey every supported model."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.errors import RenderError
from s2r.lens.distortion import distort_normalised, project_points, undistort_pixels
from s2r.profile import Camera, Distortion, StereoProfile
from s2r.render import render_board_set
from s2r.render.boards.poses import BoardGeometry
from tests.conftest import make_rig
from tests.render._helpers import detect

MODELS = {
    "plumb_bob": (-0.12, 0.05, 0.001, -0.0008, 0.01),
    "rational_polynomial": (0.3, -0.1, 0.0005, 0.0003, 0.02, 0.42, -0.05, 0.03),
    "equidistant": (-0.02, 0.01, -0.005, 0.001),
}


def _camera(model: str) -> Camera:
    return Camera(width_px=640, height_px=480, fx_px=500.0, fy_px=502.0, cx_px=321.0, cy_px=238.0,
                  distortion=Distortion(model=model, coefficients=MODELS[model]))  # type: ignore[arg-type]


@pytest.mark.parametrize("model", sorted(MODELS))
def test_forward_model_equals_opencv(model: str) -> None:
    cam = _camera(model)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-0.7, 0.7, 200), rng.uniform(-0.5, 0.5, 200), np.ones(200)])
    xd, yd = distort_normalised(cam, pts[:, 0], pts[:, 1])
    mine = np.column_stack([xd * cam.fx_px + cam.cx_px, yd * cam.fy_px + cam.cy_px])
    np.testing.assert_allclose(mine, project_points(cam, pts), atol=1e-9)


@pytest.mark.parametrize("model", sorted(MODELS))
def test_undistort_round_trip(model: str) -> None:
    cam = _camera(model)
    u, v = np.meshgrid(np.linspace(-0.5, 639.5, 41), np.linspace(-0.5, 479.5, 31))
    pix = np.column_stack([u.ravel(), v.ravel()])
    norm = undistort_pixels(cam, pix)
    back = project_points(cam, np.column_stack([norm, np.ones(len(norm))]))
    assert np.max(np.abs(back - pix)) < 1e-6


def test_uninvertible_distortion_is_refused() -> None:
    cam = Camera(width_px=640, height_px=480, fx_px=300.0, fy_px=300.0, cx_px=320.0, cy_px=240.0,
                 distortion=Distortion(coefficients=(-1.5, 0.0, 0.0, 0.0, 0.0)))
    with pytest.raises(RenderError, match=r"^distortion\.coefficients: .*cannot be inverted"):
        undistort_pixels(cam, np.array([[0.0, 0.0], [639.0, 479.0]]))


@pytest.mark.slow
@pytest.mark.parametrize("model", ["rational_polynomial", "equidistant"])
def test_rendered_corners_obey_other_models(model: str, tmp_path: Path) -> None:
    base = make_rig()
    cam = base.left.model_copy(update={"distortion": Distortion(model=model, coefficients=MODELS[model])})  # type: ignore[arg-type]
    profile: StereoProfile = base.model_copy(update={"left": cam, "right": cam})
    result = render_board_set(profile, tmp_path / model, views=2, supersample=2, jobs=1, seed=2)
    board = BoardGeometry((9, 6), 0.025, 1.0)
    for path, T in zip(result.left_paths, result.poses, strict=True):
        found = detect(path, (9, 6))
        assert found is not None
        expected = project_points(cam, board.corners() @ T[:3, :3].T + T[:3, 3])
        assert np.linalg.norm(found - expected, axis=1).mean() < 0.25
    assert cv2.imread(str(result.right_paths[0])).shape == (480, 640, 3)
