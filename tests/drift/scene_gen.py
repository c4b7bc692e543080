"""An independent generator of ordinary stereo scenes (no s2r code): textured planes at many depths.

A "room" of textured quads (a back wall, a floor and a few panels at 0.8-4 m) is ray-cast per pixel with
2x2 sub-samples through tests/raycast.py's lenses (its own plumb_bob maths), once for the left camera and
once for a right camera that is really turned by ``dR`` against the profile:
``R_true = dR @ R_profile`` with either ``T_true = dR @ T_profile`` (turned about its own centre) or
``T_true = T_profile``. Textures are seeded multi-scale noise, so SIFT finds features everywhere.

Frames: the left camera's optical frame is the world (x right, y down, z forward, metres).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tests.raycast import Lens

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Quad:
    """A textured rectangle: centre (3,), unit axes u, v (3,) spanning half sizes (metres), texture seed."""

    centre: F64
    u: F64
    v: F64
    half_u: float
    half_v: float
    texture: NDArray[np.float32]


def _texture(seed: int, size: int = 512) -> NDArray[np.float32]:
    rng = np.random.default_rng(seed)
    tex = np.zeros((size, size), np.float32)
    for cells, weight in ((8, 0.9), (32, 0.7), (128, 0.5), (512, 0.25)):
        noise = rng.random((cells, cells)).astype(np.float32)
        tex += weight * cv2.resize(noise, (size, size), interpolation=cv2.INTER_CUBIC)
    tex -= tex.min()
    return (255.0 * tex / tex.max()).astype(np.float32)


def room(seed: int = 0) -> list[Quad]:
    """A back wall at 5 m, a floor 1.1 m below and five panels at 0.8-4 m, each with its own texture."""
    rng = np.random.default_rng(seed)
    quads = [Quad(np.array([0.0, 0.0, 5.0]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), 6.0, 4.0,
                  _texture(seed * 100 + 1)),
             Quad(np.array([0.0, 1.1, 3.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 6.0, 2.9,
                  _texture(seed * 100 + 2))]
    for k in range(5):
        z = rng.uniform(0.8, 4.0)
        centre = np.array([rng.uniform(-0.5, 0.5) * z, rng.uniform(-0.35, 0.35) * z, z])
        yaw, pitch = rng.uniform(-0.6, 0.6), rng.uniform(-0.4, 0.4)
        u = np.array([np.cos(yaw), 0.0, np.sin(yaw)])
        v = np.array([0.0, np.cos(pitch), np.sin(pitch)])
        v = v - u * (u @ v)
        quads.append(Quad(centre, u, v / np.linalg.norm(v), 0.12 * z + 0.1, 0.1 * z + 0.1,
                          _texture(seed * 100 + 10 + k)))
    return quads


def _bilinear(tex: NDArray[np.float32], col: F64, row: F64) -> F64:
    """Texture values at fractional (col, row), bilinear."""
    c0 = np.clip(np.floor(col).astype(int), 0, tex.shape[1] - 2)
    r0 = np.clip(np.floor(row).astype(int), 0, tex.shape[0] - 2)
    fc, fr = col - c0, row - r0
    top = tex[r0, c0] * (1 - fc) + tex[r0, c0 + 1] * fc
    bottom = tex[r0 + 1, c0] * (1 - fc) + tex[r0 + 1, c0 + 1] * fc
    return np.asarray(top * (1 - fr) + bottom * fr, np.float64)


def _shade(origin: F64, dirs: F64, quads: list[Quad]) -> F64:
    """Grey level (N,) of the nearest quad hit by each ray (origin (3,), directions (N, 3)); 40 where none."""
    best = np.full(len(dirs), np.inf)
    grey = np.full(len(dirs), 40.0)
    for quad in quads:
        normal = np.cross(quad.u, quad.v)
        denom = dirs @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((quad.centre - origin) @ normal) / denom
        hit = origin + dirs * t[:, None]
        a = (hit - quad.centre) @ quad.u / quad.half_u
        b = (hit - quad.centre) @ quad.v / quad.half_v
        ok = (t > 0) & (t < best) & (np.abs(a) <= 1) & (np.abs(b) <= 1)
        size = quad.texture.shape[0] - 1
        grey[ok] = _bilinear(quad.texture, (a[ok] + 1) / 2 * size, (b[ok] + 1) / 2 * size)
        best[ok] = t[ok]
    return grey


def render(lens: Lens, R_cam_world: F64, t_cam_world: F64, quads: list[Quad], *, seed: int,
           noise: float = 1.0) -> NDArray[np.uint8]:
    """A grey image of the scene seen by a camera with ``X_cam = R X_world + t`` (2x2 samples, noise in DN)."""
    sub = 2
    u, v = np.meshgrid((np.arange(lens.width * sub) + 0.5) / sub - 0.5,
                       (np.arange(lens.height * sub) + 0.5) / sub - 0.5)
    dirs_cam = lens.rays(u.ravel(), v.ravel())
    dirs = dirs_cam @ R_cam_world  # R^T d, row-wise: directions in the world frame
    origin = -R_cam_world.T @ t_cam_world
    grey = _shade(origin, dirs, quads).reshape(lens.height, sub, lens.width, sub).mean(axis=(1, 3))
    grey += np.random.default_rng(seed).normal(0.0, noise, grey.shape)
    return np.clip(np.round(grey), 0, 255).astype(np.uint8)


def turned_pair(left: Lens, right: Lens, R: F64, T: F64, dR: F64, *, seed: int, keep: str = "centre",
                quads: list[Quad] | None = None) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """Left and right images of :func:`room` with the right camera really at ``dR @ R`` (see module doc)."""
    scene = room(seed) if quads is None else quads
    R_true = dR @ R
    T_true = dR @ T if keep == "centre" else T
    return (render(left, np.eye(3), np.zeros(3), scene, seed=seed),
            render(right, R_true, T_true, scene, seed=seed + 1))
