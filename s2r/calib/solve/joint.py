"""One joint stereo solve: both cameras' intrinsics and distortion, the extrinsics and every board pose.

Parameters: global ``[fx fy cx cy d_free]`` of the left camera, the same of the right camera, the
rotation vector and translation of the pair (``X_right = R X_left + T``, metres), and one board pose per
view (board frame in the LEFT camera's optical frame: rotation vector, translation in metres).
Residuals: projected minus observed pixels of every inlier corner in each camera that saw it.

Levenberg-Marquardt on the normal equations with the board poses eliminated by Schur complements (as
bundle adjusters do), Jacobians from the lens model's projection (``cv2.projectPoints`` for pinhole)
chained through ``cv2.composeRT`` for the right camera. Outliers are rejected inside the loop: after each
convergence, corners whose residual exceeds ``corner_k`` robust sigmas (at least ``corner_floor_px``) and
views whose per-camera RMS exceeds a robust threshold are removed, and the solve continues.

Uncertainty: ``cov = s^2 (J^T J)^-1`` over the global parameters (board poses marginalised by the Schur
complement), ``s^2 = SSR / (m - p)`` with ``m`` residuals and ``p`` free parameters. Directions the data do
not constrain (relative eigenvalue below 1e-12 after column scaling) make the parameters they involve
``unobservable`` (std reported as inf) instead of a NaN.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.lens import LensModel
from s2r.calib.solve.observations import StereoObservation
from s2r.errors import CalibrationError

__all__ = ["JointInit", "JointSolution", "solve_joint"]

FloatArray = NDArray[np.float64]
_MIN_VIEWS = 5


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


@dataclass(frozen=True)
class JointSolution:
    """The solved rig with uncertainties.

    ``names`` of the global parameters (``left fx`` ... ``right k2`` ... ``rx ry rz tx ty tz``), ``cov`` their
    covariance (inf on the diagonal for ``unobservable`` ones), ``sigma_px`` the residual std of one
    coordinate, ``rms_px`` the RMS corner error (both coordinates), ``per_view_px`` (n_views, 2) RMS per
    camera (nan where a camera saw nothing), ``used`` which input views survived, ``inliers`` per view and
    camera the kept-corner masks, ``residuals`` per view and camera (N, 2) px of ALL corners,
    ``view_threshold_px`` the view outlier threshold (RMS over both cameras).
    """

    K1: FloatArray
    D1: FloatArray
    K2: FloatArray
    D2: FloatArray
    R: FloatArray
    T: FloatArray
    rvecs: tuple[FloatArray, ...]
    tvecs: tuple[FloatArray, ...]
    names: tuple[str, ...]
    cov: FloatArray
    unobservable: tuple[str, ...]
    sigma_px: float
    rms_px: float
    per_view_px: FloatArray
    used: tuple[bool, ...]
    inliers: tuple[tuple[NDArray[np.bool_] | None, NDArray[np.bool_] | None], ...]
    residuals: tuple[tuple[FloatArray | None, FloatArray | None], ...]
    corners_dropped: int
    view_threshold_px: float
    warp: FloatArray = field(default_factory=lambda: np.zeros(2))

    def std(self, name: str) -> float:
        """Standard deviation of a global parameter (inf when unobservable)."""
        return float(np.sqrt(self.cov[self.names.index(name), self.names.index(name)]))

    def translation_cov(self) -> FloatArray:
        """Covariance (3x3, m^2) of T."""
        return np.asarray(self.cov[-3:, -3:], np.float64)

    def rotation_cov(self) -> FloatArray:
        """Covariance (3x3, rad^2) of the pair's rotation vector."""
        return np.asarray(self.cov[-6:-3, -6:-3], np.float64)


class _State:
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


_Masks = list[list[NDArray[np.bool_] | None]]
#: Per active view (in ``active`` order): A_gv (n, ng, 6), A_vv (n, 6, 6), b_v (n, 6).
_Blocks = tuple[FloatArray, FloatArray, FloatArray]


@dataclass(frozen=True)
class _Corners:
    """One camera's (inlier) corners of the active views, concatenated view by view: board points (M, 3) m,
    pixels (M, 2), each corner's view (position in ``active``) and its place within that view."""

    obj: FloatArray
    img: FloatArray
    seg: NDArray[np.intp]
    pos: NDArray[np.intp]
    width: int


