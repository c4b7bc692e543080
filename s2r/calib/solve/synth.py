"""Warp-based synthetic chessboard views with exactly known corners (tests, benchmarks, self-checks).

A flat chessboard texture is mapped into each camera through the board pose, the camera's K and its
distortion (inverse mapping: every output pixel is undistorted, intersected with the board plane and
sampled from the texture), rendered at ``supersample`` times the resolution and averaged down with
INTER_AREA. The corners' true positions are ``cv2.projectPoints`` of the board corners with the same
K and D. The PyBullet renderer in :mod:`s2r.render` gives physically rendered boards; this module is the
fast, dependency-free variant.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.chessboard import board_object_points
from s2r.profile import Camera, StereoProfile

__all__ = [
    "BoardPose",
    "CameraWarper",
    "board_object_points",
    "board_texture",
    "random_board_poses",
    "right_pose",
    "write_stereo_set",
]

FloatArray = NDArray[np.float64]
_PX_PER_SQUARE = 48


def board_texture(pattern: tuple[int, int], *, px_per_square: int = _PX_PER_SQUARE) -> NDArray[np.uint8]:
    """Grey chessboard texture with ``cols + 1`` x ``rows + 1`` squares and a one-square white margin."""
    cols, rows = pattern
    squares = np.indices((rows + 3, cols + 3)).sum(axis=0) % 2 == 0
    inner = np.zeros_like(squares)
    inner[1:-1, 1:-1] = True
    tex = np.where(inner & squares, 0, 255).astype(np.uint8)
    return np.kron(tex, np.ones((px_per_square, px_per_square), np.uint8))


@dataclass(frozen=True)
class BoardPose:
    """Pose of the board frame in the LEFT camera's optical frame: ``X_left = R(rvec) X_board + tvec`` (m)."""

    rvec: FloatArray
    tvec: FloatArray


class CameraWarper:
    """Renders board views for one camera; caches the undistorted ray of every (supersampled) pixel."""

    def __init__(self, camera: Camera, *, supersample: int = 2) -> None:
        self.camera = camera
        self.s = supersample
        w, h = camera.image_size
        xs = (np.arange(w * supersample, dtype=np.float64) + 0.5) / supersample - 0.5
        ys = (np.arange(h * supersample, dtype=np.float64) + 0.5) / supersample - 0.5
        grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 1, 2)
        rays = cv2.undistortPoints(grid, camera.K, camera.D, None, None, None,
                                       (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10))
        self.rays = rays.reshape(h * supersample, w * supersample, 2)

    def render(self, texture: NDArray[np.uint8], rvec: FloatArray, tvec: FloatArray, *, square_m: float,
               px_per_square: int = _PX_PER_SQUARE, background: int = 128) -> NDArray[np.uint8]:
        """Grey image (H, W) of the board at pose ``rvec, tvec`` (board frame in this camera's optical frame)."""
        R, _ = cv2.Rodrigues(np.asarray(rvec, np.float64))
        H = np.column_stack([R[:, 0], R[:, 1], np.asarray(tvec, np.float64).reshape(3)])
        Hinv = np.linalg.inv(H)
        x, y = self.rays[..., 0], self.rays[..., 1]
        bx = Hinv[0, 0] * x + Hinv[0, 1] * y + Hinv[0, 2]
        by = Hinv[1, 0] * x + Hinv[1, 1] * y + Hinv[1, 2]
        bz = Hinv[2, 0] * x + Hinv[2, 1] * y + Hinv[2, 2]
        scale = px_per_square / square_m
        map_x = ((bx / bz) * scale + 2 * px_per_square - 0.5).astype(np.float32)
        map_y = ((by / bz) * scale + 2 * px_per_square - 0.5).astype(np.float32)
        behind = bz <= 0
        map_x[behind] = -10
        hi = cv2.remap(texture, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                       borderValue=background)
        if self.s == 1:
            return np.asarray(hi, np.uint8)
        return np.asarray(cv2.resize(hi, self.camera.image_size, interpolation=cv2.INTER_AREA), np.uint8)

    def project(self, objp: NDArray[np.float32], rvec: FloatArray, tvec: FloatArray) -> NDArray[np.float64]:
        """True pixel positions (N, 2) of board points through this camera's K and D."""
        pts, _ = cv2.projectPoints(objp.astype(np.float64), rvec, tvec, self.camera.K, self.camera.D)
        return np.asarray(pts, np.float64).reshape(-1, 2)


