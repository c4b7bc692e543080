"""Corner detection: refinement window, downscaled detection, order matching, the corner cache."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from s2r.calib.detect import CornerCache, DetectItem, detect_board, detect_stream
from s2r.calib.detect.chessboard import refine_window
from s2r.calib.solve.synth import CameraWarper, board_object_points, board_texture, random_board_poses
from s2r.calib.solve.views import match_corner_order
from s2r.fileio import sha256_file
from s2r.profile import StereoProfile
from tests.calib.conftest import distorted_truth


def _grid(spacing: float, pattern: tuple[int, int] = (9, 6)) -> np.ndarray:
    cols, rows = pattern
    return (np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * spacing + 50).astype(np.float32)


def test_refine_window_fits_the_square_size() -> None:
    # 0.4 x the smallest neighbour spacing, clamped to 2..11 (half-size, pixels)
    assert refine_window(_grid(10.0), (9, 6)) == 4
    assert refine_window(_grid(100.0), (9, 6)) == 11
    assert refine_window(_grid(4.0), (9, 6)) == 2
    squeezed = _grid(20.0)
    squeezed[1] = squeezed[0] + [6.0, 0.0]  # one close pair of neighbours sets the window
    assert refine_window(squeezed, (9, 6)) == 2


def _view(profile: StereoProfile, seed: int = 3, supersample: int = 2) -> tuple[np.ndarray, np.ndarray]:
    pose = next(iter(random_board_poses(profile, views=1, pattern=(9, 6), square_m=0.025, seed=seed)))
    warper = CameraWarper(profile.left, supersample=supersample)
    image = warper.render(board_texture((9, 6)), pose.rvec, pose.tvec, square_m=0.025)
    return image, warper.project(board_object_points((9, 6), 0.025), pose.rvec, pose.tvec)


def _aligned(found: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return found if np.linalg.norm(found[0] - truth[0]) < np.linalg.norm(found[-1] - truth[0]) else found[::-1]


def test_detected_corners_match_the_projection() -> None:
    image, truth = _view(distorted_truth())
    corners, detector = detect_board(image, (9, 6))
    assert corners is not None and detector == "classic"
    err = np.linalg.norm(_aligned(corners, truth) - truth, axis=1)
    assert err.mean() < 0.08 and err.max() < 0.3


def test_large_images_are_detected_downscaled_and_refined_at_full_resolution() -> None:
    big = distorted_truth().left.scaled(1920, 1440)
    profile = distorted_truth().model_copy(update={"left": big, "right": big})
    image, truth = _view(profile, supersample=1)
    corners, _ = detect_board(image, (9, 6))
    assert corners is not None
    err = np.linalg.norm(_aligned(corners, truth) - truth, axis=1)
    assert err.mean() < 0.1 and err.max() < 0.4


def test_reversed_right_corners_are_put_back_in_left_order() -> None:
    rng = np.random.default_rng(0)
    left = _grid(20.0)
    right = left - [40.0, 0.0] + rng.normal(0, 0.5, left.shape).astype(np.float32)
    right[0] += [30.0, -25.0]  # a badly wrong first corner must not fool the check
    fixed, flipped = match_corner_order(left, right[::-1].copy(), (9, 6))
    assert flipped and np.allclose(fixed, right)
    same, flipped = match_corner_order(left, right, (9, 6))
    assert not flipped and same is right


def test_square_boards_also_handle_quarter_turns() -> None:
    left = _grid(20.0, (7, 7))
    turned = np.rot90(left.reshape(7, 7, 2), 1).reshape(-1, 2).copy()
    fixed, flipped = match_corner_order(left, turned, (7, 7))
    assert flipped and np.allclose(fixed, left)


def test_cache_keeps_finished_detections_of_an_interrupted_run(synthetic_set: tuple[Path, StereoProfile],
                                                               tmp_path: Path) -> None:
    files = sorted((synthetic_set[0] / "left").glob("*.png"))[:6]
    items = [DetectItem(name=p.name, sha256=sha256_file(p), source=p) for p in files]
    cache = CornerCache(tmp_path / "cache")
    stream = detect_stream(iter(items), pattern=(9, 6), jobs=2, cache=cache)
    first = [next(stream) for _ in range(3)]
    stream.close()  # interrupted after three results
    assert len(list((tmp_path / "cache").glob("*.json"))) >= 3
    rerun = list(detect_stream(iter(items), pattern=(9, 6), jobs=1, cache=cache))
    assert [d.cached for d in rerun[:3]] == [True] * 3
    for a, b in zip(first, rerun[:3], strict=True):
        assert a.corners is not None and b.corners is not None
        assert np.allclose(a.corners, b.corners, atol=1e-3)
    other_pattern = list(detect_stream(iter(items[:1]), pattern=(8, 6), jobs=1, cache=cache))
    assert not other_pattern[0].cached and other_pattern[0].status == "no_board"


def test_unreadable_file_detection_says_why(tmp_path: Path) -> None:
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG broken")
    det = next(detect_stream([DetectItem(name="bad.png", sha256="0" * 64, source=bad)], pattern=(9, 6)))
    assert det.status == "unreadable" and "not a readable image" in det.detail and det.size is None
    grey = cv2.imread(str(bad), cv2.IMREAD_GRAYSCALE)
    assert grey is None
