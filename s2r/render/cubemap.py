"""Wide lenses rendered through a cube map: several pinhole faces from one camera centre, resampled.

A single pinhole cannot cover a field near 180 degrees (its image grows as ``tan(theta)``), so wide
fisheye cameras are rendered through up to five 90-degree faces of a cube centred on the camera (front,
right, left, down, up in the optical frame: z forward, x right, y down). Every output pixel is
back-projected to its unit ray through the profile's lens model, assigned to the face whose axis is
closest to the ray (so it lies inside that face's 90-degree square) and mapped to that face's pixel
coordinates. Each face is cropped to the rays it receives plus a margin of ``MARGIN_PX`` pixels, so the
bilinear sample and the 3x3 depth-edge test never reach a face's border: faces overlap by that margin and
there is no seam to blend. The faces are laid side by side in one atlas image, so one ``cv2.remap`` reads
them all.

All faces share the focal length of the (supersampled) output camera, so the centre of the field is
sampled as densely as the single-pinhole path samples it (and more densely towards the face edges).

Depth: a face's depth buffer gives ``z_face`` along that face's axis ``a``. For a ray ``d`` in the camera
frame, ``1 / z_cam = (1 / z_face) * (a . d) / d_z``; with ``d = (x, y, 1)`` (normalised coordinates) the
factor is ``a . (x, y, 1)``. ``1 / z_face`` is affine in face pixels on a planar facet, so bilinear samples
are exact as in the single-pinhole path.

Equidistant (OpenCV fisheye) rays come from solving ``theta_d = theta (1 + k1 theta^2 + ... + k4 theta^8)``
for ``theta`` by Newton steps. OpenCV's model covers ``theta < 90`` degrees only (``cv2.fisheye.projectPoints``
takes ``theta = atan(r)``), so pixels beyond it, or beyond the point where ``theta_d(theta)`` stops growing, see
no scene: they are rendered black (like the dark ring around a real fisheye's image circle) and their depth is NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.lens.distortion import distort_normalised, undistort_pixels
from s2r.profile import Camera
from s2r.render.camera import PinholeView

__all__ = ["FACE_ROTATIONS", "MARGIN_PX", "CubeMap", "lens_rays", "plan_cube_map"]

FloatArray = NDArray[np.float64]
Map = tuple[NDArray[np.float32], NDArray[np.float32]]

#: Rotations ``R_face_cam`` (rows: the face's x, y, z axes in the camera frame): front, right, left, down, up.
FACE_ROTATIONS: tuple[FloatArray, ...] = (
    np.eye(3),
    np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
    np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]),
    np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
    np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
)
#: Pixels every face extends beyond the rays it serves (bilinear sample + 3x3 edge test + dilation).
MARGIN_PX = 4
#: Columns of empty atlas between two faces.
_GAP_PX = 2
#: Largest ray angle OpenCV's equidistant model represents, radians (just under 90 degrees).
_THETA_LIMIT = 0.5 * math.pi - 1e-6
_NEWTON_STEPS = 30


def _equidistant_theta(D: FloatArray, theta_d: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """``theta`` (radians) with ``theta (1 + k1 t^2 + k2 t^4 + k3 t^6 + k4 t^8) = theta_d``, and where it is valid
    (``theta`` below 90 degrees and on the rising branch of the polynomial, round trip < 1e-9 rad)."""
    k1, k2, k3, k4 = (float(v) for v in D[:4])

    def poly(t: FloatArray) -> tuple[FloatArray, FloatArray]:
        t2 = t * t
        value = t * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
        slope = 1 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
        return value, slope

    # The rising branch ends at the first zero of the slope (or at 90 degrees): find it on a fine grid.
    grid = np.linspace(0.0, _THETA_LIMIT, 4001)
    falling = np.nonzero(poly(grid)[1] <= 0)[0]
    theta_end = float(grid[falling[0] - 1]) if len(falling) else _THETA_LIMIT
    theta_d_end = float(poly(np.array([theta_end]))[0][0])
    inside = theta_d < theta_d_end
    theta = np.full(theta_d.shape, theta_end)
    t = theta_d[inside].copy()
    for _ in range(_NEWTON_STEPS):
        value, slope = poly(t)
        step = (value - theta_d[inside]) / np.maximum(slope, 1e-9)
        t = np.clip(t - step, 0.0, theta_end)
        if float(np.max(np.abs(step), initial=0.0)) < 1e-13:
            break
    theta[inside] = t
    valid = inside & (np.abs(poly(theta)[0] - theta_d) < 1e-9)
    return theta, valid


def lens_rays(camera: Camera, pixels: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Unit rays ``(N, 3)`` (camera optical frame) of pixels ``(N, 2)`` of ``camera``, and which pixels see any
    scene at all (see the module docstring; always all of them for non-fisheye models)."""
    pix = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    if camera.distortion.model != "equidistant":
        norm = undistort_pixels(camera, pix)
        d = np.column_stack([norm, np.ones(len(norm))])
        return d / np.linalg.norm(d, axis=1, keepdims=True), np.ones(len(pix), dtype=bool)
    Kinv = np.linalg.inv(camera.K)
    xd = Kinv[0, 0] * pix[:, 0] + Kinv[0, 1] * pix[:, 1] + Kinv[0, 2]
    yd = Kinv[1, 1] * pix[:, 1] + Kinv[1, 2]
    theta_d = np.hypot(xd, yd)
    theta, valid = _equidistant_theta(camera.D, theta_d)
    scale = np.where(theta_d > 1e-15, np.sin(theta) / np.maximum(theta_d, 1e-15), 1.0)
    rays = np.column_stack([xd * scale, yd * scale, np.cos(theta)])
    # Cross-check against OpenCV's forward model (the one the profile means): pixel round trip < 1e-3 px.
    ok = valid & (rays[:, 2] > 1e-6)
    if np.any(ok):
        xs, ys = distort_normalised(camera, rays[ok, 0] / rays[ok, 2], rays[ok, 1] / rays[ok, 2])
        back = (camera.K @ np.vstack([xs, ys, np.ones_like(xs)]))[:2].T
        err = float(np.max(np.abs(back - pix[ok])))
        if not err < 1e-3:
            raise RenderError(f"the fisheye lens model cannot be inverted over the image (round trip {err:.3g} px)",
                              field="distortion.coefficients", hint="check the equidistant coefficients k1..k4")
    return rays, ok


