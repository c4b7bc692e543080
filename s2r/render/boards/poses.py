"""Calibration-board poses that cover the image, tilt up to ~45 deg and keep the board inside both images.

The board frame (OpenCV's calibration object frame): origin at the first inner corner, x along the
pattern's columns, y along its rows, z into the board (away from a camera that sees its printed face).
Inner corner (i, j) sits at ``(i * square_m, j * square_m, 0)``. Poses are ``T_left_board`` (4x4, metres).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.errors import RenderError
from s2r.lens.distortion import project_points
from s2r.profile import Camera, StereoProfile
from s2r.render.rig import clip_planes

__all__ = ["BoardGeometry", "distance_range_m", "sample_board_poses"]

FloatArray = NDArray[np.float64]

#: Fraction of the image the board (with its margin) spans at the nearest / farthest sampled distance.
FILL_NEAR, FILL_FAR, FILL_MAX = 0.60, 0.40, 0.90
#: Smallest square, pixels: on a fronto-parallel board, and after tilt in any sampled view.
MIN_FRONTAL_SQUARE_PX, MIN_SQUARE_PX = 12.0, 8.0
MIN_TILT_DEG, MAX_TILT_DEG, MAX_VIEW_ANGLE_DEG = 30.0, 45.0, 70.0
#: In-plane roll range: never near 0, because pixel-aligned edges alias worst (no anti-aliasing).
MIN_ROLL_DEG, MAX_ROLL_DEG = 8.0, 30.0
#: Image cells (columns, rows) of the coverage check in :mod:`s2r.calib.detect.coverage`; corner views aim to put
#: inner corners in the 2x2 cells at each image corner of both cameras.
COVERAGE_GRID = (8, 6)
#: Corner views: tilt range (degrees, far edge at the image corner) and candidates tried per view.
CORNER_TILT_DEG = (22.0, 45.0)
#: Corner views may stand this much farther than the farthest other view (a smaller board reaches closer to
#: the image corner past the stereo disparity); nearer candidates win among equally good ones.
CORNER_FAR_FACTOR = 1.5
#: Corner views see the board obliquely already; beyond this angle (line of sight to board normal, degrees)
#: the chessboard detector starts to miss them.
CORNER_MAX_VIEW_DEG = 58.0
#: ... and below this ratio of shortest to longest imaged square side (steep perspective).
CORNER_MIN_SQUARE_RATIO = 0.58
_CORNER_TRIES = 600
_CELL_SAFETY_PX = 4.0
_EDGE_MARGIN_PX = 3.0
_SHRINK_STEPS, _RELAX_STEPS = 21, 30


@dataclass(frozen=True)
class BoardGeometry:
    """A chessboard of ``pattern`` inner corners (columns, rows), ``square_m`` squares and a light margin."""

    pattern: tuple[int, int]
    square_m: float
    border_squares: float

    @property
    def extent_m(self) -> tuple[float, float, float, float]:
        """``(x0, y0, x1, y1)`` of the whole board (squares plus margin) in the board frame, metres."""
        s, b = self.square_m, self.border_squares
        return (-(1 + b) * s, -(1 + b) * s, (self.pattern[0] + b) * s, (self.pattern[1] + b) * s)

    @property
    def size_m(self) -> tuple[float, float]:
        """Board width and height with the margin, metres."""
        x0, y0, x1, y1 = self.extent_m
        return x1 - x0, y1 - y0

    def corners(self) -> FloatArray:
        """Inner corners ``(cols * rows, 3)`` in OpenCV's order (row by row), board frame, metres (read-only:
        made once per board, as the pose search asks for them thousands of times)."""
        return _corners(self)

    def outline(self, per_edge: int = 8) -> FloatArray:
        """Points ``(4 * per_edge, 3)`` along the board's outer edge, board frame, metres (read-only)."""
        return _outline(self, per_edge)

    def centre(self) -> FloatArray:
        """Centre of the squares area in the board frame, metres (read-only)."""
        return _centre(self)


def _read_only(a: FloatArray) -> FloatArray:
    a.setflags(write=False)
    return a