def _gather(views: Sequence[StereoObservation], masks: _Masks | None, active: Sequence[int], cam: int
            ) -> _Corners | None:
    """The corners of one camera (all of them when ``masks`` is None), or None when it saw none."""
    objs, imgs, seg = [], [], []
    for j, k in enumerate(active):
        obs = views[k].left if cam == 0 else views[k].right
        mask = None if obs is None else (np.ones(len(obs.ids), bool) if masks is None else masks[k][cam])
        if obs is None or mask is None or not mask.any():
            continue
        objs.append(obs.obj[mask])
        imgs.append(obs.img[mask])
        seg.append(np.full(int(mask.sum()), j, np.intp))
    if not objs:
        return None
    segs = np.concatenate(seg)
    starts = np.flatnonzero(np.r_[True, segs[1:] != segs[:-1]])
    counts = np.diff(np.r_[starts, len(segs)])
    pos = np.arange(len(segs)) - np.repeat(starts, counts)
    return _Corners(np.concatenate(objs).astype(np.float64), np.concatenate(imgs).astype(np.float64), segs, pos,
                    int(counts.max()))


def _prepare(views: Sequence[StereoObservation], masks: _Masks | None, active: Sequence[int]
             ) -> tuple[_Corners | None, _Corners | None]:
    return _gather(views, masks, active, 0), _gather(views, masks, active, 1)


def _rotations(rvecs: Sequence[FloatArray]) -> tuple[FloatArray, FloatArray]:
    """Rotation matrices (n, 3, 3) and their derivatives (n, 3, 3, 3): ``dR[i, j]`` = dR_i / d r_j."""
    Rs, dRs = [], []
    for r in rvecs:
        R, jac = cv2.Rodrigues(np.asarray(r, np.float64).reshape(3, 1))
        Rs.append(R)
        dRs.append(np.asarray(jac, np.float64).reshape(3, 3, 3))
    return np.asarray(Rs, np.float64).reshape(-1, 3, 3), np.asarray(dRs, np.float64).reshape(-1, 3, 3, 3)