@dataclass(frozen=True)
class CubeMap:
    """The faces a wide camera is rendered through, laid side by side in one atlas image.

    Attributes:
        faces: the face pinholes (shared focal length, cropped principal points, world poses).
        axes: (n, 3) each face's optical axis in the camera frame.
        rotations: each face's ``R_face_cam``.
        offsets: atlas column of each face's pixel column 0.
        atlas_size: ``(width, height)`` of the atlas in pixels.
    """

    faces: tuple[PinholeView, ...]
    axes: FloatArray
    rotations: tuple[FloatArray, ...]
    offsets: tuple[int, ...]
    atlas_size: tuple[int, int]

    def locate(self, rays: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Atlas pixel coordinates ``(u, v)`` (N,) of rays ``(N, 3)`` (camera frame, any length, z > 0 not needed)
        and each ray's factor ``a . d`` (``d`` as given, ``a`` the face axis it falls on)."""
        d = np.asarray(rays, dtype=np.float64).reshape(-1, 3)
        dots = d @ self.axes.T
        face = np.argmax(dots, axis=1)
        u = np.full(len(d), -1e4)
        v = np.full(len(d), -1e4)
        for k, view in enumerate(self.faces):
            sel = face == k
            if not np.any(sel):
                continue
            q = d[sel] @ self.rotations[k].T
            u[sel] = view.K[0, 0] * q[:, 0] / q[:, 2] + view.K[0, 2] + self.offsets[k]
            v[sel] = view.K[1, 1] * q[:, 1] / q[:, 2] + view.K[1, 2]
        return u, v, dots[np.arange(len(d)), face]


def plan_cube_map(camera_hi: Camera, rays: FloatArray, T_cam_world: FloatArray, near: float,
                  far: float) -> CubeMap:
    """The cropped faces (focal length of ``camera_hi``, pixels) that hold every ray of ``rays`` ``(N, 3)``
    with ``MARGIN_PX`` pixels to spare; ``T_cam_world`` is the camera's world-to-optical pose."""
    f = max(camera_hi.fx_px, camera_hi.fy_px)
    axes_all = np.array([R[2] for R in FACE_ROTATIONS])
    face = np.argmax(rays @ axes_all.T, axis=1)
    faces: list[PinholeView] = []
    rotations: list[FloatArray] = []
    offsets: list[int] = []
    column = 0
    for k, R in enumerate(FACE_ROTATIONS):
        sel = face == k
        if not np.any(sel):
            continue
        q = rays[sel] @ R.T
        x, y = q[:, 0] / q[:, 2], q[:, 1] / q[:, 2]
        x0, x1, y0, y1 = float(x.min()), float(x.max()), float(y.min()), float(y.max())
        cx, cy = -f * x0 + MARGIN_PX, -f * y0 + MARGIN_PX
        width = math.ceil(f * (x1 - x0)) + 2 * MARGIN_PX + 1
        height = math.ceil(f * (y1 - y0)) + 2 * MARGIN_PX + 1
        T_face_world = np.eye(4)
        T_face_world[:3, :3] = R
        K = np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])
        faces.append(PinholeView(K, width, height, T_face_world @ np.asarray(T_cam_world, np.float64), near, far))
        rotations.append(R)
        offsets.append(column)
        column += width + _GAP_PX
    height = max(view.height for view in faces)
    axes = np.array([R[2] for R in rotations])
    return CubeMap(tuple(faces), axes, tuple(rotations), tuple(offsets), (column - _GAP_PX, height))
