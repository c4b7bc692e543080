"""An independent known-answer generator: a numpy ray caster for calibration targets (no s2r code).

It shares nothing with s2r: its own lens maths (OpenCV's plumb_bob and equidistant models written out
here), its own board layouts (Kalibr's AprilGrid as ``kalibr_create_target_pdf`` draws it, ChArUco and
chessboard textures drawn by cv2.aruco / numpy), its own poses. For every output pixel (3x3 sub-pixel
samples) the ray is unprojected through the lens, intersected with the board plane and the texture is
sampled bilinearly; samples are averaged (an anti-aliased box filter), then seeded sensor noise is added.

Frames: camera optical frame (x right, y down, z forward, metres); OpenCV pixel convention (0-based pixel
centres at integers); stereo ``X_right = R @ X_left + T``. Board frames as each target's reader defines:
ChArUco / chessboard: OpenCV's (origin at the board's top-left outer corner, x right, y down along the
printed image); AprilGrid: Kalibr's (origin at tag 0's bottom-left corner, x right, y up).

Used by tests/calib/test_targets_known_answer.py and bench/bench_targets.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
SUB = 3  # sub-samples per pixel and axis


# ----------------------------------------------------------------------------------------------- lenses
@dataclass(frozen=True)
class Lens:  # hashable: rays are cached per lens
    """``model`` 'plumb_bob' (k1 k2 p1 p2 k3) or 'equidistant' (k1 k2 k3 k4); pixels."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    model: str
    dist: tuple[float, ...]

    @property
    def K(self) -> F64:
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])

    def project(self, X: F64) -> F64:
        """Pixels (N, 2) of points (N, 3) in the optical frame (NaN behind / beyond the lens' range)."""
        x, y, z = X[:, 0], X[:, 1], X[:, 2]
        if self.model == "equidistant":
            r = np.hypot(x, y)
            th = np.arctan2(r, z)
            k1, k2, k3, k4 = self.dist
            t2 = th * th
            thd = th * (1 + k1 * t2 + k2 * t2**2 + k3 * t2**3 + k4 * t2**4)
            s = np.where(r > 1e-15, thd / np.maximum(r, 1e-15), 1.0 / np.maximum(z, 1e-15))
            xd, yd = x * s, y * s
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                a, b = np.where(z > 0, x / z, np.nan), np.where(z > 0, y / z, np.nan)
            k1, k2, p1, p2, k3 = self.dist
            r2 = a * a + b * b
            rad = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
            xd = a * rad + 2 * p1 * a * b + p2 * (r2 + 2 * a * a)
            yd = b * rad + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b
        return np.column_stack([self.fx * xd + self.cx, self.fy * yd + self.cy])

    def rays(self, u: F64, v: F64) -> F64:
        """Unit ray directions (N, 3) of pixel coordinates ``u``, ``v`` (N,)."""
        xd, yd = (u - self.cx) / self.fx, (v - self.cy) / self.fy
        if self.model == "equidistant":
            thd = np.hypot(xd, yd)
            th = thd.copy()
            k1, k2, k3, k4 = self.dist
            for _ in range(30):  # Newton on theta_d(theta) = theta_d
                t2 = th * th
                f = th * (1 + k1 * t2 + k2 * t2**2 + k3 * t2**3 + k4 * t2**4) - thd
                df = 1 + 3 * k1 * t2 + 5 * k2 * t2**2 + 7 * k3 * t2**3 + 9 * k4 * t2**4
                th = th - f / df
            s = np.where(thd > 1e-15, np.sin(th) / np.maximum(thd, 1e-15), 1.0)
            return np.column_stack([xd * s, yd * s, np.cos(th)])
        k1, k2, p1, p2, k3 = self.dist
        a, b = xd.copy(), yd.copy()
        for _ in range(40):  # fixed point, then Newton-free polish by repeated residual correction
            r2 = a * a + b * b
            rad = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
            dx = 2 * p1 * a * b + p2 * (r2 + 2 * a * a)
            dy = p1 * (r2 + 2 * b * b) + 2 * p2 * a * b
            a, b = (xd - dx) / rad, (yd - dy) / rad
        d = np.column_stack([a, b, np.ones_like(a)])
        return d / np.linalg.norm(d, axis=1, keepdims=True)