def _camera_terms(state: _State, cam: int, c: _Corners, poses: tuple[FloatArray, FloatArray, FloatArray]
                  ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Residuals (M, 2) px, global Jacobian (M, 2, ng) and view Jacobian (M, 2, 6) of one camera's corners.

    Board points go to the camera frame here (the view's pose, then the pair's for the right camera) and are
    projected in one call with a zero pose, whose translation Jacobian is d pixel / d point. ``poses``: the
    active views' rotations (n, 3, 3), their derivatives (n, 3, 3, 3) and translations (n, 3)."""
    ni, nw = state.n_intr, state.nw
    e0 = 2 * ni + nw
    ng = e0 + 6
    m = len(c.obj)
    R, dR, t = poses
    obj = c.obj
    if nw:
        basis = state.warp_basis(obj)
        obj = obj.copy()
        obj[:, 2] += basis @ state.warp
        dX_dw = R[c.seg][:, :, 2:3] * basis[:, None, :]  # (M, 3, 2)
    X = (R[c.seg] @ obj[:, :, None])[:, :, 0] + t[c.seg]
    dX_dr = (dR[c.seg].reshape(m, 9, 3) @ obj[:, :, None]).reshape(m, 3, 3).transpose(0, 2, 1)
    Jg = np.zeros((m, 2, ng))
    if cam == 1:
        R_lr, dR_lr = _rotations([state.r_lr])
        dX_drlr = (X @ dR_lr[0].reshape(9, 3).T).reshape(m, 3, 3).transpose(0, 2, 1)
        X = X @ R_lr[0].T + state.t_lr
        dX_dr = R_lr[0] @ dX_dr
        if nw:
            dX_dw = R_lr[0] @ dX_dw
    pts, jac = state.lens.projection.project(X, np.zeros(3), np.zeros(3), state.K[cam], state.D[cam])
    jac = jac.reshape(m, 2, -1)
    dp_dX = jac[:, :, 3:6]
    cols = [6, 7, 8, 9, *(10 + i for i in state.lens.free)]
    Jg[:, :, cam * ni:(cam + 1) * ni] = jac[:, :, cols]
    if nw:
        Jg[:, :, 2 * ni:e0] = dp_dX @ dX_dw
    if cam == 1:
        Jg[:, :, e0:e0 + 3] = dp_dX @ dX_drlr
        Jg[:, :, e0 + 3:] = dp_dX
        dp_dt = dp_dX @ R_lr[0]
    else:
        dp_dt = dp_dX
    Jv = np.concatenate([dp_dX @ dX_dr, dp_dt], axis=2)
    return pts.reshape(m, 2) - c.img, Jg, Jv


def _padded(values: FloatArray, c: _Corners, n: int) -> FloatArray:
    """(M, 2, k) per-corner rows into (n views, 2 * width, k), zero where a view has fewer corners."""
    out = np.zeros((n, c.width, *values.shape[1:]))
    out[c.seg, c.pos] = values
    return out.reshape(n, 2 * c.width, -1)


def _normal_equations(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int],
                      data: tuple[_Corners | None, _Corners | None] | None = None
                      ) -> tuple[float, int, FloatArray, FloatArray, _Blocks]:
    """SSR, residual count, A_gg, b_g and per active view (A_gv, A_vv, b_v); ``data``: the gathered corners
    (:func:`_prepare`) when the caller already has them."""
    ng = 2 * state.n_intr + state.nw + 6
    n = len(active)
    A, b = np.zeros((ng, ng)), np.zeros(ng)
    Agv, Avv, bv = np.zeros((n, ng, 6)), np.zeros((n, 6, 6)), np.zeros((n, 6))
    ssr, count = 0.0, 0
    R, dR = _rotations([state.rv[k] for k in active])
    poses = (R, dR, np.asarray([state.tv[k] for k in active], np.float64).reshape(-1, 3))
    for cam, c in enumerate(data if data is not None else _prepare(views, masks, active)):
        if c is None:
            continue
        r, Jg, Jv = _camera_terms(state, cam, c, poses)
        ssr += float(np.sum(r * r))
        count += r.size
        Jg2 = Jg.reshape(-1, ng)
        A += Jg2.T @ Jg2
        b += Jg2.T @ r.reshape(-1)
        Pg, Pv, Pr = _padded(Jg, c, n), _padded(Jv, c, n), _padded(r[:, :, None], c, n)
        PvT = Pv.transpose(0, 2, 1)
        Agv += Pg.transpose(0, 2, 1) @ Pv
        Avv += PvT @ Pv
        bv += (PvT @ Pr)[:, :, 0]
    return ssr, count, A, b, (Agv, Avv, bv)


def _step(A: FloatArray, b: FloatArray, blocks: _Blocks, lam: float) -> tuple[FloatArray, FloatArray]:
    """Damped Gauss-Newton step (global (ng,), per view (n, 6)) with the view blocks eliminated."""
    Agv, Avv, bv = blocks
    S = A + lam * np.diag(np.diag(A))
    damp = lam * np.einsum("nii->ni", Avv)[:, :, None] * np.eye(6) + 1e-12 * np.eye(6)
    Vi = np.linalg.inv(Avv + damp)
    AV = np.einsum("nij,njk->nik", Agv, Vi)
    S -= np.einsum("nik,njk->ij", AV, Agv)
    rhs = -b + np.einsum("nij,nj->i", AV, bv)
    dg = np.asarray(np.linalg.lstsq(S, rhs, rcond=None)[0], np.float64)
    dv = np.einsum("nij,nj->ni", Vi, -bv - np.einsum("nij,i->nj", Agv, dg))
    return dg, dv


def _levenberg_marquardt(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int],
                         iterations: int = 50, rel_tol: float = 1e-10) -> None:
    lam = 1e-3
    data = _prepare(views, masks, active)
    ssr, _, A, b, blocks = _normal_equations(state, views, masks, active, data)
    for _ in range(iterations):
        g0, (rv0, tv0) = state.global_vec(), state.copy_views()
        dg, dv = _step(A, b, blocks, lam)
        state.set_global(g0 + dg)
        for k, d in zip(active, dv, strict=True):
            state.rv[k], state.tv[k] = rv0[k] + d[:3], tv0[k] + d[3:]
        new = _normal_equations(state, views, masks, active, data)
        if np.isfinite(new[0]) and new[0] <= ssr:
            converged = ssr - new[0] < rel_tol * max(ssr, 1e-12)
            ssr, _, A, b, blocks = new
            lam = max(lam / 10, 1e-9)
            if converged:
                return
        else:
            state.set_global(g0)
            state.rv, state.tv = rv0, tv0
            lam *= 10
            if lam > 1e8:
                return


