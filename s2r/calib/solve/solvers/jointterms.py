"""The residuals and Jacobians of the joint stereo solve (:mod:`s2r.calib.solve.solvers.joint`), over every corner of
every view at once: the solve's mutable parameters (:class:`State`), the corners gathered per camera, and the
normal equations with each view's pose block kept apart for the Schur complement.

Frames and units: board points in the board frame (metres); a view's pose takes them to the LEFT camera's
optical frame, the pair's (``X_right = R X_left + T``) to the right one's; residuals are projected minus
observed pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.observations import StereoObservation
from s2r.lens.models import LensModel

__all__ = ["Blocks", "CornerSet", "JointInit", "Masks", "State", "all_residuals", "camera_terms", "gather",
           "global_columns", "normal_equations", "prepare", "residuals", "rotations"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class JointInit:
    """Starting point: K (3x3) and D (n_coef) per camera, R (3x3), T (3,) m, a board pose per view."""

    K1: FloatArray
    D1: FloatArray
    K2: FloatArray
    D2: FloatArray
    R: FloatArray
    T: FloatArray
    rvecs: Sequence[FloatArray]
    tvecs: Sequence[FloatArray]
    warp: FloatArray | None = None


class State:
    """Mutable parameters of the solve."""

    def __init__(self, lens: LensModel, init: JointInit, *, warp: bool = False,
                 views: Sequence[StereoObservation] = ()) -> None:
        self.lens = lens
        self.nw = 2 if warp else 0
        self.warp = np.zeros(2) if init.warp is None else np.asarray(init.warp, np.float64).reshape(2).copy()
        pts = [o.obj for v in views for o in (v.left, v.right) if o is not None and len(o.obj)]
        allp = np.concatenate(pts) if pts else np.zeros((1, 3))
        self.span = (float(allp[:, 0].min()), float(np.ptp(allp[:, 0])) or 1.0,
                     float(allp[:, 1].min()), float(np.ptp(allp[:, 1])) or 1.0)
        self.K = [np.asarray(init.K1, np.float64).copy(), np.asarray(init.K2, np.float64).copy()]
        self.D = [np.zeros(lens.n_coef), np.zeros(lens.n_coef)]
        for d, src in zip(self.D, (init.D1, init.D2), strict=True):
            src = np.asarray(src, np.float64).reshape(-1)[:lens.n_coef]
            d[list(lens.free)] = src[list(lens.free)]
        self.r_lr = np.asarray(cv2.Rodrigues(np.asarray(init.R, np.float64))[0], np.float64).reshape(3)
        self.t_lr = np.asarray(init.T, np.float64).reshape(3).copy()
        self.rv = [np.asarray(r, np.float64).reshape(3).copy() for r in init.rvecs]
        self.tv = [np.asarray(t, np.float64).reshape(3).copy() for t in init.tvecs]

    @property
    def n_intr(self) -> int:
        return 4 + len(self.lens.free)

    def global_vec(self) -> FloatArray:
        parts = []
        for K, D in zip(self.K, self.D, strict=True):
            parts += [[K[0, 0], K[1, 1], K[0, 2], K[1, 2]], D[list(self.lens.free)]]
        return np.concatenate([*map(np.asarray, parts), self.warp[:self.nw], self.r_lr, self.t_lr])

    def set_global(self, g: FloatArray) -> None:
        ni = self.n_intr
        for c in range(2):
            v = g[c * ni:(c + 1) * ni]
            self.K[c] = np.array([[v[0], 0, v[2]], [0, v[1], v[3]], [0, 0, 1.0]])
            self.D[c][list(self.lens.free)] = v[4:]
        self.warp[:self.nw] = g[2 * ni:2 * ni + self.nw]
        e0 = 2 * ni + self.nw
        self.r_lr, self.t_lr = g[e0:e0 + 3].copy(), g[e0 + 3:].copy()

    def warp_basis(self, obj: FloatArray) -> FloatArray:
        """(M, 2) board bend shapes at board points ``obj``: ``1 - u^2`` and ``1 - v^2`` with u, v in [-1, 1]
        across the board's corners (mrcal's parabolic board warp: the bend at the centre, metres)."""
        x0, wx, y0, wy = self.span
        u, v = 2 * (obj[:, 0] - x0) / wx - 1, 2 * (obj[:, 1] - y0) / wy - 1
        return np.column_stack([1 - u ** 2, 1 - v ** 2])

    def copy_views(self) -> tuple[list[FloatArray], list[FloatArray]]:
        return [r.copy() for r in self.rv], [t.copy() for t in self.tv]


Masks = list[list[NDArray[np.bool_] | None]]
#: Per active view (in ``active`` order): A_gv (n, ng, 6), A_vv (n, 6, 6), b_v (n, 6).
Blocks = tuple[FloatArray, FloatArray, FloatArray]


@dataclass(frozen=True)
class CornerSet:
    """One camera's (inlier) corners of the active views, concatenated view by view: board points (M, 3) m,
    pixels (M, 2), each corner's view (position in ``active``) and its place within that view, the most corners
    of a view, and the board points per view padded with zeros to that many (n active views, width, 3)."""

    obj: FloatArray
    img: FloatArray
    seg: NDArray[np.intp]
    pos: NDArray[np.intp]
    width: int
    board: FloatArray


def gather(views: Sequence[StereoObservation], masks: Masks | None, active: Sequence[int], cam: int
            ) -> CornerSet | None:
    """The corners of one camera (all of them when ``masks`` is None), or None when it saw none."""
    objs, imgs, js, counts = [], [], [], []
    for j, k in enumerate(active):
        obs = views[k].left if cam == 0 else views[k].right
        if obs is None or not len(obs.ids):
            continue
        mask = None if masks is None else masks[k][cam]
        if masks is not None and (mask is None or not mask.any()):
            continue
        if mask is None or mask.all():
            objs.append(obs.obj)
            imgs.append(obs.img)
        else:
            objs.append(obs.obj[mask])
            imgs.append(obs.img[mask])
        js.append(j)
        counts.append(len(objs[-1]))
    if not objs:
        return None
    segs = np.repeat(np.asarray(js, np.intp), counts)
    starts = np.cumsum(counts) - counts
    pos = np.arange(len(segs)) - np.repeat(starts, counts)
    obj = np.concatenate(objs).astype(np.float64)
    width = max(counts)
    board = np.zeros((len(active), width, 3))
    board[segs, pos] = obj
    return CornerSet(obj, np.concatenate(imgs).astype(np.float64), segs, pos, width, board)


def prepare(views: Sequence[StereoObservation], masks: Masks | None, active: Sequence[int]
             ) -> tuple[CornerSet | None, CornerSet | None]:
    return gather(views, masks, active, 0), gather(views, masks, active, 1)


def rotations(rvecs: Sequence[FloatArray]) -> tuple[FloatArray, FloatArray]:
    """Rotation matrices (n, 3, 3) and their derivatives (n, 3, 3, 3): ``dR[i, j]`` = dR_i / d r_j."""
    Rs, dRs = [], []
    for r in rvecs:
        R, jac = cv2.Rodrigues(np.asarray(r, np.float64).reshape(3, 1))
        Rs.append(R)
        dRs.append(np.asarray(jac, np.float64).reshape(3, 3, 3))
    return np.asarray(Rs, np.float64).reshape(-1, 3, 3), np.asarray(dRs, np.float64).reshape(-1, 3, 3, 3)


def global_columns(state: State, cam: int) -> NDArray[np.intp]:
    """The columns of the global parameters (see ``State.global_vec``) one camera's corners depend on: its own
    intrinsics, the board bend, and for the right camera the pair's rotation and translation."""
    ni, nw = state.n_intr, state.nw
    e0 = 2 * ni + nw
    cols = [*range(cam * ni, (cam + 1) * ni), *range(2 * ni, e0), *(range(e0, e0 + 6) if cam == 1 else ())]
    return np.asarray(cols, np.intp)


