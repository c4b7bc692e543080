"""Recordings with a known sensor, made WITHOUT s2r (numpy and cv2 only): a chessboard imaged through homographies.

- :func:`stereo_recording`: stereo pairs of a chessboard (9x6 inner corners) at known poses, each image rendered by
  area-averaging 4x4 point samples per pixel, blurred by a Gaussian of known sigma (cv2.GaussianBlur), with known
  additive Gaussian noise, rounded to 8 bits. Optional repeated frames of one still pose.
- :func:`device_recording`: a left infrared image of the same board and the device's depth registered to it
  (uint16 mm PNG, 0 = no data): the board plane in front of a wall, disparity noise of known sigma (growing with
  distance), holes from a correlated random field at a known fill rate per distance, and a dropout band of known
  width on the wall's side of the board's outline.

The camera: 320x240, f = 300 px, centre (159.5, 119.5), no distortion, right camera 6 cm to the right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

W, H = 320, 240
F = 300.0
CX, CY = (W - 1) / 2.0, (H - 1) / 2.0
BASELINE = 0.06
COLS, ROWS = 9, 6
SQUARE = 0.04
DARK, LIGHT, WALL_GREY = 50.0, 190.0, 110.0
K = np.array([[F, 0, CX], [0, F, CY], [0, 0, 1.0]])

PROFILE_YAML = f"""schema_version: 1
name: sensor_truth_rig
left: {{width_px: {W}, height_px: {H}, fx_px: {F}, fy_px: {F}, cx_px: {CX}, cy_px: {CY}}}
right: {{width_px: {W}, height_px: {H}, fx_px: {F}, fy_px: {F}, cx_px: {CX}, cy_px: {CY}}}
extrinsics:
  rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
  translation_m: [-{BASELINE}, 0.0, 0.0]
matcher: {{num_disparities: 64, block_size: 5, min_depth_m: 0.3, max_depth_m: 5.0}}
simulation: {{clip_near_m: 0.05, clip_far_m: 50.0}}
provenance: {{origin: real, method: tests.sensor.recordings, convention: exact}}
"""


def write_profile(path: Path) -> Path:
    """The generator's camera as an s2r profile YAML (written as text)."""
    path.write_text(PROFILE_YAML)
    return path


def board_pose(distance: float, tilt_x_deg: float, tilt_y_deg: float, shift: tuple[float, float] = (0.0, 0.0)
               ) -> tuple[np.ndarray, np.ndarray]:
    """(R, t) of the board (origin at the first inner corner) with its centre at ``distance`` m ahead."""
    R, _ = cv2.Rodrigues(np.array([math.radians(tilt_x_deg), math.radians(tilt_y_deg), 0.0]))
    centre_board = np.array([(COLS - 1) * SQUARE / 2, (ROWS - 1) * SQUARE / 2, 0.0])
    t = np.array([shift[0], shift[1], distance]) - R @ centre_board
    return R, t


def _board_grey(bx: np.ndarray, by: np.ndarray, levels: tuple[float, float] = (DARK, LIGHT)) -> np.ndarray:
    """Grey level at board coordinates (m): squares (one ring beyond the inner corners) at ``levels`` (dark,
    light), the margin as light, then the wall."""
    i, j = np.floor(bx / SQUARE), np.floor(by / SQUARE)
    squares = (i >= -1) & (i <= COLS - 1) & (j >= -1) & (j <= ROWS - 1)
    margin = (bx >= -2 * SQUARE) & (bx < (COLS + 1) * SQUARE) & (by >= -2 * SQUARE) & (by < (ROWS + 1) * SQUARE)
    grey = np.where(margin, levels[1], WALL_GREY)
    return np.where(squares, np.where((i + j) % 2 == 0, levels[0], levels[1]), grey)


