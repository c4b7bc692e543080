"""Gazebo conventions pinned with hand-computed values (REFERENCE.md)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from s2r.errors import SourceError
from s2r.sources.conventions import (
    crop_magnification,
    focal_from_hfov,
    gazebo_to_opencv_distortion,
    gz_sim_distortion_scale,
    hfov_from_focal,
    intrinsics_for,
    opencv_to_gazebo_distortion,
    scale_distortion,
)
from s2r.sources.description import LensIntrinsics

# 640 / (2 tan(1.047 / 2)): tan(0.5235) = 0.577215... -> 554.3827 px (the seed's ~60 deg camera)
F_SEED = 554.3827128226441


def test_focal_from_hfov_seed_and_xbot() -> None:
    assert focal_from_hfov(640, 1.047) == pytest.approx(F_SEED, abs=1e-9)
    # 1.57 is not exactly pi/2: tan(0.785) = 0.999204 -> 320 / 0.999204 = 320.2549 (not 320.0)
    assert focal_from_hfov(640, 1.57) == pytest.approx(320.255, abs=5e-4)
    assert focal_from_hfov(640, math.pi / 2) == pytest.approx(320.0, abs=1e-9)


def test_hfov_from_focal_is_the_exact_inverse() -> None:
    for hfov in (0.3, 1.047, 1.57, 2.5):
        assert hfov_from_focal(848, focal_from_hfov(848, hfov)) == pytest.approx(hfov, rel=1e-14)
    # the seed's camera_info fx 381.36 at 640 px is 2 atan(320 / 381.36) = 1.3963 rad = 80.0 deg
    assert math.degrees(hfov_from_focal(640, 381.36)) == pytest.approx(80.0, abs=0.01)


@pytest.mark.parametrize(("convention", "cx", "cy"), [
    ("gazebo-classic", 320.5, 240.5),  # (W + 1) / 2, (H + 1) / 2
    ("gz-sim", 320.0, 240.0),          # W / 2, H / 2
    ("exact", 319.5, 239.5),           # (W - 1) / 2, (H - 1) / 2
])
def test_principal_point_per_convention(convention: str, cx: float, cy: float) -> None:
    k = intrinsics_for(640, 480, 1.047, convention)
    assert k.fx == pytest.approx(F_SEED) and k.fy == pytest.approx(F_SEED)
    assert (k.cx, k.cy) == (cx, cy)


def test_lens_intrinsics_override_horizontal_fov_in_both_simulators() -> None:
    """gazebo-classic Camera::LoadCameraIntrinsics and gz-sensors both render with <lens><intrinsics>; its cx, cy
    are continuous pixels (OpenCV's + 0.5): 318.0 -> 317.5 exact, 318.0 gz-sim, 318.5 classic (+1 convention)."""
    lens = LensIntrinsics(fx=500.0, fy=501.0, cx=318.0, cy=242.0, s=0.5)
    assert tuple(intrinsics_for(640, 480, 1.047, "gz-sim", lens)) == (500.0, 501.0, 318.0, 242.0, 0.5)
    assert tuple(intrinsics_for(640, 480, 1.047, "gazebo-classic", lens)) == (500.0, 501.0, 318.5, 242.5, 0.5)
    assert tuple(intrinsics_for(640, 480, 1.047, "exact", lens))[2:4] == (317.5, 241.5)


def _gz_rendering_distort(t: np.ndarray, center: tuple[float, float], k: tuple[float, ...], w: int, h: int,
                          hfov: float | None) -> np.ndarray:
    """gz-rendering ogre/src/OgreDistortionPass.cc Distort() with CreateRenderPass()'s texSize and focalLength,
    written from the source: S = max(W, H), fov = FOVy * aspect (W >= H), F = S / (2 tan(fov / 2)).
    ``hfov`` None: F = S, which is Gazebo classic's legacy Distortion::Distort (texture offsets as they are)."""
    k1, k2, k3, p1, p2 = k
    aspect = w / h
    size = max(w, h)
    f = float(size)
    if hfov is not None:
        fovy = 2 * math.atan(math.tan(hfov / 2) / aspect)  # OgreCamera::SetHFOV
        f = size / (2 * math.tan(fovy * aspect / 2))
    n = (t - np.array(center)) * (size / f)
    x, y = n[:, 0], n[:, 1]
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    dx = x * radial + p2 * (r2 + 2 * x * x) + 2 * p1 * x * y
    dy = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return (np.array(center) * size + np.column_stack([dx, dy]) * f) / size


def test_gz_sim_distortion_units_are_image_normalised_ones_scaled() -> None:
    """gz-sim's k1 = classic's (image-normalised) k1 / s^2 etc., s = 2 tan(fov / 2): the two maps are identical."""
    w, h, hfov = 640, 480, 1.2
    s = gz_sim_distortion_scale(w, h, hfov)
    fovy = 2 * math.atan(math.tan(0.6) / (4 / 3))
    assert s == pytest.approx(2 * math.tan(fovy * (4 / 3) / 2), rel=1e-15)  # 1.5097..., not 2 tan(0.6) = 1.3683
    classic = (-0.31, 0.09, 0.01, 0.002, -0.001)
    gz = scale_distortion(classic, s)
    assert gz[0] == pytest.approx(-0.31 / s**2) and gz[3] == pytest.approx(0.002 / s)
    t = np.column_stack([g.ravel() for g in np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 7))])
    center = (0.53, 0.49)
    expected = _gz_rendering_distort(t, center, gz, w, h, hfov)
    legacy = _gz_rendering_distort(t, center, classic, w, h, None)
    assert np.abs(expected - legacy).max() < 1e-12
    assert scale_distortion(gz, 1 / s) == pytest.approx(classic, rel=1e-12)


