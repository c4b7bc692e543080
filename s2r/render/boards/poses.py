"""Calibration-board poses that cover the image, tilt up to ~45 deg and keep the board inside both images.

The board frame (OpenCV's calibration object frame): origin at the first inner corner, x along the
pattern's columns, y along its rows, z into the board (away from a camera that sees its printed face).
Inner corner (i, j) sits at ``(i * square_m, j * square_m, 0)``. Poses are ``T_left_board`` (4x4, metres).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.errors import RenderError
from s2r.lens.distortion import project_points
from s2r.profile import Camera, StereoProfile
from s2r.render.boards.geometry import BoardGeometry
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
#: Candidates scored together: refinement steps (those after a new best are redrawn around it) and grid-view
#: fallbacks (the first that fits wins).
_REFINE_BATCH = 12
_CELL_SAFETY_PX = 4.0
_EDGE_MARGIN_PX = 3.0
_SHRINK_STEPS, _RELAX_STEPS = 21, 30


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
    return bool(_fits_many(profile, board, np.asarray(T, np.float64)[None], max_view_deg=max_view_deg)[0])


def _in_cameras(profile: StereoProfile, T: FloatArray) -> Iterator[tuple[Camera, FloatArray, FloatArray]]:
    """Per camera (left, right): the camera, and the rotations (n, 3, 3) and translations (n, 3) m of the
    poses ``T`` (n, 4, 4) ``T_left_board`` as board -> that camera's optical frame."""
    for cam, R, t in ((profile.left, np.eye(3), np.zeros(3)), (profile.right, profile.R, profile.T.reshape(3))):
        yield cam, R @ T[:, :3, :3], T[:, :3, 3] @ R.T + t


def _project_many(cam: Camera, points: FloatArray, R: FloatArray, t: FloatArray) -> FloatArray:
    """(n, P, 2) pixels of board points (P, 3) under n poses (R (n, 3, 3), t (n, 3)) in ``cam``."""
    if len(R) == 0:
        return np.zeros((0, len(points), 2))
    pts = np.einsum("pk,njk->npj", points, R) + t[:, None, :]
    return project_points(cam, pts.reshape(-1, 3)).reshape(len(R), len(points), 2)


def _fits_many(profile: StereoProfile, board: BoardGeometry, T: FloatArray, *,
               max_view_deg: float = MAX_VIEW_ANGLE_DEG) -> NDArray[np.bool_]:
    """:func:`_fits` of each of the poses ``T`` (n, 4, 4), in one pass (n,); each check projects only the poses
    that passed the cheaper ones (``cv2.projectPoints`` also computes its Jacobian: the costly part)."""
    near, far = clip_planes(profile)
    outline, corners = board.outline(), board.corners()
    ok = np.ones(len(T), bool)
    cameras = list(_in_cameras(profile, T))
    for _, R, t in cameras:
        z = np.einsum("pk,nk->np", outline, R[:, 2, :]) + t[:, 2:3]
        ok &= ~(np.any(z < 1.2 * near, axis=1) | np.any(z > 0.9 * far, axis=1))
        centre = R @ board.centre() + t
        cos_view = np.einsum("nk,nk->n", R[:, :, 2], centre) / np.linalg.norm(centre, axis=1)
        ok &= cos_view >= math.cos(math.radians(max_view_deg))
    m = _EDGE_MARGIN_PX
    for cam, R, t in cameras:
        idx = np.flatnonzero(ok)
        uv = _project_many(cam, outline, R[idx], t[idx])
        ok[idx] = ~(np.any(uv < m, axis=(1, 2)) | np.any(uv[:, :, 0] > cam.width_px - 1 - m, axis=1)
                    | np.any(uv[:, :, 1] > cam.height_px - 1 - m, axis=1))
    for cam, R, t in cameras:
        idx = np.flatnonzero(ok)
        grid = _project_many(cam, corners, R[idx], t[idx]).reshape(len(idx), board.pattern[1], board.pattern[0], 2)
        step = np.minimum(np.linalg.norm(np.diff(grid, axis=1), axis=3).min(axis=(1, 2), initial=np.inf),
                          np.linalg.norm(np.diff(grid, axis=2), axis=3).min(axis=(1, 2), initial=np.inf))
        ok[idx] = step >= MIN_SQUARE_PX
    return ok