def right_pose(profile: StereoProfile, rvec: FloatArray, tvec: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Board pose in the right optical frame from its pose in the left one (OpenCV extrinsics)."""
    r_lr, _ = cv2.Rodrigues(profile.R)
    col = [np.asarray(v, np.float64).reshape(3, 1) for v in (rvec, tvec, r_lr, profile.T)]
    r3, t3 = cv2.composeRT(*col)[:2]
    return np.asarray(r3, np.float64).reshape(3), np.asarray(t3, np.float64).reshape(3)


def _inside(pts: FloatArray, size: tuple[int, int], margin: float) -> bool:
    w, h = size
    return bool(np.all((pts[:, 0] > margin) & (pts[:, 0] < w - 1 - margin)
                       & (pts[:, 1] > margin) & (pts[:, 1] < h - 1 - margin)))


def random_board_poses(profile: StereoProfile, *, views: int, pattern: tuple[int, int], square_m: float,
                       seed: int, distance_m: tuple[float, float] | None = None,
                       max_tilt_deg: float = 50.0, margin_px: float = 3.0) -> Iterator[BoardPose]:
    """Seeded board poses (in the left optical frame) whose corners all land inside BOTH images.

    Board centres are spread over the image (stratified over a 3x3 grid of target cells), distances drawn
    from ``distance_m`` (default: where the board spans 25-60 % of the image width), tilts up to
    ``max_tilt_deg`` about random in-plane axes, in-plane roll up to 20 degrees.
    """
    rng = np.random.default_rng(seed)
    cols, rows = pattern
    objp = board_object_points(pattern, square_m).astype(np.float64)
    outer = np.array([[-1, -1, 0], [cols, -1, 0], [-1, rows, 0], [cols, rows, 0]], np.float64) * square_m
    objp = np.vstack([objp, outer])
    centre = np.array([(cols - 1) * square_m / 2, (rows - 1) * square_m / 2, 0.0])
    cam = profile.left
    width_m = (cols + 1) * square_m
    if distance_m is None:
        distance_m = (cam.fx_px * width_m / (0.6 * cam.width_px), cam.fx_px * width_m / (0.25 * cam.width_px))
    made = 0
    for _ in range(views * 400):
        if made >= views:
            return
        cell = made % 9
        u = cam.width_px * ((cell % 3) + rng.uniform(0.1, 0.9)) / 3
        v = cam.height_px * ((cell // 3) + rng.uniform(0.1, 0.9)) / 3
        z = rng.uniform(*distance_m)
        ray = np.array([(u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px, 1.0])
        tilt = np.deg2rad(rng.uniform(0, max_tilt_deg))
        axis_angle = rng.uniform(0, 2 * np.pi)
        tilt_vec = tilt * np.array([np.cos(axis_angle), np.sin(axis_angle), 0.0])
        roll = np.deg2rad(rng.uniform(-20, 20))
        R_tilt, _ = cv2.Rodrigues(tilt_vec)
        R_roll, _ = cv2.Rodrigues(np.array([0.0, 0.0, roll]))
        R = R_tilt @ R_roll
        tvec = ray * z - R @ centre
        rvec = cv2.Rodrigues(R)[0].reshape(3)
        pl, _ = cv2.projectPoints(objp, rvec, tvec, cam.K, cam.D)
        rr, tr = right_pose(profile, rvec, tvec)
        pr, _ = cv2.projectPoints(objp, rr, tr, profile.right.K, profile.right.D)
        if _inside(np.asarray(pl, np.float64).reshape(-1, 2), cam.image_size, margin_px) and _inside(
                np.asarray(pr, np.float64).reshape(-1, 2), profile.right.image_size, margin_px):
            made += 1
            yield BoardPose(rvec=rvec, tvec=tvec)


def _noisy(image: NDArray[np.uint8], rng: np.random.Generator, sigma: float) -> NDArray[np.uint8]:
    if sigma <= 0:
        return image
    noisy = image.astype(np.float32) + rng.normal(0.0, sigma, image.shape).astype(np.float32)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def write_stereo_set(profile: StereoProfile, out_dir: Path, *, views: int, pattern: tuple[int, int] = (9, 6),
                     square_m: float = 0.025, seed: int = 0, supersample: int = 2, noise_sigma: float = 1.5,
                     blank_views: int = 0, ext: str = "png") -> list[BoardPose]:
    """Write ``out_dir/left/NN.ext`` and ``out_dir/right/NN.ext`` for ``views`` board poses plus
    ``blank_views`` pairs without a board (background and noise only, appended after the board views).

    Returns the board poses in the left optical frame (ground truth). Noise is seeded Gaussian grey noise.
    """
    rng = np.random.default_rng(seed + 1)
    tex = board_texture(pattern)
    warpers = (CameraWarper(profile.left, supersample=supersample),
               CameraWarper(profile.right, supersample=supersample))
    for side in ("left", "right"):
        (out_dir / side).mkdir(parents=True, exist_ok=True)
    poses = list(random_board_poses(profile, views=views, pattern=pattern, square_m=square_m, seed=seed))
    for i, pose in enumerate(poses):
        rr, tr = right_pose(profile, pose.rvec, pose.tvec)
        for side, warper, (rv, tv) in (("left", warpers[0], (pose.rvec, pose.tvec)),
                                       ("right", warpers[1], (rr, tr))):
            img = warper.render(tex, rv, tv, square_m=square_m)
            cv2.imwrite(str(out_dir / side / f"{i:02d}.{ext}"), _noisy(img, rng, noise_sigma))
    w, h = profile.image_size
    for j in range(blank_views):
        for side in ("left", "right"):
            blank = np.full((h, w), 128, np.uint8)
            cv2.imwrite(str(out_dir / side / f"{len(poses) + j:02d}.{ext}"), _noisy(blank, rng, max(noise_sigma, 3.0)))
    return poses