def test_crop_magnification_hand_value() -> None:
    """k1 = -0.2 about the centre: corner offset 0.5 (r^2 = 0.5) -> 0.5 (1 - 0.1) = 0.45, span 0.9, x 1/0.9."""
    mx, my = crop_magnification((-0.2, 0.0, 0.0, 0.0, 0.0), (0.5, 0.5))
    assert (mx, my) == (pytest.approx(1 / 0.9), pytest.approx(1 / 0.9))
    assert crop_magnification((0.1, 0.0, 0.0, 0.0, 0.0), (0.5, 0.5)) == (1.0, 1.0)  # only barrel is cropped


def test_unknown_convention_is_refused() -> None:
    with pytest.raises(SourceError, match=r"--convention.*gazebo-classic, gz-sim, exact"):
        intrinsics_for(640, 480, 1.0, "ros")


def test_square_image_distortion_conversion_is_exact() -> None:
    # 480x480, f = 400: a = f / W = 5/6; k1_cv = k1 a^2, k2_cv = k2 a^4, k3_cv = k3 a^6, p_cv = p a
    a = 400.0 / 480.0
    fit = gazebo_to_opencv_distortion(-0.2, 0.05, 0.01, 0.001, -0.002, width=480, height=480, fx=400.0, fy=400.0)
    k1, k2, p1, p2, k3 = fit.coefficients
    assert k1 == pytest.approx(-0.2 * a**2, rel=1e-9)   # -0.138889
    assert k2 == pytest.approx(0.05 * a**4, rel=1e-9)   # 0.024113
    assert k3 == pytest.approx(0.01 * a**6, rel=1e-9)
    assert p1 == pytest.approx(0.001 * a, rel=1e-9)
    assert p2 == pytest.approx(-0.002 * a, rel=1e-9)
    assert fit.max_px < 1e-9
    back = opencv_to_gazebo_distortion(fit.coefficients, width=480, height=480, fx=400.0, fy=400.0)
    assert back.coefficients == pytest.approx((-0.2, 0.05, 0.01, 0.001, -0.002), rel=1e-9)


def _gazebo_distort(u: np.ndarray, v: np.ndarray, k: tuple[float, ...], w: int, h: int) -> np.ndarray:
    """Gazebo classic's Distortion::Distort on texture coordinates (centre 0.5, 0.5), back in pixels."""
    k1, k2, k3, p1, p2 = k
    x, y = (u + 0.5) / w - 0.5, (v + 0.5) / h - 0.5
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    xd = x * radial + p2 * (r2 + 2 * x * x) + 2 * p1 * x * y
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.column_stack([(xd + 0.5) * w - 0.5, (yd + 0.5) * h - 0.5])


def test_non_square_conversion_reports_its_true_pixel_error() -> None:
    """640x480: no exact equivalent; the reported worst error bounds cv2.projectPoints vs Gazebo's formula."""
    w, h, f = 640, 480, 554.38
    gz = (-0.25, 0.08, 0.0, 0.0, 0.0)
    fit = gazebo_to_opencv_distortion(*gz, width=w, height=h, fx=f, fy=f)
    assert fit.max_px > 0.01  # not exact ...
    grid_u, grid_v = np.meshgrid(np.linspace(0, w - 1, 25), np.linspace(0, h - 1, 25))
    u, v = grid_u.ravel(), grid_v.ravel()
    cx, cy = (w - 1) / 2, (h - 1) / 2
    rays = np.column_stack([(u - cx) / f, (v - cy) / f, np.ones_like(u)])
    K = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1.0]])
    cv_px = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, np.array(fit.coefficients))[0].reshape(-1, 2)
    err = np.hypot(*(cv_px - _gazebo_distort(u, v, gz, w, h)).T)
    assert err.max() <= fit.max_px + 1e-6  # ... and the reported figure is the real one
    assert err.max() == pytest.approx(fit.max_px, rel=1e-6)