def _candidates_in(cam: Camera, board: BoardGeometry, target: FloatArray, d: FloatArray, tilt: FloatArray,
                   roll: FloatArray) -> FloatArray:
    """``T_cam_board`` (n, 4, 4) of n candidates: the board centre ``d`` (n,) metres along pixel ``target``'s
    (n, 2) pinhole ray, tilted by rotation vectors ``tilt`` (n, 3) (camera frame, radians) after an in-plane
    ``roll`` (n,) (radians)."""
    ray = np.column_stack([(target[:, 0] - cam.cx_px) / cam.fx_px, (target[:, 1] - cam.cy_px) / cam.fy_px,
                           np.ones(len(target))])
    R = Rotation.from_rotvec(tilt).as_matrix() @ Rotation.from_euler("z", roll[:, None]).as_matrix()
    T = np.tile(np.eye(4), (len(target), 1, 1))
    T[:, :3, :3] = R
    T[:, :3, 3] = d[:, None] * ray - R @ board.centre()
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
    """``T_left_board`` from poses (4, 4) or (n, 4, 4) in ``camera``'s optical frame (left: unchanged; right:
    X_r = R X_l + T)."""
    if camera == "left":
        return T_cam
    T = np.array(T_cam, np.float64)
    T[..., :3, :3] = profile.R.T @ T_cam[..., :3, :3]
    T[..., :3, 3] = (T_cam[..., :3, 3] - profile.T.reshape(3)) @ profile.R
    return T


