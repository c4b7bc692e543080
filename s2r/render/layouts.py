"""Scene layouts for ground-truth depth: textured planes and a box room, as surfaces in the left optical frame.

Every surface gets its own seeded multi-scale speckle texture (never a repeating pattern), sized so that a
texel covers about a pixel where the surface is seen, keeping matching well-posed from 0.5 m to 5 m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.errors import RenderError
from s2r.lens.distortion import undistort_pixels
from s2r.profile import Camera, StereoProfile
from s2r.render.cubemap import lens_rays
from s2r.render.textures import speckle_texture, write_png
from s2r.render.world import Surface, box_faces, write_mesh

__all__ = ["SCENES", "Layout", "scene_layouts"]

FloatArray = NDArray[np.float64]
#: One frame's surfaces and its description (plain, YAML-ready values).
Layout = tuple[tuple[Surface, ...], dict[str, Any]]
SCENES = ("planes", "slanted", "span", "room")
#: Depth ratio (far / near) a "span" plane covers across the image width: every pixel sees another sub-pixel phase.
SPAN_RATIO = 1.5
_TEXTURE_PX = 1024
_MAX_SIDE_FACTOR = 20.0
_MAX_INCIDENCE_DEG = 72.0
#: Largest angle from the optical axis (degrees) a fisheye scene's planes are sized for.
_FISHEYE_FIELD_DEG = 62.0


def _field_rays(profile: StereoProfile) -> FloatArray:
    """Rays ``(N, 3)`` (z = 1) through the left image's border, undistorted, in the left optical frame."""
    cam = profile.left
    w, h = cam.width_px, cam.height_px
    t, s = np.linspace(-0.5, w - 0.5, 33), np.linspace(-0.5, h - 0.5, 25)
    border = np.concatenate([
        np.column_stack([t, np.full_like(t, -0.5)]), np.column_stack([t, np.full_like(t, h - 0.5)]),
        np.column_stack([np.full_like(s, -0.5), s]), np.column_stack([np.full_like(s, w - 0.5), s]),
    ])
    if cam.distortion.model == "equidistant":
        return _fisheye_field_rays(cam, border)
    norm = undistort_pixels(cam, border)
    return np.column_stack([norm, np.ones(len(norm))])


def _fisheye_field_rays(cam: Camera, border: FloatArray) -> FloatArray:
    """Border rays (z = 1) of a fisheye, with angles from the axis capped at ``_FISHEYE_FIELD_DEG``: scenes cover
    what the rectified images (at most ~90 deg wide, see ``s2r.rectification``) see, not the whole circle."""
    rays, ok = lens_rays(cam, border)
    rays = rays[ok]
    theta = np.arccos(np.clip(rays[:, 2], -1.0, 1.0))
    capped = np.minimum(theta, math.radians(_FISHEYE_FIELD_DEG))
    side = np.maximum(np.hypot(rays[:, 0], rays[:, 1]), 1e-12)  # sin(theta) of unit rays
    x, y = rays[:, 0] / side * np.tan(capped), rays[:, 1] / side * np.tan(capped)
    return np.column_stack([x, y, np.ones(len(x))])


def _plane_side_m(profile: StereoProfile, R: FloatArray, centre: FloatArray) -> float:
    """Side (metres) of a square plane (normal ``R[:, 2]``, centred at ``centre``) that fills both views."""
    n = R[:, 2]
    rays = _field_rays(profile)
    denom = rays @ n
    if np.any(denom <= 1e-3):
        raise RenderError("a slanted plane does not cover the field of view", field="scene",
                          hint="the field of view is too wide for slanted planes; use planes or room")
    hits = rays * (float(n @ centre) / denom)[:, None]
    local = (hits - centre) @ R
    extent = float(np.max(np.abs(local[:, :2]))) + profile.baseline_m
    side = 2.2 * extent
    if side > _MAX_SIDE_FACTOR * float(np.linalg.norm(centre)):
        raise RenderError("a slanted plane would be too large to texture", field="scene", hint="use planes or room")
    return side


def _square(side: float) -> list[tuple[FloatArray, tuple[float, float, float, float]]]:
    h = side / 2.0
    corners = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
    return [(corners, (0.0, 0.0, 1.0, 1.0))]


def _pose(R: FloatArray, t: FloatArray) -> FloatArray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _textured(tmp: Path, name: str, quads: Any, seed: Sequence[int], T: FloatArray) -> Surface:
    mesh = write_mesh(tmp / f"{name}.obj", quads)
    texture = write_png(tmp / f"{name}.png", speckle_texture(_TEXTURE_PX, seed=int(np.random.SeedSequence(
        list(seed)).generate_state(1)[0]), finest_px=1.5))
    return Surface(mesh, texture, T)


def _plane_frame(profile: StereoProfile, tmp: Path, k: int, d: float, R: FloatArray, seed: int, scene: str
                 ) -> Layout:
    centre = np.array([0.0, 0.0, d])
    side = _plane_side_m(profile, R, centre)
    surface = _textured(tmp, f"{scene}{k}", _square(side), (seed, k), _pose(R, centre))
    normal = (-R[:, 2]).tolist()
    desc = {"scene": scene, "distance_m": d, "surfaces": [
        {"kind": "plane", "point_m": centre.tolist(), "normal": normal, "side_m": side}]}
    return (surface,), desc


