"""A profile camera emulated by a render backend (PyBullet or MuJoCo): supersampling, lens distortion and exact
ground-truth depth.

One capture renders an ideal pinhole ("wide" camera) in the camera's optical frame at ``S`` times the
resolution, wide enough to cover the distorted field, then

- image: remaps the wide render through the profile's distortion at ``S`` x size (bilinear) and averages
  ``S x S`` blocks down (INTER_AREA). K is scaled about pixel edges: ``c_hi = S (c + 0.5) - 0.5``,
  ``f_hi = S f``, so block averages land on the profile's pixel grid. Distortion-free cameras skip the remap.
- depth: samples the wide render's inverse depth ``1 / z`` bilinearly at each output pixel's exact ray.
  On a planar facet ``1 / z`` is affine in pinhole pixel coordinates, so this is exact (float precision);
  pixels whose 3x3 neighbourhood straddles a depth edge or the background are NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.lens.distortion import is_pinhole, normalised_rays, undistort_pixels
from s2r.profile import Camera
from s2r.render.backend import Backend, get_backend
from s2r.render.camera import PinholeView
from s2r.render.cubemap import CubeMap, lens_rays, plan_cube_map

__all__ = ["CameraSetup", "Capture", "capture", "prepared"]

FloatArray = NDArray[np.float64]
Map = tuple[NDArray[np.float32], NDArray[np.float32]]

#: Relative 1/z span within a 3x3 neighbourhood above which a pixel counts as a depth edge.
EDGE_RELATIVE_SPAN = 0.02
#: Largest wide-render size, as a multiple of the supersampled image size per axis.
_MAX_WIDE_FACTOR = 3.0
_MARGIN_PX = 3


@dataclass(frozen=True)
class CameraSetup:
    """One profile camera placed in the world (the left optical frame).

    Attributes:
        camera: the profile camera (image size, K, distortion) the output images obey.
        T_cam_world: 4x4 pose mapping world points (metres) into this camera's optical frame.
        near, far: clip planes in metres.
        supersample: render at ``supersample`` x size, then average down.
    """

    camera: Camera
    T_cam_world: FloatArray
    near: float
    far: float
    supersample: int

    def key(self) -> str:
        """A string identifying the setup (cache key)."""
        pose = ",".join(f"{v:.12g}" for v in np.asarray(self.T_cam_world).ravel())
        return f"{self.camera.model_dump_json()}|{pose}|{self.near}|{self.far}|{self.supersample}"


@dataclass(frozen=True)
class Prepared:
    """Per-process precomputation of a setup: the wide pinhole (or the cube map) and the maps into it.

    Attributes:
        wide: the wide pinhole rendered for the image; with a cube map, its first face (clip planes).
        map_hi: supersampled output pixel -> wide (or atlas) pixel; None: identity.
        map_lo: output pixel centre -> wide (or atlas) pixel.
        cube: the cube map of a lens too wide for one pinhole (module :mod:`s2r.render.cubemap`), else None.
        factor_lo: cube map only, (H, W) float32 ``a . (x, y, 1)`` turning face inverse depth into camera 1/z.
    """

    wide: PinholeView
    map_hi: Map | None
    map_lo: Map
    cube: CubeMap | None = None
    factor_lo: NDArray[np.float32] | None = None

    def locate(self, x: FloatArray, y: FloatArray) -> tuple[Map, NDArray[np.float32] | None]:
        """Wide (or atlas) pixel maps of normalised camera rays ``(x, y)`` (same shape, float64) and, with a cube
        map, the factor turning the sampled face inverse depth into the camera's 1/z (None: 1)."""
        if self.cube is None:
            return _map_into(self.wide, x, y), None
        rays = np.column_stack([x.ravel(), y.ravel(), np.ones(x.size)])
        u, v, factor = self.cube.locate(rays)
        return ((u.reshape(x.shape).astype(np.float32), v.reshape(x.shape).astype(np.float32)),
                factor.reshape(x.shape).astype(np.float32))