# ----------------------------------------------------------------------------------------------- targets
@dataclass
class Target:
    """A planar target: a grey texture (rows, cols) uint8, ``texel_m`` metres per texel, the board-frame
    position (metres) of texel (0, 0)'s outer corner and the direction of texture rows (``y_up``: Kalibr),
    and the true corners ``ids`` -> board points (N, 3)."""

    kind: str
    texture: NDArray[np.uint8]
    texel_m: float
    y_up: bool
    ids: NDArray[np.int64]
    points: F64
    yaml: str
    extent: tuple[float, float, float, float] = field(default=(0, 0, 0, 0))  # x0 y0 x1 y1 metres

    def board_to_texel(self, bx: F64, by: F64) -> tuple[F64, F64]:
        """Continuous texel coordinates (column, row; pixel centres at integers) of board points."""
        x0, y0, _x1, y1 = self.extent
        col = (bx - x0) / self.texel_m - 0.5
        row = ((y1 - by) if self.y_up else (by - y0)) / self.texel_m - 0.5
        return col, row


def charuco_target(squares: tuple[int, int] = (11, 8), square_m: float = 0.03, marker_m: float = 0.022,
                   dictionary: str = "DICT_5X5_100", tpx: int = 80) -> Target:
    """A ChArUco board drawn by cv2.aruco, OpenCV board frame; corner id k = OpenCV's ChArUco id."""
    sx, sy = squares
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    board = cv2.aruco.CharucoBoard((sx, sy), square_m, marker_m, d)
    img = board.generateImage((sx * tpx, sy * tpx), marginSize=0, borderBits=1)
    margin = tpx  # one square of white quiet zone
    tex = np.pad(img, margin, constant_values=255)
    ids = np.arange((sx - 1) * (sy - 1))
    jj, ii = np.divmod(ids, sx - 1)
    pts = np.column_stack([(ii + 1) * square_m, (jj + 1) * square_m, np.zeros(len(ids))])
    texel = square_m / tpx
    ext = (-margin * texel, -margin * texel, (sx * tpx + margin) * texel, (sy * tpx + margin) * texel)
    yml = (f"target_type: charuco\nsquaresX: {sx}\nsquaresY: {sy}\nsquareLength: {square_m}\n"
           f"markerLength: {marker_m}\ndictionary: {dictionary}\n")
    return Target("charuco", tex, texel, False, ids, pts, yml, ext)


