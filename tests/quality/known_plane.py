"""An independent device-depth recording generator, numpy only (no s2r code, no OpenCV): a chessboard plane at a
known pose seen by an ideal pinhole left camera, its depth image carrying known disparity noise, a known share of
pattern-period mismatches, a known hole share and a known depth bias. Every expected figure is computed here from
first principles."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Camera:
    """Ideal pinhole: focal lengths and principal point (px), image size (px), stereo baseline (m)."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    baseline_m: float

    @property
    def fb(self) -> float:
        """Focal length times baseline (px m)."""
        return self.fx * self.baseline_m


@dataclass(frozen=True)
class Frame:
    """One frame: 8-bit left image, device depth (uint16 mm, 0 = none), truth (m, NaN off the board), the inner-
    corner region mask, the valid and mismatched masks (both over the whole image) and the board's unit normal."""

    left: NDArray[np.uint8]
    depth_mm: NDArray[np.uint16]
    truth_m: FloatArray
    roi: NDArray[np.bool_]
    valid: NDArray[np.bool_]
    mismatched: NDArray[np.bool_]
    normal: FloatArray


def rotation(yaw_deg: float, pitch_deg: float) -> FloatArray:
    """Rotation about the camera's y axis (yaw) then x axis (pitch)."""
    a, b = np.radians(yaw_deg), np.radians(pitch_deg)
    ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    return ry @ rx


def _board_coords(cam: Camera, R: FloatArray, t: FloatArray, u: FloatArray, v: FloatArray
                  ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Where each pixel ray (pixel coordinates u, v) meets the board plane: board x, y (m) through the inverse of
    the plane's homography ``K [r1 r2 t]``, and the camera depth z of that point."""
    K = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1]])
    h = np.linalg.inv(K @ np.column_stack([R[:, 0], R[:, 1], t]))
    w = h[2, 0] * u + h[2, 1] * v + h[2, 2]
    bx = (h[0, 0] * u + h[0, 1] * v + h[0, 2]) / w
    by = (h[1, 0] * u + h[1, 1] * v + h[1, 2]) / w
    z = R[2, 0] * bx + R[2, 1] * by + t[2]
    return bx, by, z


def _texture(bx: FloatArray, by: FloatArray, pattern: tuple[int, int], square: float) -> FloatArray:
    """Board colour (0 black, 1 white) at board coordinates: first inner corner at (0, 0), one white square of
    margin around the (cols + 1) x (rows + 1) squares, 0.5 (grey) off the board."""
    cols, rows = pattern
    i, j = np.floor(bx / square), np.floor(by / square)
    on_squares = (i >= -1) & (i <= cols - 1) & (j >= -1) & (j <= rows - 1)
    on_board = (i >= -2) & (i <= cols) & (j >= -2) & (j <= rows)
    colour = np.where(on_squares, ((i + j) % 2 != 0).astype(np.float64), 1.0)
    return np.where(on_board, colour, 0.5)


def render(cam: Camera, pattern: tuple[int, int], square: float, distance_m: float, yaw: float, pitch: float, *,
           sigma_d_px: float, mismatch_share: float, hole_share: float, bias: float,
           rng: np.random.Generator, supersample: int = 3) -> Frame:
    """The board's centre ``distance_m`` ahead of the camera, turned by ``yaw``/``pitch`` degrees. Depth on the
    board: disparity ``f B / (z (1 + bias))`` plus ``N(0, sigma_d_px)``; ``mismatch_share`` of the board pixels are
    matched one pattern period (two squares) off along the row; ``hole_share`` of all pixels have no depth."""
    cols, rows = pattern
    R = rotation(yaw, pitch)
    t = np.array([0.0, 0.0, distance_m]) - R @ np.array([(cols - 1) * square / 2, (rows - 1) * square / 2, 0.0])
    s = supersample
    sub = (np.arange(s) + 0.5) / s - 0.5
    v, u = np.mgrid[0:cam.height, 0:cam.width].astype(np.float64)
    grey = np.zeros(u.shape)
    for dy in sub:
        for dx in sub:
            bx, by, _ = _board_coords(cam, R, t, u + dx, v + dy)
            grey += _texture(bx, by, pattern, square)
    left = np.clip(np.round(40 + 175 * grey / s**2), 0, 255).astype(np.uint8)
    bx, by, z = _board_coords(cam, R, t, u, v)
    on = (bx >= -2 * square) & (bx <= cols * square) & (by >= -2 * square) & (by <= rows * square) & (z > 0)
    truth = np.where(on, z, np.nan)
    d = cam.fb / (truth * (1 + bias)) + sigma_d_px * rng.standard_normal(u.shape)
    period = 2 * square * cam.fx / truth  # two squares along the row, in pixels (fronto-parallel approximation)
    mismatched = on & (rng.random(u.shape) < mismatch_share)
    d = np.where(mismatched, d + period, d)  # matched nearer: a period further along the row
    depth = np.where(on & (d > 0), np.round(1000 * cam.fb / np.where(d > 0, d, 1.0)), 0)
    depth[rng.random(u.shape) < hole_share] = 0
    depth = np.clip(depth, 0, 65535).astype(np.uint16)
    roi = _roi(cam, R, t, pattern, square, u, v)
    return Frame(left, depth, truth, roi, depth > 0, mismatched & (depth > 0), R[:, 2])