def _wide_view(setup: CameraSetup, cam_hi: Camera) -> PinholeView:
    """The pinhole (same focal length as ``cam_hi``) whose image covers every ray of ``cam_hi``."""
    w, h = cam_hi.width_px, cam_hi.height_px
    if is_pinhole(cam_hi):
        return PinholeView(cam_hi.K, w, h, setup.T_cam_world, setup.near, setup.far)
    t = np.linspace(-0.5, w - 0.5, 4 * w + 1)
    s = np.linspace(-0.5, h - 0.5, 4 * h + 1)
    border = np.concatenate([
        np.column_stack([t, np.full_like(t, -0.5)]), np.column_stack([t, np.full_like(t, h - 0.5)]),
        np.column_stack([np.full_like(s, -0.5), s]), np.column_stack([np.full_like(s, w - 0.5), s]),
    ])
    norm = undistort_pixels(cam_hi, border)
    fx, fy = cam_hi.fx_px, cam_hi.fy_px
    x0, y0 = norm.min(axis=0)
    x1, y1 = norm.max(axis=0)
    cx, cy = -fx * x0 + _MARGIN_PX, -fy * y0 + _MARGIN_PX
    width, height = math.ceil(fx * (x1 - x0)) + 2 * _MARGIN_PX, math.ceil(fy * (y1 - y0)) + 2 * _MARGIN_PX
    if width > _MAX_WIDE_FACTOR * w or height > _MAX_WIDE_FACTOR * h:
        raise RenderError(
            f"the lens field is too wide to render through a pinhole ({width}x{height} px needed)",
            field="distortion.coefficients", hint="use a milder distortion model or a smaller field of view",
        )
    K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    return PinholeView(K, width, height, setup.T_cam_world, setup.near, setup.far)


def _map_into(wide: PinholeView, x: FloatArray, y: FloatArray) -> Map:
    """Wide-render pixel coordinates (float32 maps) of normalised rays ``(x, y)``."""
    K = wide.K
    return (K[0, 0] * x + K[0, 2]).astype(np.float32), (K[1, 1] * y + K[1, 2]).astype(np.float32)


def _grid(camera: Camera) -> FloatArray:
    u, v = np.meshgrid(np.arange(camera.width_px, dtype=np.float64), np.arange(camera.height_px, dtype=np.float64))
    return np.column_stack([u.ravel(), v.ravel()])


def _cube_prepared(setup: CameraSetup, cam_hi: Camera) -> Prepared:
    """The cube-map precomputation of a lens too wide for one pinhole (see :mod:`s2r.render.cubemap`)."""
    cam = setup.camera
    rays_hi, ok_hi = lens_rays(cam_hi, _grid(cam_hi))
    rays_lo, ok_lo = lens_rays(cam, _grid(cam))
    if not np.any(ok_lo):
        raise RenderError("no pixel of the camera sees the scene through its lens model", field="distortion",
                          hint="check the distortion coefficients and the focal length")
    cube = plan_cube_map(cam_hi, np.concatenate([rays_hi[ok_hi], rays_lo[ok_lo]]), setup.T_cam_world,
                         setup.near, setup.far)

    def maps(camera: Camera, rays: FloatArray, ok: NDArray[np.bool_]) -> tuple[Map, NDArray[np.float32]]:
        u, v, factor = cube.locate(rays)
        u[~ok], v[~ok] = -1e4, -1e4  # outside the lens field: black, no depth
        factor = np.where(ok, factor / np.where(ok, rays[:, 2], 1.0), 1.0)  # a . (x, y, 1) for unit rays d
        shape = (camera.height_px, camera.width_px)
        return ((u.reshape(shape).astype(np.float32), v.reshape(shape).astype(np.float32)),
                factor.reshape(shape).astype(np.float32))

    map_hi, _ = maps(cam_hi, rays_hi, ok_hi)
    map_lo, factor_lo = maps(cam, rays_lo, ok_lo)
    return Prepared(cube.faces[0], map_hi, map_lo, cube, factor_lo)


_PREPARED: dict[str, Prepared] = {}


def prepared(setup: CameraSetup) -> Prepared:
    """The cached :class:`Prepared` of ``setup`` in this process."""
    key = setup.key()
    if key not in _PREPARED:
        cam = setup.camera
        s = setup.supersample
        cam_hi = cam.scaled(cam.width_px * s, cam.height_px * s) if s > 1 else cam
        try:
            wide = _wide_view(setup, cam_hi)
        except RenderError:
            if cam.distortion.model != "equidistant":
                raise
            prep = _cube_prepared(setup, cam_hi)  # a fisheye wider than one pinhole covers: cube map
        else:
            map_hi = None if is_pinhole(cam_hi) else _map_into(wide, *normalised_rays(cam_hi, cam_hi.width_px,
                                                                                      cam_hi.height_px))
            prep = Prepared(wide, map_hi, _map_into(wide, *normalised_rays(cam, cam.width_px, cam.height_px)))
        if len(_PREPARED) > 16:
            _PREPARED.clear()
        _PREPARED[key] = prep
    return _PREPARED[key]