@functools.lru_cache(maxsize=16)
def _corners(board: BoardGeometry) -> FloatArray:
    cols, rows = board.pattern
    j, i = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return _read_only(np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]).astype(np.float64) * board.square_m)


@functools.lru_cache(maxsize=16)
def _outline(board: BoardGeometry, per_edge: int) -> FloatArray:
    x0, y0, x1, y1 = board.extent_m
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)
    xs = np.concatenate([x0 + (x1 - x0) * t, np.full_like(t, x1), x1 - (x1 - x0) * t, np.full_like(t, x0)])
    ys = np.concatenate([np.full_like(t, y0), y0 + (y1 - y0) * t, np.full_like(t, y1), y1 - (y1 - y0) * t])
    return _read_only(np.column_stack([xs, ys, np.zeros_like(xs)]))


@functools.lru_cache(maxsize=16)
def _centre(board: BoardGeometry) -> FloatArray:
    return _read_only(np.array([(board.pattern[0] - 1) / 2.0, (board.pattern[1] - 1) / 2.0, 0.0]) * board.square_m)


def distance_range_m(profile: StereoProfile, board: BoardGeometry) -> tuple[float, float]:
    """Nearest and farthest board distance (metres) to sample, from fill, square size and clip planes."""
    cam = profile.left
    bw, bh = board.size_m
    fill_1m = max(bw * cam.fx_px / cam.width_px, bh * cam.fy_px / cam.height_px)  # image fraction at 1 m
    d_square = board.square_m * min(cam.fx_px, cam.fy_px) / MIN_FRONTAL_SQUARE_PX
    if fill_1m / d_square > FILL_MAX:
        raise RenderError(
            f"a {board.pattern[0]}x{board.pattern[1]} board of {board.square_m * 1000:g} mm squares spans "
            f"{100 * fill_1m / d_square:.0f}% of the image where its squares are {MIN_FRONTAL_SQUARE_PX:g} px; "
            "it cannot fit the view at any distance with refinable corners",
            field="pattern", hint="use fewer corners (--pattern) or a higher-resolution profile",
        )
    near_d, far_d = fill_1m / FILL_NEAR, min(fill_1m / FILL_FAR, d_square)
    near_d = min(near_d, far_d)
    near, far = clip_planes(profile)
    half = 0.5 * math.hypot(bw, bh)
    lo, hi = max(near_d, 1.2 * near + half), min(far_d, 0.9 * far - half)
    if lo > hi:
        if 0.9 * far - half < near_d:
            raise RenderError(
                f"the far clip plane ({far:g} m) cuts off the board, which must be {near_d:.2f}-{far_d:.2f} m away",
                field="simulation.clip_far_m", hint=f"raise clip_far_m above {(near_d + half) / 0.9:.2f} m",
            )
        raise RenderError(
            f"the near clip plane ({near:g} m) cuts off the board, which must be {near_d:.2f}-{far_d:.2f} m away",
            field="simulation.clip_near_m", hint=f"lower clip_near_m below {(far_d - half) / 1.2:.3f} m",
        )
    return lo, hi


def _fits(profile: StereoProfile, board: BoardGeometry, T: FloatArray, *,
          max_view_deg: float = MAX_VIEW_ANGLE_DEG) -> bool:
    """True when the whole board lies inside both images, in front, facing them (the board normal at most
    ``max_view_deg`` from the line of sight to its centre), with big enough squares."""
    near, far = clip_planes(profile)
    outline, corners = board.outline(), board.corners()
    for cam, R, t in ((profile.left, np.eye(3), np.zeros(3)), (profile.right, profile.R, profile.T)):
        T_cam = np.eye(4)
        T_cam[:3, :3], T_cam[:3, 3] = R @ T[:3, :3], R @ T[:3, 3] + t
        pts = outline @ T_cam[:3, :3].T + T_cam[:3, 3]
        if np.any(pts[:, 2] < 1.2 * near) or np.any(pts[:, 2] > 0.9 * far):
            return False
        centre = T_cam[:3, :3] @ board.centre() + T_cam[:3, 3]
        cos_view = float(T_cam[:3, 2] @ centre / np.linalg.norm(centre))
        if cos_view < math.cos(math.radians(max_view_deg)):
            return False
        uv = project_points(cam, pts)
        m = _EDGE_MARGIN_PX
        if np.any(uv < m) or np.any(uv[:, 0] > cam.width_px - 1 - m) or np.any(uv[:, 1] > cam.height_px - 1 - m):
            return False
        grid = project_points(cam, corners @ T_cam[:3, :3].T + T_cam[:3, 3])
        grid = grid.reshape(board.pattern[1], board.pattern[0], 2)
        step = min(np.linalg.norm(np.diff(grid, axis=0), axis=2).min(), np.linalg.norm(np.diff(grid, axis=1),
                                                                                       axis=2).min())
        if step < MIN_SQUARE_PX:
            return False
    return True