def _region_cells(n: int, side: float) -> range:
    """Grid indices (of ``n``) of the coverage check's third of the image at ``side`` (-1, 0, +1)."""
    part = int(side) + 1
    return range(part * n // 3, (part + 1) * n // 3)


def _region_scores(profile: StereoProfile, board: BoardGeometry, T: FloatArray, sx: float, sy: float
                   ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Scores (each (n,)) of fitting poses ``T`` (n, 4, 4) for image region ``(sx, sy)`` (each -1, 0 or +1; a
    corner or an edge middle): the smaller share, over both cameras, of that region's coverage cells reached by
    inner corners, the larger distance (in cells) from the region's outer point to the nearest inner corner,
    and the smallest ratio of shortest to longest imaged square side (perspective foreshortening)."""
    n = len(T)
    share, worst, ratio = np.ones(n), np.zeros(n), np.ones(n)
    if n == 0:
        return share, worst, ratio
    gx, gy = COVERAGE_GRID
    cols, rows = _region_cells(gx, sx), _region_cells(gy, sy)
    for cam, R, t in _in_cameras(profile, T):
        uv = _project_many(cam, board.corners(), R, t)
        inward = uv - _CELL_SAFETY_PX * np.array([sx, sy])  # count a cell only with a corner well inside it
        cell = np.floor((inward + 0.5) * np.array([gx / cam.width_px, gy / cam.height_px])).astype(int)
        inside = ((cell[..., 0] >= cols.start) & (cell[..., 0] < cols.stop) & (cell[..., 1] >= rows.start)
                  & (cell[..., 1] < rows.stop))
        code = np.sort(np.where(inside, cell[..., 0] * gy + cell[..., 1], -1), axis=1)
        first = np.concatenate([np.ones((n, 1), bool), code[:, 1:] != code[:, :-1]], axis=1)
        hit = np.count_nonzero(first & (code >= 0), axis=1)  # distinct cells reached
        share = np.minimum(share, hit / (len(cols) * len(rows)))
        anchor = np.array([(sx + 1) / 2 * cam.width_px, (sy + 1) / 2 * cam.height_px])
        off = np.abs(uv - anchor) * np.array([gx / cam.width_px, gy / cam.height_px])
        worst = np.maximum(worst, np.min(np.max(off, axis=2), axis=1))
        grid = uv.reshape(n, board.pattern[1], board.pattern[0], 2)
        sides = np.concatenate([np.linalg.norm(np.diff(grid, axis=a), axis=3).reshape(n, -1) for a in (1, 2)], axis=1)
        ratio = np.minimum(ratio, sides.min(axis=1) / sides.max(axis=1))
    return share, worst, ratio


_CORNER_LO = np.array([0.25, 0.25, 0.0, -0.4, CORNER_TILT_DEG[0], MIN_ROLL_DEG])
_CORNER_HI = np.array([0.85, 0.85, 1.0, 0.4, CORNER_TILT_DEG[1], MAX_ROLL_DEG])


def _corner_params(rng: np.random.Generator, around: FloatArray | None) -> FloatArray:
    """Corner-view parameters ``(ax, ay, u, dphi, tilt_deg, roll_deg)``: aim as a share of the image
    half-size, log-distance fraction ``u``, tilt-axis offset (radians) and signed roll; drawn uniformly, or
    near ``around`` (a local refinement step), always within the sampling bounds."""
    if around is None:
        p: FloatArray = rng.uniform(_CORNER_LO, _CORNER_HI)
        p[5] *= rng.choice([-1.0, 1.0])
        return p
    return _around(around, _corner_step(rng))


def _corner_step(rng: np.random.Generator) -> FloatArray:
    """One refinement step of the corner-view parameters (the random part of :func:`_corner_params`)."""
    return np.asarray(rng.normal(0.0, 0.08, 6) * (_CORNER_HI - _CORNER_LO), np.float64)


def _around(around: FloatArray, step: FloatArray) -> FloatArray:
    """Parameters ``around`` moved by ``step``, within the sampling bounds, the roll's sign kept."""
    sign = 1.0 if around[5] >= 0 else -1.0
    p = np.clip(np.concatenate([around[:5], [abs(around[5])]]) + step, _CORNER_LO, _CORNER_HI)
    p[5] *= sign
    return p


#: A corner-view candidate: its score (smaller is better), ``T_left_board`` and parameters.
_Scored = tuple[tuple[float, float], FloatArray, FloatArray]


def _corner_pose(profile: StereoProfile, board: BoardGeometry, rng: np.random.Generator, sx: float, sy: float,
                 lo: float, hi: float) -> FloatArray | None:
    """The best fitting candidate with inner corners in image region ``(sx, sy)`` (see :func:`_region_scores`).

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
    best: _Scored | None = None

    def scored(params: FloatArray) -> Iterator[tuple[int, _Scored]]:
        """The candidates ``params`` (n, 6) that fit and keep their squares, in order: (index, scored)."""
        d = lo * (far / lo) ** params[:, 2]
        phi = math.atan2(-sx, sy) + params[:, 3]  # far edge toward (sx, sy)
        tilt = np.radians(params[:, 4])[:, None] * np.column_stack([np.cos(phi), np.sin(phi), np.zeros(len(phi))])
        T = _to_left(profile, _candidates_in(cam, board, centre + np.array([sx, sy]) * params[:, :2] * half, d,
                                             tilt, np.radians(params[:, 5])), camera)
        fit = np.flatnonzero(_fits_many(profile, board, T, max_view_deg=CORNER_MAX_VIEW_DEG))
        share, worst, ratio = _region_scores(profile, board, T[fit], sx, sy)
        for i, s_, w, r in zip(fit, share, worst, ratio, strict=True):
            if r >= CORNER_MIN_SQUARE_RATIO:
                yield int(i), ((-min(float(s_), 0.5), float(d[i]) if s_ >= 0.5 else float(w)), T[i], params[i])

    # The candidates and random numbers of a one-by-one search (draw, score, keep the best), scored in batches:
    # the first half at random, then refinement steps around the best so far, re-batched when it changes.
    for _, candidate in scored(np.array([_corner_params(rng, None) for _ in range(_CORNER_TRIES // 2)])):
        if best is None or candidate[0] < best[0]:
            best = candidate
    left = _CORNER_TRIES - _CORNER_TRIES // 2
    while best is None and left:  # nothing fits yet: keep drawing at random, one by one
        found = next(scored(np.array([_corner_params(rng, None)])), None)
        best, left = (None if found is None else found[1]), left - 1
    steps = [_corner_step(rng) for _ in range(left)]
    while best is not None and steps:  # a few at a time: the rest of a batch is redrawn when the best changes
        params = np.array([_around(best[2], step) for step in steps[:_REFINE_BATCH]])
        found = next(((k, c) for k, c in scored(params) if c[0] < best[0]), None)
        best, steps = (best, steps[len(params):]) if found is None else (found[1], steps[found[0] + 1:])
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
    schedule = np.array(list(_schedule(d0, hi)))
    for chunk in np.array_split(schedule, range(_REFINE_BATCH, len(schedule), _REFINE_BATCH)):
        shrink, d, relax = chunk.T
        T = _candidates_in(cam, board, centre + shrink[:, None] * pos * half, d, tilt * relax[:, None], roll * relax)
        fits = np.flatnonzero(_fits_many(profile, board, T))
        if len(fits):  # the first that fits, in the order of the schedule
            return np.asarray(T[fits[0]], np.float64)
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