class Capture:
    """One rendered camera: the output image, and (computed on first use) the wide render's depth.

    Attributes:
        rgb: (H, W, 3) uint8 RGB image in the profile camera's geometry (distortion included).
        wide_z: (Hw, Ww) float32 metric z (m) of the wide render along its optical axis, NaN where nothing was hit.
        prep: the setup's precomputation (wide K and maps).
    """

    def __init__(self, rgb: NDArray[np.uint8], wide_z: NDArray[np.float32], prep: Prepared) -> None:
        self.rgb = rgb
        self.wide_z = wide_z
        self.prep = prep

    @cached_property
    def inv_z(self) -> NDArray[np.float32]:
        """(Hw, Ww) float32 inverse depth 1/z (1/m) of the wide render, 0 where nothing was hit."""
        z = self.wide_z
        return np.where(np.isfinite(z) & (z > 0), 1.0 / np.where(z > 0, z, 1.0), 0.0).astype(np.float32)

    @cached_property
    def edge(self) -> NDArray[np.uint8]:
        """(Hw, Ww) uint8, 1 where the wide render's depth is not locally planar (edges, background)."""
        return _edges(self.inv_z)

    def sample_inverse_depth(self, map_xy: Map) -> NDArray[np.float32]:
        """Inverse depth (1/m) at wide-render pixel coordinates ``map_xy``; NaN near edges or background."""
        inv: NDArray[np.float32] = np.asarray(
            cv2.remap(self.inv_z, map_xy[0], map_xy[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                      borderValue=0.0), dtype=np.float32)
        bad = cv2.remap(self.edge, map_xy[0], map_xy[1], cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                        borderValue=1)
        inv[(bad > 0) | ~(inv > 0)] = np.nan
        return inv

    def inverse_z_at(self, x: FloatArray, y: FloatArray) -> NDArray[np.float32]:
        """Inverse depth 1/z (1/m, z along this camera's optical axis) of the rays with normalised coordinates
        ``(x, y)`` (float64 arrays of one shape); NaN near depth edges, background or outside the render."""
        map_xy, factor = self.prep.locate(x, y)
        inv = self.sample_inverse_depth(map_xy)
        return inv if factor is None else np.asarray(inv * factor, dtype=np.float32)

    def depth_m(self) -> NDArray[np.float32]:
        """(H, W) float32 z in metres along the camera's optical axis at each output pixel; NaN unknown."""
        inv = self.sample_inverse_depth(self.prep.map_lo)
        if self.prep.factor_lo is not None:
            inv = inv * self.prep.factor_lo
        return np.asarray(1.0 / inv, dtype=np.float32)


def _edges(inv_z: NDArray[np.float32]) -> NDArray[np.uint8]:
    kernel = np.ones((3, 3), np.uint8)
    hi = cv2.dilate(inv_z, kernel)
    lo = cv2.erode(inv_z, kernel)
    bad = (lo <= 0) | (hi - lo > EDGE_RELATIVE_SPAN * lo)
    return np.asarray(cv2.dilate(bad.astype(np.uint8), kernel), dtype=np.uint8)


def _render_atlas(cube: CubeMap, backend: Backend) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render every face of ``cube`` into one atlas: RGB (black between faces) and z (NaN = nothing)."""
    width, height = cube.atlas_size
    rgb = np.zeros((height, width, 3), np.uint8)
    depth = np.full((height, width), np.nan, np.float32)
    for view, column in zip(cube.faces, cube.offsets, strict=True):
        face_rgb, face_depth = backend.render(view)
        rgb[: view.height, column:column + view.width] = face_rgb
        depth[: view.height, column:column + view.width] = face_depth
    return rgb, depth


def capture(setup: CameraSetup, backend: Backend | None = None) -> Capture:
    """Render the backend's current world (default: PyBullet's) through ``setup`` (supersampled, distorted);
    see the module docstring."""
    backend = backend or get_backend()
    prep = prepared(setup)
    if prep.cube is None:
        rgb_w, depth_w = backend.render(prep.wide)
        border = cv2.BORDER_REPLICATE
    else:
        rgb_w, depth_w = _render_atlas(prep.cube, backend)
        border = cv2.BORDER_CONSTANT  # black outside the fisheye's field
    img = rgb_w
    if prep.map_hi is not None:
        img = np.asarray(cv2.remap(rgb_w, prep.map_hi[0], prep.map_hi[1], cv2.INTER_LINEAR, borderMode=border,
                                   borderValue=(0, 0, 0)), dtype=np.uint8)
    cam = setup.camera
    if setup.supersample > 1:
        img = np.asarray(cv2.resize(img, (cam.width_px, cam.height_px), interpolation=cv2.INTER_AREA),
                         dtype=np.uint8)
    return Capture(np.asarray(img, dtype=np.uint8), depth_w, prep)
