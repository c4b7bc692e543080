"""An independent device-depth recording generator (no s2r code): a chessboard at known poses seen by an ideal
pinhole left camera, with the device's depth image registered to it carrying a known bias, relative noise and
hole rate. Truth and metrics are computed here from first principles, so the test does not share s2r's code."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class DeviceFrame:
    """One frame: 8-bit grey left image, float64 true depth (m, NaN off the board) and the device depth (uint16 mm)."""

    left: NDArray[np.uint8]
    truth_m: NDArray[np.float64]
    depth_mm: NDArray[np.uint16]
    board_mask: NDArray[np.bool_]
    R: NDArray[np.float64]
    t: NDArray[np.float64]


def board_image(pattern: tuple[int, int], square_px: int, margin_px: int) -> NDArray[np.uint8]:
    """A chessboard of (cols + 1) x (rows + 1) squares with a white margin; first inner corner at (m + s, m + s)."""
    cols, rows = pattern
    h, w = (rows + 1) * square_px + 2 * margin_px, (cols + 1) * square_px + 2 * margin_px
    img = np.full((h, w), 255, np.uint8)
    for r in range(rows + 1):
        for c in range(cols + 1):
            if (r + c) % 2 == 0:
                y, x = margin_px + r * square_px, margin_px + c * square_px
                img[y:y + square_px, x:x + square_px] = 0
    return img


def render_frame(K: NDArray[np.float64], size: tuple[int, int], pattern: tuple[int, int], square_m: float,
                 distance_m: float, yaw_deg: float, pitch_deg: float, *, bias: float, rel_noise: float,
                 hole_rate: float, rng: np.random.Generator) -> DeviceFrame:
    """A board whose centre sits ``distance_m`` ahead of the camera, turned by yaw/pitch; its depth image is
    ``truth * (1 + bias) * (1 + rel_noise * N(0, 1))`` on and around the board, with ``hole_rate`` pixels zeroed."""
    cols, rows = pattern
    spx, margin = 40, 40
    tex = board_image(pattern, spx, margin)
    R = Rotation.from_euler("yx", [yaw_deg, pitch_deg], degrees=True).as_matrix()
    centre_board = np.array([(cols - 1) * square_m / 2, (rows - 1) * square_m / 2, 0.0])
    t = np.array([0.0, 0.0, distance_m]) - R @ centre_board
    # texture pixel (u, v) -> board point ((u - margin - spx) / spx * square, (v - margin - spx) / spx * square, 0)
    A = np.array([[square_m / spx, 0, -(margin + spx) * square_m / spx],
                  [0, square_m / spx, -(margin + spx) * square_m / spx], [0, 0, 1]])
    H = K @ np.column_stack([R[:, 0], R[:, 1], t]) @ A
    w, h = size
    grey = cv2.warpPerspective(tex, H, (w, h), flags=cv2.INTER_AREA, borderValue=128)
    # supersampled anti-aliasing: render at 4x and shrink
    S = np.diag([4.0, 4.0, 1.0])
    S[0, 2] = S[1, 2] = 1.5
    big = cv2.warpPerspective(tex, S @ H, (4 * w, 4 * h), flags=cv2.INTER_LINEAR, borderValue=128)
    grey = cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA)
    # truth: ray (x, y, 1) meets plane n . P = n . t
    n = R[:, 2]
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    x, y = (xs - K[0, 2]) / K[0, 0], (ys - K[1, 2]) / K[1, 1]
    z = (n @ t) / (n[0] * x + n[1] * y + n[2])
    inv = np.linalg.inv(H)
    uvw = np.einsum("ij,jhw->ihw", inv, np.stack([xs, ys, np.ones_like(xs)]))
    u, v = uvw[0] / uvw[2], uvw[1] / uvw[2]
    mask = (u >= 0) & (u < tex.shape[1]) & (v >= 0) & (v < tex.shape[0])
    truth = np.where(mask, z, np.nan)
    noisy = truth * (1 + bias) * (1 + rel_noise * rng.standard_normal(truth.shape))
    depth = np.where(mask, np.round(noisy * 1000.0), 0)
    depth[rng.random(depth.shape) < hole_rate] = 0
    return DeviceFrame(np.asarray(grey, np.uint8), truth, depth.astype(np.uint16), mask, R, t)


def write_recording(folder: Path, frames: list[DeviceFrame]) -> tuple[Path, Path]:
    """Write ``left/NNN.png`` (8-bit) and ``depth/NNN.png`` (uint16 mm) as realsense-ros would; returns both."""
    left, depth = folder / "left", folder / "depth"
    left.mkdir(parents=True)
    depth.mkdir(parents=True)
    for i, f in enumerate(frames):
        cv2.imwrite(str(left / f"{i:03d}.png"), f.left)
        cv2.imwrite(str(depth / f"{i:03d}.png"), f.depth_mm)
    return left, depth