def _slant(profile: StereoProfile, k: int) -> FloatArray:
    """Rotation of slanted plane k: yaw/pitch from a fixed list, scaled down until every ray of the view
    meets the plane at most ``_MAX_INCIDENCE_DEG`` from its normal (wide lenses get gentler slants)."""
    yaw = (30.0, -40.0, 20.0, -25.0, 45.0)[k % 5]
    pitch = (15.0, -10.0, 25.0, 0.0, -20.0)[k % 5]
    rays = _field_rays(profile)
    rays = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    limit = math.cos(math.radians(_MAX_INCIDENCE_DEG))
    for _ in range(40):
        R = np.asarray(Rotation.from_euler("yx", [yaw, pitch], degrees=True).as_matrix(), dtype=np.float64)
        if float(np.min(rays @ R[:, 2])) >= limit:
            break
        yaw, pitch = 0.9 * yaw, 0.9 * pitch
    return R


def _span(profile: StereoProfile, k: int, seed: int) -> FloatArray:
    """Rotation of "span" plane k: tilted about the vertical axis so that its depth grows by ``SPAN_RATIO`` from
    one side of the left image to the other (side chosen by the seed), plus a smaller seeded tilt about the
    horizontal axis. The plane ``Z - a X - b Y = Z0`` has depth ``Z0 / (1 - a x - b y)`` along the ray (x, y, 1)."""
    rng = np.random.default_rng([seed, k, 77])
    rays = _field_rays(profile)
    x_max, y_max = float(np.max(np.abs(rays[:, 0]))), float(np.max(np.abs(rays[:, 1])))
    a = (SPAN_RATIO - 1.0) / (SPAN_RATIO + 1.0) / x_max * (1.0 if rng.random() < 0.5 else -1.0)
    b = rng.uniform(-0.3, 0.3) * abs(a) * x_max / y_max
    z = np.array([-a, -b, 1.0]) / math.sqrt(a * a + b * b + 1.0)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _room(profile: StereoProfile, tmp: Path, distances: Sequence[float], seed: int) -> Layout:
    depth = max(distances) + 0.5
    rays = _field_rays(profile)
    half_w = 0.8 * depth * float(np.max(np.abs(rays[:, 0])))
    half_h = 0.8 * depth * float(np.max(np.abs(rays[:, 1])))
    room = (2.0 * half_w, 2.0 * half_h, depth + 0.3)
    centre = np.array([0.0, 0.0, (depth - 0.3) / 2.0])
    surfaces = [_textured(tmp, "room", box_faces(room, inward=True), (seed, 1000), _pose(np.eye(3), centre))]
    desc: dict[str, Any] = {"scene": "room", "distance_m": depth, "surfaces": [
        {"kind": "room", "centre_m": centre.tolist(), "size_m": list(room)}]}
    for k, d in enumerate(sorted(distances)):
        size = 0.25 * d * float(np.max(np.abs(rays[:, 0])))
        lateral = (-0.45, 0.45, 0.0, -0.25, 0.25)[k % 5] * d * float(np.max(np.abs(rays[:, 0])))
        R = np.asarray(Rotation.from_euler("y", 25.0 * (-1) ** k, degrees=True).as_matrix(), dtype=np.float64)
        c = np.array([lateral, 0.15 * d, d + size / 2.0])
        surfaces.append(_textured(tmp, f"box{k}", box_faces((size, size, size)), (seed, 2000 + k), _pose(R, c)))
        desc["surfaces"].append({"kind": "box", "centre_m": c.tolist(), "size_m": [size] * 3,
                                 "yaw_deg": 25.0 * (-1) ** k})
    return tuple(surfaces), desc


def scene_layouts(profile: StereoProfile, tmp: Path, *, scene: str, distances_m: Sequence[float], seed: int
                  ) -> list[Layout]:
    """The frames of ``scene`` (one per distance for planes/slanted, one room frame), textures in ``tmp``."""
    if scene == "planes":
        return [_plane_frame(profile, tmp, k, d, np.eye(3), seed, scene) for k, d in enumerate(distances_m)]
    if scene == "slanted":
        return [_plane_frame(profile, tmp, k, d, _slant(profile, k), seed, scene) for k, d in enumerate(distances_m)]
    if scene == "span":
        return [_plane_frame(profile, tmp, k, d, _span(profile, k, seed), seed, scene)
                for k, d in enumerate(distances_m)]
    if scene == "room":
        return [_room(profile, tmp, distances_m, seed)]
    raise RenderError(f"unknown scene {scene!r}", field="scene", hint=f"choose one of {', '.join(SCENES)}")


def check_distances(distances_m: Sequence[float], near: float, far: float) -> list[float]:
    """The distances as floats, each inside the clip planes; RenderError naming the bad one otherwise."""
    out = [float(d) for d in distances_m]
    if not out:
        raise RenderError("no distances given", field="distances", hint="e.g. --distances 0.5,1,2")
    for d in out:
        if not (math.isfinite(d) and near < d < far):
            raise RenderError(f"distance {d:g} m lies outside the clip planes {near:g}-{far:g} m",
                              field="distances", hint="choose distances between the clip planes")
    return out