def _candidate(profile: StereoProfile, board: BoardGeometry, target: FloatArray, d: float, tilt: FloatArray,
               roll: float) -> FloatArray:
    return _candidate_in(profile.left, board, target, d, tilt, roll)


def _candidate_in(cam: Camera, board: BoardGeometry, target: FloatArray, d: float, tilt: FloatArray,
                  roll: float) -> FloatArray:
    """``T_cam_board`` with the board centre ``d`` metres along pixel ``target``'s (pinhole) ray, tilted by
    rotation vector ``tilt`` (camera frame, radians) after an in-plane ``roll`` (radians)."""
    ray = np.array([(target[0] - cam.cx_px) / cam.fx_px, (target[1] - cam.cy_px) / cam.fy_px, 1.0])
    R = Rotation.from_rotvec(tilt).as_matrix() @ Rotation.from_euler("z", roll).as_matrix()
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = d * ray - R @ board.centre()
    return T


def _schedule(d0: float, hi: float) -> Iterator[tuple[float, float, float]]:
    """Fallbacks ``(shrink, distance, relax)`` for a view that does not fit: at each pull toward the image
    centre (``shrink`` 1 -> 0) first try moving the board back a little (the stereo overlap widens with
    distance; far boards constrain the focal length less, so only a third of the way),
    then reduce tilt and roll (``relax``) at the centre and the farthest distance."""
    steps = [d0 + (hi - d0) * t for t in (0.0, 1 / 3)]
    for shrink in np.linspace(1.0, 0.0, _SHRINK_STEPS):
        for d in steps:
            yield float(shrink), d, 1.0
    for k in range(1, _RELAX_STEPS + 1):
        yield 0.0, hi, 0.9**k


def _to_left(profile: StereoProfile, T_cam: FloatArray, camera: str) -> FloatArray:
    """``T_left_board`` from a pose in ``camera``'s optical frame (left: unchanged; right: X_r = R X_l + T)."""
    if camera == "left":
        return T_cam
    T = np.eye(4)
    T[:3, :3] = profile.R.T @ T_cam[:3, :3]
    T[:3, 3] = profile.R.T @ (T_cam[:3, 3] - profile.T)
    return T