def camera_terms(state: State, cam: int, c: CornerSet, poses: tuple[FloatArray, FloatArray, FloatArray], *,
                 with_global: bool = True) -> tuple[FloatArray, FloatArray | None, FloatArray]:
    """Residuals (M, 2) px, global Jacobian (M, 2, k) over :func:`global_columns` only (the others are zero;
    None without ``with_global``: pose-only fits) and view Jacobian (M, 2, 6) of one camera's corners.

    Board points go to the camera frame here (the view's pose, then the pair's for the right camera) and are
    projected in one call with a zero pose, whose translation Jacobian is d pixel / d point. ``poses``: the
    active views' rotations (n, 3, 3), their derivatives (n, 3, 3, 3) and translations (n, 3)."""
    ni, nw = state.n_intr, state.nw
    m = len(c.obj)
    R, dR, t = poses
    n = len(R)
    board = _bent_board(state, c, n)
    # Per view, the rows taking a board point to this camera's frame (3), the derivatives of that by the view's
    # rotation vector (9, row a * 3 + j = d X_a / d r_j) and, for the right camera, to the left camera's frame
    # (3). One batched product over the views' zero-padded points, then read back per corner: 10x faster than
    # gathering (M, 3, 3) and (M, 3, 3, 3) arrays per corner. The pair's rotation is folded into the rows.
    dR_a = dR.transpose(0, 2, 1, 3).reshape(n, 3, 9)  # [view, a, (j, k)]
    if cam == 1:
        R_lr, dR_lr = rotations([state.r_lr])
        Rp = R_lr[0]
        R_cam, t_cam = Rp @ R, t @ Rp.T + state.t_lr
        dR_a = Rp @ dR_a
    else:
        R_cam, t_cam = R, t
    rows = np.concatenate([R_cam, dR_a.reshape(n, 9, 3), *([R] if cam == 1 else [])], axis=1)  # (n, 12|15, 3)
    Y = (board @ rows.transpose(0, 2, 1))[c.seg, c.pos]  # (M, 12|15)
    X = Y[:, :3] + t_cam[c.seg]
    pts, jac = state.lens.projection.project(X, np.zeros(3), np.zeros(3), state.K[cam], state.D[cam])
    jac = jac.reshape(m, 2, -1)
    dp_dX = np.ascontiguousarray(jac[:, :, 3:6])  # (M, 2, 3): d pixel / d point in this camera's frame
    dp_dt = dp_dX if cam == 0 else (dp_dX.reshape(-1, 3) @ Rp).reshape(m, 2, 3)
    Jv = np.empty((m, 2, 6))
    Jv[:, :, :3] = dp_dX @ Y[:, 3:12].reshape(m, 3, 3)
    Jv[:, :, 3:] = dp_dt
    if not with_global:
        return pts.reshape(m, 2) - c.img, None, Jv
    Jg = np.empty((m, 2, ni + nw + (6 if cam == 1 else 0)))  # the columns of global_columns(state, cam)
    Jg[:, :, :ni] = jac[:, :, state.lens.jacobian_columns]
    if nw:
        dX_dw = R_cam[c.seg, :, 2][:, :, None] * state.warp_basis(c.obj)[:, None, :]  # (M, 3, 2)
        Jg[:, :, ni:ni + nw] = dp_dX @ dX_dw
    if cam == 1:
        X_left = Y[:, 12:15] + t[c.seg]
        dX_drlr = (X_left @ dR_lr[0].transpose(1, 0, 2).reshape(9, 3).T).reshape(m, 3, 3)  # [a, j]
        Jg[:, :, ni + nw:ni + nw + 3] = dp_dX @ dX_drlr
        Jg[:, :, ni + nw + 3:] = dp_dX
    return pts.reshape(m, 2) - c.img, Jg, Jv