def chessboard_target(inner: tuple[int, int] = (9, 6), square_m: float = 0.03, tpx: int = 64) -> Target:
    """A chessboard (Kalibr 'checkerboard' file), corners row by row from the top-left inner corner."""
    cols, rows = inner[0] + 1, inner[1] + 1
    j, i = np.meshgrid(np.arange(cols * tpx) // tpx, np.arange(rows * tpx) // tpx)
    img = np.where((i + j) % 2 == 0, 0, 255).astype(np.uint8)
    tex = np.pad(img, tpx, constant_values=255)
    n = inner[0] * inner[1]
    jj, ii = np.divmod(np.arange(n), inner[0])
    pts = np.column_stack([(ii + 1) * square_m, (jj + 1) * square_m, np.zeros(n)])
    texel = square_m / tpx
    ext = (-tpx * texel, -tpx * texel, (cols + 1) * tpx * texel, (rows + 1) * tpx * texel)
    yml = (f"target_type: 'checkerboard'\ntargetCols: {inner[0]}\ntargetRows: {inner[1]}\n"
           f"rowSpacingMeters: {square_m}\ncolSpacingMeters: {square_m}\n")
    return Target("checkerboard", tex, texel, False, np.arange(n), pts, yml, ext)


def aprilgrid_target(tags: tuple[int, int] = (6, 6), tag_m: float = 0.04, spacing: float = 0.3,
                     tpx: int = 100) -> Target:
    """Kalibr's AprilGrid: tag36h11 with a 2-bit border, turned 180 deg, black squares of the gap size at
    each tag corner, tag 0 at the bottom left, Kalibr's corner ids and board frame (x right, y up)."""
    cols, rows = tags
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    gap = round(spacing * tpx)
    pitch = tpx + gap
    W, H = cols * pitch + gap, rows * pitch + gap  # grid from -gap to the far edge + gap (corner squares)
    margin = tpx // 2
    tex = np.full((H + 2 * margin, W + 2 * margin), 255, np.uint8)
    for ty in range(rows):
        for tx in range(cols):
            tid = ty * cols + tx
            mk = cv2.aruco.generateImageMarker(d, tid, tpx, borderBits=2)
            mk = mk[::-1, ::-1]  # Kalibr prints tags turned 180 degrees
            c0 = margin + gap + tx * pitch
            r0 = margin + gap + (rows - 1 - ty) * pitch  # tag 0 at the bottom
            tex[r0:r0 + tpx, c0:c0 + tpx] = mk
            for dc, dr in ((-gap, -gap), (tpx, -gap), (tpx, tpx), (-gap, tpx)):
                tex[r0 + dr:r0 + dr + gap, c0 + dc:c0 + dc + gap] = 0
    texel = tag_m / tpx
    # board frame: tag 0's bottom-left corner at (0, 0), y up; its texel column margin + gap
    x0 = -(margin + gap) * texel
    y0 = -(margin + gap) * texel
    ext = (x0, y0, x0 + tex.shape[1] * texel, y0 + tex.shape[0] * texel)
    ids, pts = [], []
    step = tag_m * (1 + gap / tpx)
    for r in range(2 * rows):
        for c in range(2 * cols):
            ids.append(r * 2 * cols + c)
            pts.append([(c // 2) * step + (c % 2) * tag_m, (r // 2) * step + (r % 2) * tag_m, 0.0])
    yml = (f"target_type: 'aprilgrid'\ntagCols: {cols}\ntagRows: {rows}\ntagSize: {tag_m}\n"
           f"tagSpacing: {gap / tpx}\n")
    return Target("aprilgrid", tex, texel, True, np.array(ids), np.array(pts), yml, ext)


# ----------------------------------------------------------------------------------------------- render
def _sample(tex: NDArray[np.float32], col: F64, row: F64, bg: F64) -> F64:
    """Bilinear texture samples at texel coordinates (N,), ``bg`` outside the texture."""
    n = col.size
    cols = 4096
    pad = (-n) % cols
    mx = np.pad(col.astype(np.float32), (0, pad), constant_values=-10.0).reshape(-1, cols)
    my = np.pad(row.astype(np.float32), (0, pad), constant_values=-10.0).reshape(-1, cols)
    val = cv2.remap(tex, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=-1.0).reshape(-1)[:n]
    inside = (col >= -0.5) & (col <= tex.shape[1] - 0.5) & (row >= -0.5) & (row <= tex.shape[0] - 0.5)
    return np.where(inside & (val >= 0), val, bg)


_RAYS: dict[Lens, NDArray[np.float32]] = {}


def _lens_rays(lens: Lens) -> NDArray[np.float32]:
    """Unit rays (SUB * SUB, H * W, 3) of every sub-sample of every pixel (cached per lens)."""
    if lens not in _RAYS:
        h, w = lens.height, lens.width
        offs = (np.arange(SUB) + 0.5) / SUB - 0.5
        vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
        if len(_RAYS) > 2:
            _RAYS.clear()
        _RAYS[lens] = np.stack([lens.rays((uu + ox).ravel(), (vv + oy).ravel()).astype(np.float32)
                                for oy in offs for ox in offs])
    return _RAYS[lens]


def render(lens: Lens, target: Target, R_cam_board: F64, t_cam_board: F64, *, seed: int,
           noise: float = 1.0) -> NDArray[np.uint8]:
    """Grey image (H, W) of the target at pose ``X_cam = R X_board + t`` through ``lens``."""
    rng = np.random.default_rng(seed)
    h, w = lens.height, lens.width
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    bg = (90.0 + 25.0 * np.sin(uu / 23.0) * np.cos(vv / 31.0)).ravel()  # a smooth background
    ex, ey, n = (R_cam_board[:, k].astype(np.float32) for k in range(3))
    tn, tx, ty = (float(t_cam_board @ R_cam_board[:, k]) for k in (2, 0, 1))
    acc = np.zeros(h * w)
    tex = target.texture.astype(np.float32)
    for d in _lens_rays(lens):
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.float32(tn) / (d @ n)  # ray length to the board plane
        bx, by = s * (d @ ex) - np.float32(tx), s * (d @ ey) - np.float32(ty)  # board frame, metres
        col, row = target.board_to_texel(bx, by)
        ok = (s > 0) & np.isfinite(s)
        acc += _sample(tex, np.where(ok, col, -10.0), np.where(ok, row, -10.0), bg)
    img = 0.1 * 255 + 0.8 * (acc.reshape(h, w) / SUB**2)  # contrast 25..229, so noise does not clip
    img = img + rng.normal(0.0, noise, img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


# ----------------------------------------------------------------------------------------------- rigs
@dataclass
class Rig:
    name: str
    left: Lens
    right: Lens
    R: F64  # X_right = R X_left + T
    T: F64
    target: Target


def _rot(rv: F64) -> F64:
    return np.asarray(cv2.Rodrigues(np.asarray(rv, np.float64).reshape(3, 1))[0], np.float64)


def _scaled(lens: Lens, s: float) -> Lens:
    """The lens at ``s`` x the resolution (K scaled about pixel edges)."""
    return Lens(round(lens.width * s), round(lens.height * s), lens.fx * s, lens.fy * s, s * (lens.cx + 0.5) - 0.5,
                s * (lens.cy + 0.5) - 0.5, lens.model, lens.dist)


def pinhole_rig(target: Target, name: str, scale: float = 1.0) -> Rig:
    """640x480 (x ``scale``) pinhole plumb_bob rig, 8 cm baseline, slightly rotated right camera."""
    lens_l = Lens(640, 480, 520.0, 521.5, 323.4, 236.8, "plumb_bob", (-0.21, 0.06, 0.0004, -0.0003, 0.0))
    lens_r = Lens(640, 480, 518.2, 519.1, 317.9, 243.1, "plumb_bob", (-0.19, 0.05, -0.0002, 0.0002, 0.0))
    R = _rot(np.radians([0.4, -0.7, 0.3]))
    return Rig(name, _scaled(lens_l, scale), _scaled(lens_r, scale), R, -R @ np.array([0.08, 0.001, -0.0005]), target)


def fisheye_rig(target: Target, name: str, scale: float = 1.0) -> Rig:
    """T265-like 848x800 (x ``scale``) equidistant pair (about 160 deg diagonal), 6.4 cm baseline."""
    lens_l = Lens(848, 800, 286.2, 286.9, 425.3, 398.1, "equidistant", (-0.0074, 0.043, -0.041, 0.0076))
    lens_r = Lens(848, 800, 285.1, 285.6, 421.6, 403.7, "equidistant", (-0.0061, 0.041, -0.039, 0.0072))
    R = _rot(np.radians([0.3, 0.5, -0.2]))
    return Rig(name, _scaled(lens_l, scale), _scaled(lens_r, scale), R, -R @ np.array([0.064, -0.0004, 0.0003]),
               target)


def _visible(lens: Lens, X: F64, margin: float = 4.0) -> NDArray[np.bool_]:
    uv = lens.project(X)
    ok = np.isfinite(uv).all(axis=1) & (X[:, 2] > 0.05)
    ok &= (uv[:, 0] > margin) & (uv[:, 0] < lens.width - 1 - margin)
    ok &= (uv[:, 1] > margin) & (uv[:, 1] < lens.height - 1 - margin)
    return ok


def _dir_of_pixel(lens: Lens, u: float, v: float) -> F64:
    return lens.rays(np.array([u]), np.array([v]))[0]


def sample_poses(rig: Rig, views: int, seed: int, cut_share: float = 0.4) -> list[tuple[F64, F64, bool]]:
    """``views`` poses (R_left_board, t_left_board, cut?) with ~``cut_share`` of them cut by an image edge
    in at least one camera, the rest whole in both."""
    rng = np.random.default_rng(seed)
    tg = rig.target
    x0, y0, x1, y1 = tg.extent
    centre = tg.points.mean(axis=0)
    size = max(x1 - x0, y1 - y0)
    fov = 2 * math.atan(0.5 * rig.left.width / rig.left.fx)
    wide = rig.left.model == "equidistant"
    out: list[tuple[F64, F64, bool]] = []
    n_cut = round(cut_share * views)
    want_cut = [k * n_cut // views != (k + 1) * n_cut // views for k in range(views)]
    while len(out) < views:
        cut = want_cut[len(out)]
        for _ in range(5000):
            if wide:
                dist = rng.uniform(0.9, 1.8) * size / (2 * math.tan(0.5 * min(fov, 1.6)))
                spread = 0.42 if cut else 0.30
            else:
                dist = rng.uniform(1.0, 1.7) * size / (2 * math.tan(0.5 * fov))
                spread = 0.55 if cut else 0.30
            u = rig.left.cx + rng.uniform(-1, 1) * spread * rig.left.width * (1.3 if cut else 1)
            v = rig.left.cy + rng.uniform(-1, 1) * spread * rig.left.height * (1.3 if cut else 1)
            ray = _dir_of_pixel(rig.left, u, v)
            tilt = np.radians(rng.uniform(10, 45)) * np.array([*(lambda a: (math.cos(a), math.sin(a)))(
                rng.uniform(0, 2 * math.pi)), 0.0])
            roll = np.radians(rng.uniform(-30, 30))
            R = _rot(tilt) @ _rot(np.array([0, 0, roll]))
            if tg.y_up:  # Kalibr's frame has y up: flip so the printed face looks at the camera
                R = R @ np.diag([1.0, -1.0, -1.0])
            t = ray / ray[2] * dist - R @ centre if ray[2] > 0.2 else ray * dist - R @ centre
            XL = tg.points @ R.T + t
            XR = XL @ rig.R.T + rig.T
            # the printed face must face the camera
            normal = R[:, 2] if tg.y_up else -R[:, 2]
            if normal @ (-(R @ centre + t)) < 0.2 * np.linalg.norm(R @ centre + t):
                continue
            vl, vr = _visible(rig.left, XL), _visible(rig.right, XR)
            if cut:
                share = min(vl.mean(), vr.mean())
                if not (0.3 <= share <= 0.8) or (vl & vr).sum() < 12:
                    continue
                if vl.all() and vr.all():
                    continue
            elif not (vl.all() and vr.all()):
                continue
            out.append((R, t, cut))
            break
        else:
            raise RuntimeError("no pose found")
    return out


def write_rig(rig: Rig, folder: Path, *, views: int = 20, seed: int = 0, noise: float = 1.0) -> dict[str, object]:
    """Render ``views`` stereo pairs into ``folder/left/NN.png``, ``folder/right/NN.png``, write
    ``folder/target.yaml``; returns the truth (K, D, R, T, poses)."""
    (folder / "left").mkdir(parents=True, exist_ok=True)
    (folder / "right").mkdir(parents=True, exist_ok=True)
    (folder / "target.yaml").write_text(rig.target.yaml)
    poses = sample_poses(rig, views, seed)
    for k, (R, t, _cut) in enumerate(poses):
        for side, lens, (Rs, ts) in (("left", rig.left, (R, t)), ("right", rig.right, (rig.R @ R, rig.R @ t + rig.T))):
            img = render(lens, rig.target, Rs, ts, seed=seed * 1000 + 2 * k + (side == "right"), noise=noise)
            cv2.imwrite(str(folder / side / f"{k:02d}.png"), img)
    return {"left": rig.left, "right": rig.right, "R": rig.R, "T": rig.T, "poses": poses,
            "cut": sum(c for *_, c in poses)}