def _region_cells(n: int, side: float) -> range:
    """Grid indices (of ``n``) of the coverage check's third of the image at ``side`` (-1, 0, +1)."""
    part = int(side) + 1
    return range(part * n // 3, (part + 1) * n // 3)


def _region_score(profile: StereoProfile, board: BoardGeometry, T: FloatArray, sx: float, sy: float
                  ) -> tuple[float, float, float]:
    """Score of a fitting pose for image region ``(sx, sy)`` (each -1, 0 or +1; a corner or an edge middle):
    the smaller share, over both cameras, of that region's coverage cells reached by inner corners, the
    larger distance (in cells) from the region's outer point to the nearest inner corner, and the smallest
    ratio of shortest to longest imaged square side (perspective foreshortening)."""
    share, worst, ratio = 1.0, 0.0, 1.0
    gx, gy = COVERAGE_GRID
    cols, rows = _region_cells(gx, sx), _region_cells(gy, sy)
    for cam, R, t in ((profile.left, np.eye(3), np.zeros(3)), (profile.right, profile.R, profile.T)):
        uv = project_points(cam, board.corners() @ (R @ T[:3, :3]).T + (R @ T[:3, 3] + t))
        inward = uv - _CELL_SAFETY_PX * np.array([sx, sy])  # count a cell only with a corner well inside it
        cell = np.floor((inward + 0.5) * np.array([gx / cam.width_px, gy / cam.height_px])).astype(int)
        inside = cell[(cell[:, 0] >= cols.start) & (cell[:, 0] < cols.stop) & (cell[:, 1] >= rows.start)
                      & (cell[:, 1] < rows.stop)]
        hit = np.unique(inside[:, 0] * gy + inside[:, 1]).size  # distinct cells reached
        share = min(share, hit / (len(cols) * len(rows)))
        anchor = np.array([(sx + 1) / 2 * cam.width_px, (sy + 1) / 2 * cam.height_px])
        off = np.abs(uv - anchor) * np.array([gx / cam.width_px, gy / cam.height_px])
        worst = max(worst, float(np.min(np.max(off, axis=1))))
        grid = uv.reshape(board.pattern[1], board.pattern[0], 2)
        sides = np.concatenate([np.linalg.norm(np.diff(grid, axis=a), axis=2).ravel() for a in (0, 1)])
        ratio = min(ratio, float(sides.min() / sides.max()))
    return share, worst, ratio


def _corner_params(rng: np.random.Generator, around: FloatArray | None) -> FloatArray:
    """Corner-view parameters ``(ax, ay, u, dphi, tilt_deg, roll_deg)``: aim as a share of the image
    half-size, log-distance fraction ``u``, tilt-axis offset (radians) and signed roll; drawn uniformly, or
    near ``around`` (a local refinement step), always within the sampling bounds."""
    lo_b = np.array([0.25, 0.25, 0.0, -0.4, CORNER_TILT_DEG[0], MIN_ROLL_DEG])
    hi_b = np.array([0.85, 0.85, 1.0, 0.4, CORNER_TILT_DEG[1], MAX_ROLL_DEG])
    if around is None:
        p: FloatArray = rng.uniform(lo_b, hi_b)
        p[5] *= rng.choice([-1.0, 1.0])
        return p
    sign = 1.0 if around[5] >= 0 else -1.0
    step = rng.normal(0.0, 0.08, 6) * (hi_b - lo_b)
    p = np.clip(np.concatenate([around[:5], [abs(around[5])]]) + step, lo_b, hi_b)
    p[5] *= sign
    return p


def _corner_pose(profile: StereoProfile, board: BoardGeometry, rng: np.random.Generator, sx: float, sy: float,
                 lo: float, hi: float) -> FloatArray | None:
    """The best fitting candidate with inner corners in image region ``(sx, sy)`` (see :func:`_region_score`).

    The centre is aimed toward that region in the camera that sees least there (left for the left side,
    right for the right one: the other camera's view is shifted outward by the disparity), tilted
    ``CORNER_TILT_DEG`` so the far edge is at the region (smaller squares reach closer to it), rolled like
    any view; candidates are drawn at random, then refined around the best. Among candidates reaching half
    the region's cells the nearest wins. None when no candidate fits.
    """
    camera = "left" if sx < 0 else "right"
    cam = profile.left if camera == "left" else profile.right
    half, centre = np.array([cam.width_px / 2.0, cam.height_px / 2.0]), np.array([cam.cx_px, cam.cy_px])
    far = min(CORNER_FAR_FACTOR * hi, 0.9 * clip_planes(profile)[1] - 0.5 * math.hypot(*board.size_m))
    best: tuple[tuple[float, float], FloatArray, FloatArray] | None = None
    for k in range(_CORNER_TRIES):
        p = _corner_params(rng, best[2] if best is not None and k >= _CORNER_TRIES // 2 else None)
        d = float(lo * (far / lo) ** p[2])
        phi = math.atan2(-sx, sy) + p[3]  # far edge toward (sx, sy)
        tilt = math.radians(p[4]) * np.array([math.cos(phi), math.sin(phi), 0.0])
        T = _to_left(profile, _candidate_in(cam, board, centre + np.array([sx, sy]) * p[:2] * half, d, tilt,
                                            math.radians(p[5])), camera)
        if not _fits(profile, board, T, max_view_deg=CORNER_MAX_VIEW_DEG):
            continue
        share, worst, ratio = _region_score(profile, board, T, sx, sy)
        if ratio < CORNER_MIN_SQUARE_RATIO:
            continue
        score = (-min(share, 0.5), d if share >= 0.5 else worst)
        if best is None or score < best[0]:
            best = (score, T, p)
    return None if best is None else best[1]


def _corner_views(views: int) -> dict[int, tuple[float, float]]:
    """View index -> image region ``(sx, sy)`` for a third of the views (none below 8 views, at most 12),
    spread evenly through the set: the four corners, then the left and right edge middles (the stereo
    overlap cuts those off: the left camera's left edge and the right camera's right edge)."""
    regions = [(-1.0, -1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, 0.0), (1.0, 0.0)]
    n = min(views // 3, 12) if views >= 8 else 0
    return {int((i + 0.5) * views / n): regions[i % 6] for i in range(n)} if n else {}


def _grid_pose(profile: StereoProfile, board: BoardGeometry, k: int, pos: FloatArray, d0: float, hi: float,
               tilt: FloatArray, roll: float) -> FloatArray:
    """View ``k`` aimed at ``pos`` (image half-sizes from the principal point), falling back along
    :func:`_schedule` until it fits both images."""
    cam = profile.left
    half, centre = np.array([cam.width_px / 2.0, cam.height_px / 2.0]), np.array([cam.cx_px, cam.cy_px])
    for shrink, d, relax in _schedule(d0, hi):
        T = _candidate(profile, board, centre + shrink * pos * half, d, tilt * relax, roll * relax)
        if _fits(profile, board, T):
            return T
    raise RenderError(
        f"view {k}: the board does not fit inside both images at any sampled pose",
        field="pattern", hint="use a smaller board (--pattern / --square) or check the profile's extrinsics",
    )


def sample_board_poses(profile: StereoProfile, board: BoardGeometry, *, views: int, seed: int) -> list[FloatArray]:
    """``views`` poses ``T_left_board`` (4x4, metres), deterministic for ``seed``.

    Corner views (two per image corner per 10 views, see :func:`_corner_views`) put inner corners into the
    corner cells of both images (:func:`_corner_pose`). Every other view aims the board centre at one of 9
    image positions (corners, edge midpoints, centre; shuffled by the seed, with jitter), at a
    log-stratified distance, tilted by a stratified angle of 30-45 deg about a random in-plane axis and
    rolled 8-30 deg either way; a candidate that does not fit both images is moved back and pulled toward
    the image centre, then un-tilted, until it fits (see :func:`_schedule`).
    """
    lo, hi = distance_range_m(profile, board)
    rng = np.random.default_rng(seed)
    corner_rng = np.random.default_rng([seed, 1])
    corner_views = _corner_views(views)
    grid = np.array([(x, y) for y in (-1.0, 0.0, 1.0) for x in (-1.0, 0.0, 1.0)])
    order = rng.permutation(len(grid))
    poses: list[FloatArray] = []
    for k in range(views):
        pos = grid[order[k % len(grid)]] + rng.uniform(-0.1, 0.1, 2)
        frac = (k * 0.6180339887 + rng.uniform(0.0, 0.15)) % 1.0
        band = k % 3
        angle = math.radians(MIN_TILT_DEG + rng.uniform(band, band + 1) * (MAX_TILT_DEG - MIN_TILT_DEG) / 3.0)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        tilt = angle * np.array([math.cos(phi), math.sin(phi), 0.0])
        roll = math.radians(rng.uniform(MIN_ROLL_DEG, MAX_ROLL_DEG) * rng.choice([-1.0, 1.0]))
        T = None
        if k in corner_views:
            T = _corner_pose(profile, board, corner_rng, *corner_views[k], lo, hi)
        poses.append(T if T is not None else _grid_pose(profile, board, k, pos, lo * (hi / lo) ** frac, hi, tilt,
                                                         roll))
    return poses