def _all_residuals(state: _State, views: Sequence[StereoObservation], ks: Sequence[int]
                   ) -> dict[int, tuple[FloatArray | None, FloatArray | None]]:
    """Residuals (N, 2) px of ALL corners of views ``ks`` per camera (None where a camera saw nothing)."""
    out: dict[int, list[FloatArray | None]] = {k: [None, None] for k in ks}
    R, dR = _rotations([state.rv[k] for k in ks])
    poses = (R, dR, np.asarray([state.tv[k] for k in ks], np.float64).reshape(-1, 3))
    for cam, c in enumerate(_prepare(views, None, ks)):
        if c is None:
            continue
        r, _, _ = _camera_terms(state, cam, c, poses)
        for j in np.unique(c.seg):
            out[ks[int(j)]][cam] = r[c.seg == j]
    return {k: (v[0], v[1]) for k, v in out.items()}


def _robust_threshold(values: FloatArray, k_mad: float = 5.0, k_median: float = 2.0, floor: float = 0.3) -> float:
    med = float(np.median(values))
    return max(med + k_mad * 1.4826 * float(np.median(np.abs(values - med))), k_median * med, floor)


def _reject(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int], *,
            view_thr: float | None, corner_k: float, corner_floor_px: float,
            max_view_error_px: float | None) -> tuple[bool, float]:
    """Drop outlier corners and views (in place); returns (anything changed?, the view RMS threshold px).

    A view's RMS is over the inlier corners of both cameras; the threshold is ``max_view_error_px`` or a
    robust one (median + 5 MAD-sigmas, at least 2x the median and 0.3 px) fixed at the first round."""
    res = _all_residuals(state, views, active)
    comps = np.concatenate([np.abs(r[masks[k][c]]).reshape(-1) for k in active for c, r in enumerate(res[k])
                            if r is not None and masks[k][c] is not None])
    sigma = float(np.median(comps)) / 0.6745 if comps.size else 0.0  # median |x| = 0.6745 sigma
    corner_thr = max(corner_k * sigma, corner_floor_px)
    changed = False
    rms = {}
    for k in active:
        sq: list[FloatArray] = []
        for c, r in enumerate(res[k]):
            mask = masks[k][c]
            if r is None or mask is None:
                continue
            bad = np.linalg.norm(r, axis=1) > corner_thr
            if np.any(bad & mask) and np.sum(mask & ~bad) >= 4:
                masks[k][c] = mask & ~bad
                changed = True
            sq.append(np.sum(r[masks[k][c]] ** 2, axis=1))  # type: ignore[index]
        rms[k] = float(np.sqrt(np.mean(np.concatenate(sq)))) if sq else 0.0
    if view_thr is None:
        view_thr = float(max_view_error_px) if max_view_error_px is not None else \
            _robust_threshold(np.array(list(rms.values())))
    bad_views = [k for k in active if rms[k] > view_thr]
    if bad_views and len(active) - len(bad_views) >= _MIN_VIEWS:
        for k in bad_views:
            active.remove(k)
        changed = True
    return changed, view_thr


def _covariance(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int],
                names: list[str]) -> tuple[FloatArray, tuple[str, ...], float]:
    ssr, m, A, _, blocks = _normal_equations(state, views, masks, active)
    Agv, Avv, _ = blocks
    S = A - np.einsum("nij,njk,nlk->il", Agv, np.linalg.pinv(Avv), Agv)
    p = len(names) + 6 * len(active)
    sigma2 = ssr / max(1, m - p)
    scale = 1.0 / np.sqrt(np.maximum(np.diag(S), 1e-300))
    Sn = S * np.outer(scale, scale)
    w, V = np.linalg.eigh(Sn)
    null = w < 1e-12 * max(float(w.max()), 1e-300)
    cov = np.zeros_like(S)
    keep = ~null
    cov_n = (V[:, keep] / w[keep]) @ V[:, keep].T
    cov = sigma2 * cov_n * np.outer(scale, scale)
    bad = np.any(np.abs(V[:, null]) > 1e-3, axis=1) if null.any() else np.zeros(len(names), bool)
    bad |= ~np.isfinite(np.diag(cov))
    cov[bad, :] = np.nan
    cov[:, bad] = np.nan
    cov[bad, bad] = np.inf
    return cov, tuple(n for n, b in zip(names, bad, strict=True) if b), float(np.sqrt(sigma2))