def _on_board(bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    return (bx >= -2 * SQUARE) & (bx < (COLS + 1) * SQUARE) & (by >= -2 * SQUARE) & (by < (ROWS + 1) * SQUARE)


def _board_coords(R: np.ndarray, t: np.ndarray, u: np.ndarray, v: np.ndarray, cam_x: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Board coordinates and camera depth where pixel rays of a camera at x = cam_x (left frame) meet the board."""
    rays = np.stack([(u - CX) / F, (v - CY) / F, np.ones_like(u)], axis=-1)
    n = R[:, 2]
    origin = np.array([cam_x, 0.0, 0.0])
    s = (n @ (t - origin)) / (rays @ n)  # ray parameter = depth along the camera's z
    points = origin + rays * s[..., None] - t
    local = points @ R  # R^T (P - t)
    return local[..., 0], local[..., 1], s


def render_image(R: np.ndarray, t: np.ndarray, *, cam_x: float = 0.0, supersample: int = 4,
                 levels: tuple[float, float] = (DARK, LIGHT)) -> np.ndarray:
    """(H, W) float64 ideal image: the board (and a flat wall around it) area-averaged over each pixel."""
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    acc = np.zeros((H, W))
    v0, u0 = np.mgrid[0:H, 0:W].astype(np.float64)
    for dy in offsets:
        for dx in offsets:
            bx, by, _ = _board_coords(R, t, u0 + dx, v0 + dy, cam_x)
            acc += _board_grey(bx, by, levels)
    return acc / supersample ** 2


def camera_image(ideal: np.ndarray, *, blur: float, noise: float, rng: np.random.Generator) -> np.ndarray:
    """Blur by a Gaussian of ``blur`` px, add Gaussian noise of ``noise`` grey levels, round to uint8."""
    out = ideal
    if blur > 0:
        k = 2 * math.ceil(4 * blur) + 1
        out = cv2.GaussianBlur(ideal, (k, k), blur, borderType=cv2.BORDER_REFLECT)
    out = out + rng.normal(0.0, noise, size=out.shape)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


POSES = [(0.62, 10, -15, (0.0, 0.0)), (0.7, -12, 15, (0.02, 0.0)), (0.85, 15, 10, (-0.03, 0.02)),
         (0.95, -5, -12, (0.0, -0.02)), (0.66, 15, 5, (0.02, 0.01)), (0.8, 8, -8, (0.0, 0.0))]


@dataclass
class Truth:
    """The known sensor a recording was made with."""

    noise_dn: float = 0.0
    blur_px: float = 0.0
    sigma_d_px: float = 0.0
    sigma_growth_px_per_m: float = 0.0
    fill: list[tuple[float, float]] = field(default_factory=list)  # (distance m, fill %), linear between
    edge_band_px: float = 0.0
    hole_scale_px: float = 0.0

    def fill_at(self, z: np.ndarray) -> np.ndarray:
        xs, ys = zip(*self.fill, strict=True)
        return np.interp(z, xs, ys) / 100.0


def stereo_recording(out: Path, truth: Truth, *, poses: list = POSES, still_repeats: int = 0, seed: int = 1,
                     levels: tuple[float, float] = (DARK, LIGHT)) -> Path:
    """Write ``out/left/NN.png`` and ``out/right/NN.png``; ``still_repeats`` extra frames repeat the first pose;
    ``levels``: the dark and light squares' grey levels (0 and 255: the noise is clipped)."""
    rng = np.random.default_rng(seed)
    (out / "left").mkdir(parents=True)
    (out / "right").mkdir()
    frames = list(poses) + [poses[0]] * still_repeats
    for k, (dist, tx, ty, shift) in enumerate(frames):
        R, t = board_pose(dist, tx, ty, shift)
        for side, cam_x in (("left", 0.0), ("right", BASELINE)):
            ideal = render_image(R, t, cam_x=cam_x, levels=levels)
            cv2.imwrite(str(out / side / f"{k:02d}.png"), camera_image(ideal, blur=truth.blur_px,
                                                                          noise=truth.noise_dn, rng=rng))
    return out


def _rank_uniform(field_: np.ndarray) -> np.ndarray:
    """A field's values replaced by their ranks scaled into (0, 1): uniform marginals, same correlation order."""
    flat = field_.ravel()
    ranks = np.empty(flat.size)
    ranks[np.argsort(flat)] = np.arange(flat.size)
    return ((ranks + 0.5) / flat.size).reshape(field_.shape)


def device_depth(R: np.ndarray, t: np.ndarray, truth: Truth, rng: np.random.Generator, *, wall_gap: float = 0.6
                 ) -> np.ndarray:
    """(H, W) float64 metres depth of the board in front of a wall ``wall_gap`` m behind its centre (0 = no data)."""
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    bx, by, z_board = _board_coords(R, t, u, v, 0.0)
    wall = t[2] + wall_gap
    board = _on_board(bx, by) & (z_board > 0)
    z = np.where(board, z_board, wall)
    # occlusion-like band: wall pixels within edge_band_px of the board's outline (on the wall's side)
    dist_to_board = cv2.distanceTransform((~board).astype(np.uint8), cv2.DIST_L2, 5)
    keep = ~((~board) & (dist_to_board <= truth.edge_band_px))
    blurred = rng.standard_normal((H, W))
    if truth.hole_scale_px > 0:
        k = 2 * math.ceil(4 * truth.hole_scale_px) + 1
        blurred = cv2.GaussianBlur(blurred, (k, k), truth.hole_scale_px)
    uniform = _rank_uniform(blurred)
    keep &= uniform < truth.fill_at(z)
    fb = F * BASELINE
    sigma = truth.sigma_d_px + truth.sigma_growth_px_per_m * (z - 1.0)
    d = fb / z + rng.standard_normal(z.shape) * sigma
    keep &= d > 0
    return np.where(keep, fb / np.where(d > 0, d, 1.0), 0.0)


DEPTH_POSES = [(0.62, 10, -15, (0.0, 0.0)), (0.8, -12, 20, (0.02, 0.0)), (0.9, 15, 10, (-0.02, 0.02)),
               (1.2, -5, -20, (0.0, -0.02)), (1.6, 10, 5, (0.02, 0.01)), (1.55, 0, 10, (0.0, 0.0)),
               (1.1, 5, -10, (0.0, 0.0)), (0.7, -8, 8, (0.0, 0.01)), (1.7, -10, 0, (0.0, 0.0)),
               (1.35, 12, 12, (0.01, 0.0)), (1.3, -6, -12, (0.0, 0.01)), (0.95, 0, 18, (0.0, 0.0))]


def device_recording(out: Path, truth: Truth, *, poses: list = DEPTH_POSES, seed: int = 2, npy: bool = False
                     ) -> Path:
    """Write ``out/left/NN.png`` (infrared, noise 1 DN, blur 0.7 px) and ``out/depth/NN.png`` (uint16 mm, 0 no
    data) or, with ``npy``, ``out/depth/NN.npy`` (float32 metres, 0 no data)."""
    rng = np.random.default_rng(seed)
    (out / "left").mkdir(parents=True)
    (out / "depth").mkdir()
    for k, (dist, tx, ty, shift) in enumerate(poses):
        R, t = board_pose(dist, tx, ty, shift)
        cv2.imwrite(str(out / "left" / f"{k:02d}.png"),
                    camera_image(render_image(R, t), blur=0.7, noise=1.0, rng=rng))
        depth = device_depth(R, t, truth, rng)
        if npy:
            np.save(out / "depth" / f"{k:02d}.npy", depth.astype(np.float32))
        else:
            mm = np.clip(np.round(depth * 1000), 0, 65535).astype(np.uint16)
            cv2.imwrite(str(out / "depth" / f"{k:02d}.png"), mm)
    return out


def perfect_recording(out: Path, *, poses: list = DEPTH_POSES, seed: int = 2) -> Path:
    """The simulator's side of :func:`device_recording`: the same poses' infrared images and PERFECT depth
    (``out/depth/NN.npy``, float32 metres: every pixel, no noise)."""
    rng = np.random.default_rng(seed)
    (out / "left").mkdir(parents=True)
    (out / "depth").mkdir()
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    for k, (dist, tx, ty, shift) in enumerate(poses):
        R, t = board_pose(dist, tx, ty, shift)
        cv2.imwrite(str(out / "left" / f"{k:02d}.png"), camera_image(render_image(R, t), blur=0.7, noise=1.0, rng=rng))
        bx, by, z_board = _board_coords(R, t, u, v, 0.0)
        z = np.where(_on_board(bx, by) & (z_board > 0), z_board, t[2] + 0.6)
        np.save(out / "depth" / f"{k:02d}.npy", z.astype(np.float32))
    return out
