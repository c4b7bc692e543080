"""A second, independent generator of stereo pairs through a rig turned by a known dR (shares no code with s2r
nor with tests/drift/scene_gen.py's ray caster).

The scene is a textured far backdrop (at infinity: it moves only with the rotation) and a textured near plane
in front of it. Both are painted on a VIRTUAL pinhole image of the left camera; every raw pixel of each camera
is traced back to that image with numpy (its own pinhole / equidistant projection and unprojection) and
sampled with cv2.remap. Frames: camera optical axes (x right, y down, z forward); the right camera sees
``X_r = R X_l + T`` (the profile's convention), and really sits at ``R_true = dR @ R``, ``T_true = dR @ T``
(turned about its own centre).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["Cam", "photo_texture", "render_pair", "rotvec_matrix"]

F = NDArray[np.float64]


@dataclass(frozen=True)
class Cam:
    """A camera: width, height (px), fx, fy, cx, cy (px), ``model`` "pinhole" or "equidistant" with k1..k4."""

    w: int
    h: int
    fx: float
    fy: float
    cx: float
    cy: float
    model: str = "pinhole"
    k: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)


def rotvec_matrix(rotvec_rad: F) -> F:
    """Rodrigues' formula (3,) -> (3, 3), written out here."""
    theta = float(np.linalg.norm(rotvec_rad))
    if theta < 1e-15:
        return np.eye(3)
    a = np.asarray(rotvec_rad, float) / theta
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def photo_texture(h: int, w: int, rng: np.random.Generator) -> NDArray[np.uint8]:
    """Photo-like grey texture: noise at several octaves (1/f-ish) plus random blobs with sharp edges."""
    out = np.zeros((h, w))
    for cell, weight in ((64, 1.0), (24, 0.7), (8, 0.5), (3, 0.35)):
        small = rng.normal(size=(h // cell + 2, w // cell + 2))
        out += weight * cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    for _ in range(40):
        centre = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        axes = (int(rng.integers(4, 30)), int(rng.integers(4, 30)))
        cv2.ellipse(out, centre, axes, float(rng.uniform(0, 180)), 0, 360, float(rng.normal(0, 1.5)), -1)
    out = (out - out.mean()) / (out.std() + 1e-9)
    return np.clip(128 + 45 * out, 0, 255).astype(np.uint8)


def _project(cam: Cam, rays: F) -> F:
    """(N, 3) rays in the camera frame -> (N, 2) raw pixels."""
    x, y, z = rays[:, 0], rays[:, 1], rays[:, 2]
    if cam.model == "pinhole":
        u, v = x / z, y / z
    else:
        r = np.hypot(x, y)
        theta = np.arctan2(r, z)
        t2 = theta * theta
        td = theta * (1 + cam.k[0] * t2 + cam.k[1] * t2**2 + cam.k[2] * t2**3 + cam.k[3] * t2**4)
        scale = np.where(r > 1e-12, td / np.maximum(r, 1e-12), 1.0 / np.maximum(z, 1e-12))
        u, v = x * scale, y * scale
    return np.column_stack([cam.fx * u + cam.cx, cam.fy * v + cam.cy])


def _unproject(cam: Cam, px: F) -> F:
    """(N, 2) raw pixels -> (N, 3) unit-z rays (pinhole) or unit rays (equidistant) in the camera frame."""
    u = (px[:, 0] - cam.cx) / cam.fx
    v = (px[:, 1] - cam.cy) / cam.fy
    if cam.model == "pinhole":
        return np.column_stack([u, v, np.ones(len(u))])
    td = np.hypot(u, v)
    theta = td.copy()
    for _ in range(20):  # Newton on theta (1 + k1 t^2 + ...) = td
        t2 = theta * theta
        f = theta * (1 + cam.k[0] * t2 + cam.k[1] * t2**2 + cam.k[2] * t2**3 + cam.k[3] * t2**4) - td
        df = 1 + 3 * cam.k[0] * t2 + 5 * cam.k[1] * t2**2 + 7 * cam.k[2] * t2**3 + 9 * cam.k[3] * t2**4
        theta = theta - f / df
    s = np.where(td > 1e-12, np.sin(theta) / np.maximum(td, 1e-12), 1.0)
    return np.column_stack([u * s, v * s, np.cos(theta)])


def _virtual_px(K_virtual: F, rays_left: F) -> F:
    p = rays_left @ K_virtual.T
    return p[:, :2] / p[:, 2:3]


def _maps(cam: Cam, R_cam_from_left: F, T_cam: F, K_virtual: F, plane_depth_m: float) -> tuple[F, F, F]:
    """For every raw pixel of ``cam``: where its ray meets the far backdrop and the near plane ``Z_left = depth``
    on the virtual left image (two (H, W, 2) maps), and the ray's depth along Z_left at the plane (for tests)."""
    u, v = np.meshgrid(np.arange(cam.w, dtype=float), np.arange(cam.h, dtype=float))
    rays = _unproject(cam, np.column_stack([u.ravel(), v.ravel()]))
    d_left = rays @ R_cam_from_left  # R^T ray: the direction in the left frame
    centre = -R_cam_from_left.T @ T_cam  # the camera centre in the left frame
    far = _virtual_px(K_virtual, d_left)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (plane_depth_m - centre[2]) / d_left[:, 2]
    near_pts = centre[None, :] + s[:, None] * d_left
    near = _virtual_px(K_virtual, near_pts)
    shape = (cam.h, cam.w, 2)
    return far.reshape(shape), near.reshape(shape), s.reshape(cam.h, cam.w)


def _sample(image: NDArray[np.uint8], coords: F) -> NDArray[np.uint8]:
    maps = coords.astype(np.float32)
    return np.asarray(cv2.remap(image, maps[..., 0], maps[..., 1], cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT),
                      np.uint8)


def render_pair(left: Cam, right: Cam, R: F, T: F, dR: F, *, seed: int, plane_depth_m: float = 1.5,
                plane_box: tuple[float, float, float, float] = (0.15, 0.5, 0.75, 0.95), about_centre: bool = True
                ) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """Raw grey (left, right) images of the backdrop + a near plane covering ``plane_box`` (x0, y0, x1, y1 as
    fractions of the virtual left image), through a rig really at ``dR @ R``, ``dR @ T`` (the right camera
    turned about its own centre) or, with ``about_centre`` False, ``dR @ R``, ``T``."""
    rng = np.random.default_rng(seed)
    scale = 1.5  # the virtual image is wider than the cameras so that every ray lands on the texture
    Wv, Hv = int(left.w * scale), int(left.h * scale)
    f = min(left.fx, left.fy) / 1.3
    K_virtual = np.array([[f, 0, Wv / 2], [0, f, Hv / 2], [0, 0, 1.0]])
    backdrop, near_tex = photo_texture(Hv, Wv, rng), photo_texture(Hv, Wv, rng)
    x0, y0, x1, y1 = plane_box
    images = []
    T_true = (dR if about_centre else np.eye(3)) @ np.asarray(T, float).reshape(3)
    for cam, Rc, Tc in ((left, np.eye(3), np.zeros(3)), (right, dR @ R, T_true)):
        far, near, s = _maps(cam, Rc, Tc, K_virtual, plane_depth_m)
        inside = (near[..., 0] >= x0 * Wv) & (near[..., 0] < x1 * Wv) & (near[..., 1] >= y0 * Hv) \
            & (near[..., 1] < y1 * Hv) & (s > 0)
        images.append(np.where(inside, _sample(near_tex, near), _sample(backdrop, far)).astype(np.uint8))
    return images[0], images[1]
