"""A lens model that folds over inside the image is found, named and judged poor.

The fold radius is checked against OpenCV's own distortion (``cv2.projectPoints`` of rays at growing angles:
where the pixel radius stops growing), on a strong barrel lens, a real rational fit that folds (a public
270x180 stereo set's left camera, ``--mono --distortion rational``) and a real k1k2p1p2 fit that does not.
The end-to-end case projects a board with plain numpy through a strong barrel lens, on views that stay in
the middle of the image, where nothing in the fit's residuals shows the fold.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from s2r.calib.detect import Detection
from s2r.calib.solve.honesty.verdict import mono_verdict
from s2r.calib.solve.pipelines.mono import calibrate_mono_detections
from s2r.lens.fold import corner_radius, fold_radius, fold_warnings, radial_problem
from s2r.profile import Camera, Distortion

Array = NDArray[np.float64]
#: (fx, fy, cx, cy) px, OpenCV coefficients, (width, height) px.
Case = tuple[tuple[float, ...], tuple[float, ...], tuple[int, int]]
#: A real rational fit that folds: the left camera of a public 270x180 stereo set (sourishg's, 28 views),
#: ``s2r calibrate --mono --distortion rational``: K and k1 k2 p1 p2 k3 k4 k5 k6.
REAL_RATIONAL = ((195.26, 231.35, 131.83, 92.87), (8.53, 9.2, 0.0, 0.0, -75.28, 8.43, 8.16, -72.14), (270, 180))
#: A real k1k2p1p2 fit that does not fold: OpenCV's sample stereo set's left camera (640x480).
REAL_PLAIN = ((533.5, 533.6, 342.1, 234.1), (-0.289, 0.099, 0.001, 0.0, 0.0), (640, 480))
BARREL = ((500.0, 500.0, 319.5, 239.5), (-0.5, 0.0, 0.0, 0.0, 0.0), (640, 480))


def _opencv_fold(intrinsics: tuple[float, ...], coefficients: tuple[float, ...]) -> float | None:
    """Where the distorted radius of OpenCV's projection of rays along the diagonal first stops growing."""
    fx, fy, cx, cy = intrinsics
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    r = np.tan(np.radians(np.linspace(0, 89.5, 40_001)))
    rays = np.column_stack([r / np.sqrt(2), r / np.sqrt(2), np.ones_like(r)])
    px = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, np.asarray(coefficients, np.float64))[0].reshape(-1, 2)
    rd = np.hypot((px[:, 0] - cx) / fx, (px[:, 1] - cy) / fy)
    falls = np.flatnonzero(np.diff(rd) <= 0)
    return None if not len(falls) else float(rd[falls[0]])


def _camera(case: Case) -> Camera:
    (fx, fy, cx, cy), coefs, (w, h) = case
    model = "rational_polynomial" if len(coefs) == 8 else "plumb_bob"
    return Camera(width_px=w, height_px=h, fx_px=fx, fy_px=fy, cx_px=cx, cy_px=cy,
                  distortion=Distortion(model=model, coefficients=coefs))  # type: ignore[arg-type]


@pytest.mark.parametrize("case", [BARREL, REAL_RATIONAL, REAL_PLAIN], ids=["barrel", "real-rational", "real-plain"])
def test_fold_radius_is_where_opencvs_projection_stops_growing(case: Case) -> None:
    intrinsics, coefs, _ = case
    ours, theirs = fold_radius(coefs), _opencv_fold(intrinsics, coefs)
    if theirs is None:
        assert ours is None
    else:
        assert ours is not None and ours == pytest.approx(theirs, abs=2e-3)


def test_fold_radius_known_answers() -> None:
    # r_d = r - 0.5 r^3 peaks at r = sqrt(2/3), where r_d = sqrt(2/3) * (2/3); the slope floor (0.05) is met
    # 0.0005 before
    assert fold_radius((-0.5, 0, 0, 0, 0)) == pytest.approx(np.sqrt(2 / 3) * 2 / 3, abs=1e-3)
    assert fold_radius((0, 0, 0, 0, 0)) is None
    assert fold_radius((-0.289, 0.099, 0, 0, 0)) is None  # 1 - 0.867 r^2 + 0.495 r^4 has no real root
    # a denominator reaching zero at r = 1 (45 degrees) while r_d grows without bound: no fold, and an image
    # reaching r_d = 0.8 (its corner ray at r = 0.55) is served
    assert fold_radius((0, 0, 0, 0, 0, -1.0, 0, 0)) is None
    assert radial_problem((0, 0, 0, 0, 0, -1.0, 0, 0), 0.8) == ""