def _names(lens: LensModel, warp: bool = False) -> list[str]:
    intr = ["fx", "fy", "cx", "cy", *(lens.coef_names[i] for i in lens.free)]
    return [f"{side} {n}" for side in ("left", "right") for n in intr] + (["warp x", "warp y"] if warp else []) \
        + ["rx", "ry", "rz", "tx", "ty", "tz"]


def solve_joint(views: Sequence[StereoObservation], lens: LensModel, init: JointInit, *, max_rounds: int = 6,
                corner_k: float = 5.0, corner_floor_px: float = 0.3,
                max_view_error_px: float | None = None, rel_tol: float = 1e-10,
                covariance: bool = True, warp: bool = False) -> JointSolution:
    """Refine everything together from ``init`` (see the module docstring); ``init.rvecs[k]`` / ``tvecs[k]``
    is view k's board pose in the left camera. Views may miss one camera or show different corners.
    ``rel_tol``: LM stops when the sum of squares falls by less than this share (resampling solves, started
    from the full solution, use a looser one); ``covariance`` False skips the covariance (NaN; they need
    none); ``warp`` also solves the board's bend (two parameters, metres, see ``_State.warp_basis``; the
    initial one from ``init.warp``).

    Raises:
        CalibrationError: fewer than 5 views, or the solve diverged (non-finite parameters).
    """
    if len(views) < _MIN_VIEWS:
        raise CalibrationError(f"only {len(views)} views for the joint solve, at least {_MIN_VIEWS} needed",
                               hint="record more views with the board visible in both cameras")
    state = _State(lens, init, warp=warp, views=views)
    masks: _Masks = [[None if o is None else np.ones(len(o.ids), bool) for o in (v.left, v.right)] for v in views]
    active = list(range(len(views)))
    view_thr: float | None = None
    for _ in range(max_rounds):
        _levenberg_marquardt(state, views, masks, active, rel_tol=rel_tol)
        changed, view_thr = _reject(state, views, masks, active, view_thr=view_thr, corner_k=corner_k,
                                    corner_floor_px=corner_floor_px, max_view_error_px=max_view_error_px)
        if not changed:
            break
    else:
        _levenberg_marquardt(state, views, masks, active, rel_tol=rel_tol)
    if not np.all(np.isfinite(state.global_vec())):
        raise CalibrationError("the joint calibration solve diverged (non-finite parameters)",
                               hint="check the views: the board must be fully visible and sharp in both cameras")
    names = _names(lens, warp)
    if covariance:
        cov, unobservable, sigma = _covariance(state, views, masks, active, names)
    else:
        cov, unobservable, sigma = np.full((len(names), len(names)), np.nan), (), float("nan")
    per_view = np.full((len(views), 2), np.nan)
    residuals = []
    sq, n = 0.0, 0
    dropped = 0
    every = _all_residuals(state, views, list(range(len(views))))
    for k in range(len(views)):
        res = every[k]
        residuals.append(res)
        for c, r in enumerate(res):
            mask = masks[k][c]
            if r is None or mask is None:
                continue
            e2 = np.sum(r[mask] ** 2, axis=1)
            per_view[k, c] = float(np.sqrt(np.mean(e2))) if e2.size else np.nan
            if k in active:
                sq, n = sq + float(e2.sum()), n + e2.size
                dropped += int(np.sum(~mask))
    return JointSolution(
        K1=state.K[0], D1=state.D[0], K2=state.K[1], D2=state.D[1],
        R=np.asarray(cv2.Rodrigues(state.r_lr)[0], np.float64), T=state.t_lr.copy(),
        rvecs=tuple(state.rv), tvecs=tuple(state.tv), names=tuple(names), cov=cov, unobservable=unobservable,
        sigma_px=sigma, rms_px=float(np.sqrt(sq / max(1, n))), per_view_px=per_view,
        used=tuple(k in active for k in range(len(views))),
        inliers=tuple((m[0], m[1]) for m in masks), residuals=tuple((r[0], r[1]) for r in residuals),
        corners_dropped=dropped, view_threshold_px=float(view_thr) if view_thr is not None else float("nan"),
        warp=state.warp.copy())