def _bent_board(state: State, c: CornerSet, n: int) -> FloatArray:
    """``c``'s board points per view, zero-padded (n, width, 3) m, with the board's bend when it is solved."""
    if not state.nw:
        return c.board
    board = np.zeros((n, c.width, 3))
    board[c.seg, c.pos] = c.obj
    board[c.seg, c.pos, 2] += state.warp_basis(c.obj) @ state.warp
    return board


def residuals(state: State, cam: int, c: CornerSet, poses: tuple[FloatArray, FloatArray, FloatArray]
              ) -> FloatArray:
    """Residuals (M, 2) px of one camera's corners, as :func:`camera_terms` gives them, without Jacobians."""
    R, _, t = poses
    if cam == 1:
        Rp = rotations([state.r_lr])[0][0]
        R, t = Rp @ R, t @ Rp.T + state.t_lr
    X = (_bent_board(state, c, len(R)) @ R.transpose(0, 2, 1))[c.seg, c.pos] + t[c.seg]
    pts, _ = state.lens.projection.project(X, np.zeros(3), np.zeros(3), state.K[cam], state.D[cam])
    return pts.reshape(-1, 2) - c.img


def padded(values: FloatArray, c: CornerSet, n: int) -> FloatArray:
    """(M, 2, k) per-corner rows into (n views, 2 * width, k), zero where a view has fewer corners."""
    out = np.zeros((n, c.width, *values.shape[1:]))
    out[c.seg, c.pos] = values
    return out.reshape(n, 2 * c.width, -1)