def test_wide_fields_poles_and_cancelling_coefficients() -> None:
    """Cases from QA: a fold past 76 degrees in a 145-degree image; a near-cancelling rational fit whose
    denominator reaches zero at 3 degrees (the whole image squeezed into them), judged alike wherever the
    sample grid falls; a rational model reaching the corner only beyond a shared root."""
    wide = Camera(width_px=1280, height_px=720, fx_px=200, fy_px=200, cx_px=639.5, cy_px=359.5,
                  distortion=Distortion(coefficients=(-0.015, 0, 0, 0, 0)))
    assert _opencv_fold((200, 200, 639.5, 359.5), (-0.015, 0, 0, 0, 0)) == pytest.approx(3.14, abs=0.01)
    assert "folds over at 85 %" in fold_warnings([("the", wide)])[0]
    cancelling = (-385.823, 286.215, 0, 0, -382.429, -400.078, -261.501, -378.943)
    for corner in (0.734, 0.734 * 1000 / 300):
        problem = radial_problem(cancelling, corner)
        assert problem.startswith("stretches the image ") and "nearly cancel" in problem
    assert radial_problem(cancelling, 0.001) == ""  # an image within the first degree is served
    # a real rational fit (an ill-posed public set, 14 views): numerator and denominator share a root at 9 deg
    shared_root = (-58.7912, 749.683, 0.0008, 0.0074, -138.975, -58.7129, 745.372, -92.5723)
    assert radial_problem(shared_root, 0.403).startswith("stretches the image 2.")


def test_fold_warnings_name_the_camera_and_how_far_out() -> None:
    folds = fold_warnings([("left", _camera(REAL_PLAIN)), ("right", _camera(REAL_RATIONAL))])
    assert len(folds) == 1 and folds[0].startswith("right camera: the rational_polynomial lens model folds over at ")
    share = math.floor(100 * fold_radius(REAL_RATIONAL[1]) / corner_radius(_camera(REAL_RATIONAL)))  # type: ignore[operator]
    assert f"at {share} % of the way" in folds[0] and 70 < share < 90
    assert folds[0].endswith("use fewer lens terms (--distortion k1k2p1p2) or add views with the board near the "
                             "image corners")
    barrel = fold_warnings([("the", _camera(BARREL))])  # two terms already: the remedy is views, or fisheye
    assert len(barrel) == 1 and "plumb_bob lens model folds over at 68 %" in barrel[0]  # 0.544 of 0.800
    assert "--lens fisheye" in barrel[0] and "--distortion" not in barrel[0]


def _board() -> Array:
    grid = np.mgrid[0:9, 0:6].T.reshape(-1, 2) * 0.025
    return np.column_stack([grid - grid.mean(axis=0), np.zeros(len(grid))])


def _rotation(v: Array) -> Array:
    theta = float(np.linalg.norm(v))
    k = v / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.asarray(np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx, np.float64)


def _views(k1: float, n: int = 20, seed: int = 5) -> list[Array]:
    """Board corners (px) through fx = fy = 500, (319.5, 239.5), radial k1 only, written out with numpy; each
    view within an undistorted radius of 0.6 (k1 = -0.5 folds at 0.82: the views stop short of it)."""
    rng = np.random.default_rng(seed)
    views: list[Array] = []
    while len(views) < n:
        R = _rotation(rng.uniform(-0.6, 0.6, 3) * np.array([1, 1, 0.3]) + 1e-9)
        t = np.array([*rng.uniform(-0.25, 0.25, 2), rng.uniform(0.6, 1.0)])
        X = _board() @ R.T + t
        x, y = X[:, 0] / X[:, 2], X[:, 1] / X[:, 2]
        if np.hypot(x, y).max() > 0.6:
            continue
        s = 1 + k1 * (x * x + y * y)
        uv = np.column_stack([500 * x * s + 319.5, 500 * y * s + 239.5]) + rng.normal(0, 0.05, (len(x), 2))
        views.append(uv)
    return views


def _mono(views: list[Array]) -> tuple[list[tuple[str, str]], list[str]]:
    dets = [Detection(f"cam/{i:02d}", "", "ok", size=(640, 480), corners=v.astype(np.float32))
            for i, v in enumerate(views)]
    cal = calibrate_mono_detections(dets, pattern=(9, 6), square_m=0.025, compare=False)
    assert cal.verdict is not None
    return [(r.level, r.text) for r in cal.verdict.reasons], list(cal.warnings)


def test_a_fit_that_folds_inside_the_image_is_poor_and_says_so() -> None:
    """k1 = -0.5 is solved to within 0.01 and folds at 68 % of the way to the corners: warned, judged poor.
    k1 = -0.2 folds at 108 %, past the corners: nothing said."""
    reasons, warnings = _mono(_views(-0.5))
    folds = [w for w in warnings if "folds over" in w]
    assert len(folds) == 1 and "the camera: the plumb_bob lens model folds over at 68 %" in folds[0], warnings
    assert ("poor", folds[0]) in reasons
    reasons, warnings = _mono(_views(-0.2))
    assert not [w for w in warnings if "folds over" in w], warnings
    assert not [text for _, text in reasons if "folds over" in text]


def test_the_verdict_is_poor_for_a_fold_whatever_else() -> None:
    fine = dict(rms_px=0.1, heldout_px=0.12, fx_px=500.0, fx_std_px=0.1, coverage=0.9)
    assert mono_verdict(**fine).level == "good"  # type: ignore[arg-type]
    verdict = mono_verdict(**fine, lens_folds=["the camera: the plumb_bob lens model folds over at 68 %"])  # type: ignore[arg-type]
    assert verdict.level == "poor" and any("folds over" in r.text for r in verdict.reasons)