def _roi(cam: Camera, R: FloatArray, t: FloatArray, pattern: tuple[int, int], square: float, u: FloatArray,
         v: FloatArray) -> NDArray[np.bool_]:
    """Pixels inside the quadrilateral of the four outermost inner corners (convex polygon test)."""
    cols, rows = pattern
    corners = np.array([[0, 0, 0], [(cols - 1) * square, 0, 0], [(cols - 1) * square, (rows - 1) * square, 0],
                        [0, (rows - 1) * square, 0]], np.float64)
    cam_pts = corners @ R.T + t
    px = np.column_stack([cam.fx * cam_pts[:, 0] / cam_pts[:, 2] + cam.cx, cam.fy * cam_pts[:, 1] / cam_pts[:, 2]
                          + cam.cy])
    signs = []
    for k in range(4):
        (x0, y0), (x1, y1) = px[k], px[(k + 1) % 4]
        signs.append((x1 - x0) * (v - y0) - (y1 - y0) * (u - x0))
    stack = np.stack(signs)
    return np.asarray(np.all(stack >= 0, axis=0) | np.all(stack <= 0, axis=0), bool)


def expected(cam: Camera, frame: Frame, *, sigma_d_px: float, bias: float) -> dict[str, float]:
    """First-principles figures of ``frame``'s region: fill rate and mismatch share (%, from the generator's own
    masks), sub-pixel RMS (= sigma_d, px), plane-fit RMS (perpendicular distances, % of the median true depth),
    Z accuracy (% = the bias) and the median true distance (m)."""
    roi = frame.roi
    z = frame.truth_m[roi]
    v, u = np.nonzero(roi)
    rays = np.stack([(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, np.ones(u.size)])
    along = np.abs(frame.normal @ rays)
    zb = z * (1 + bias)
    dist = float(np.median(z))
    keep = frame.valid[roi] & ~frame.mismatched[roi]
    perpendicular = zb**2 * sigma_d_px / cam.fb * along
    return {"distance_m": dist, "fill_rate_pct": 100.0 * float(frame.valid[roi].mean()),
            "outlier_pct": 100.0 * float(frame.mismatched[roi].sum()) / float(frame.valid[roi].sum()),
            "subpixel_rms_px": sigma_d_px,
            "plane_fit_rms_pct": 100.0 * float(np.sqrt(np.mean(perpendicular[keep] ** 2))) / dist,
            "z_accuracy_pct": 100.0 * bias}


def write_png16(path: str, image: NDArray[np.uint16] | NDArray[np.uint8]) -> None:
    """A minimal PNG writer (zlib, no filtering), grey 8 or 16 bit: keeps the generator free of imaging libraries."""
    import struct
    import zlib

    array = np.asarray(image)
    depth = 16 if array.dtype == np.uint16 else 8
    raw = array.astype(">u2" if depth == 16 else np.uint8).tobytes()
    stride = array.shape[1] * depth // 8
    rows = b"".join(b"\x00" + raw[i * stride:(i + 1) * stride] for i in range(array.shape[0]))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", array.shape[1], array.shape[0], depth, 0, 0, 0, 0)
    with open(path, "wb") as fh:
        fh.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows, 6))
                 + chunk(b"IEND", b""))