def normal_equations(state: State, views: Sequence[StereoObservation], masks: Masks, active: list[int],
                     data: tuple[CornerSet | None, CornerSet | None] | None = None, *, poses_only: bool = False
                     ) -> tuple[float, int, FloatArray, FloatArray, Blocks]:
    """SSR, residual count, A_gg, b_g and per active view (A_gv, A_vv, b_v); ``data``: the gathered corners
    (:func:`prepare`) when the caller already has them; ``poses_only``: only the view blocks A_vv, b_v (the
    global ones are zeros: for fitting board poses with everything else fixed)."""
    ng = 2 * state.n_intr + state.nw + 6
    n = len(active)
    A, b = np.zeros((ng, ng)), np.zeros(ng)
    Agv, Avv, bv = np.zeros((n, ng, 6)), np.zeros((n, 6, 6)), np.zeros((n, 6))
    ssr, count = 0.0, 0
    R, dR = rotations([state.rv[k] for k in active])
    poses = (R, dR, np.asarray([state.tv[k] for k in active], np.float64).reshape(-1, 3))
    for cam, c in enumerate(data if data is not None else prepare(views, masks, active)):
        if c is None:
            continue
        r, Jg, Jv = camera_terms(state, cam, c, poses, with_global=not poses_only)
        ssr += float(np.sum(r * r))
        count += r.size
        Pv, Pr = padded(Jv, c, n), padded(r[:, :, None], c, n)
        PvT = Pv.transpose(0, 2, 1)
        Avv += PvT @ Pv
        bv += (PvT @ Pr)[:, :, 0]
        if Jg is not None:
            cols = global_columns(state, cam)
            Jg2 = Jg.reshape(-1, len(cols))
            A[np.ix_(cols, cols)] += Jg2.T @ Jg2
            b[cols] += Jg2.T @ r.reshape(-1)
            Agv[:, cols] += padded(Jg, c, n).transpose(0, 2, 1) @ Pv
    return ssr, count, A, b, (Agv, Avv, bv)


def all_residuals(state: State, views: Sequence[StereoObservation], ks: Sequence[int]
                   ) -> dict[int, tuple[FloatArray | None, FloatArray | None]]:
    """Residuals (N, 2) px of ALL corners of views ``ks`` per camera (None where a camera saw nothing)."""
    out: dict[int, list[FloatArray | None]] = {k: [None, None] for k in ks}
    R, dR = rotations([state.rv[k] for k in ks])
    poses = (R, dR, np.asarray([state.tv[k] for k in ks], np.float64).reshape(-1, 3))
    for cam, c in enumerate(prepare(views, None, ks)):
        if c is None:
            continue
        r = residuals(state, cam, c, poses)
        starts = np.flatnonzero(np.r_[True, c.seg[1:] != c.seg[:-1]])
        for j, part in zip(c.seg[starts], np.split(r, starts[1:]), strict=True):
            out[ks[int(j)]][cam] = part
    return {k: (v[0], v[1]) for k, v in out.items()}
