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
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.lens import LensModel
from s2r.calib.solve.observations import BoardObservation, StereoObservation
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

    def __init__(self, lens: LensModel, init: JointInit) -> None:
        self.lens = lens
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
        return np.concatenate([*map(np.asarray, parts), self.r_lr, self.t_lr])

    def set_global(self, g: FloatArray) -> None:
        ni = self.n_intr
        for c in range(2):
            v = g[c * ni:(c + 1) * ni]
            self.K[c] = np.array([[v[0], 0, v[2]], [0, v[1], v[3]], [0, 0, 1.0]])
            self.D[c][list(self.lens.free)] = v[4:]
        self.r_lr, self.t_lr = g[2 * ni:2 * ni + 3].copy(), g[2 * ni + 3:].copy()

    def copy_views(self) -> tuple[list[FloatArray], list[FloatArray]]:
        return [r.copy() for r in self.rv], [t.copy() for t in self.tv]


def _camera_terms(state: _State, cam: int, obs: BoardObservation, mask: NDArray[np.bool_], k: int
                  ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Residuals (2n,), global Jacobian (2n, ng) and view Jacobian (2n, 6) of one camera's inlier corners."""
    ni = state.n_intr
    ng = 2 * ni + 6
    proj = state.lens.projection
    obj, img = obs.obj[mask], obs.img[mask]
    cols = [6, 7, 8, 9, *(10 + i for i in state.lens.free)]
    Jg = np.zeros((2 * len(obj), ng))
    if cam == 0:
        pts, jac = proj.project(obj, state.rv[k], state.tv[k], state.K[0], state.D[0])
        Jg[:, :ni] = jac[:, cols]
        Jv = jac[:, :6]
    else:
        r3, t3, dr3dr1, _, dr3dr2, _, dt3dr1, dt3dt1, dt3dr2, dt3dt2 = cv2.composeRT(
            state.rv[k].reshape(3, 1), state.tv[k].reshape(3, 1), state.r_lr.reshape(3, 1), state.t_lr.reshape(3, 1))
        pts, jac = proj.project(obj, np.asarray(r3, np.float64).reshape(3), np.asarray(t3, np.float64).reshape(3),
                                state.K[1], state.D[1])
        jr, jt = jac[:, 0:3], jac[:, 3:6]
        Jg[:, ni:2 * ni] = jac[:, cols]
        Jg[:, 2 * ni:2 * ni + 3] = jr @ dr3dr2 + jt @ dt3dr2
        Jg[:, 2 * ni + 3:] = jt @ dt3dt2
        Jv = np.hstack([jr @ dr3dr1 + jt @ dt3dr1, jt @ dt3dt1])
    return (pts - img).reshape(-1), Jg, Jv


_Masks = list[list[NDArray[np.bool_] | None]]


def _normal_equations(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int]
                      ) -> tuple[float, int, FloatArray, FloatArray, list[tuple[FloatArray, FloatArray, FloatArray]]]:
    """SSR, residual count, A_gg, b_g and per active view (A_gv, A_vv, b_v)."""
    ng = 2 * state.n_intr + 6
    A, b = np.zeros((ng, ng)), np.zeros(ng)
    blocks = []
    ssr, m = 0.0, 0
    for k in active:
        Agv, Avv, bv = np.zeros((ng, 6)), np.zeros((6, 6)), np.zeros(6)
        for cam, obs in enumerate((views[k].left, views[k].right)):
            mask = masks[k][cam]
            if obs is None or mask is None or not mask.any():
                continue
            r, Jg, Jv = _camera_terms(state, cam, obs, mask, k)
            ssr += float(r @ r)
            m += r.size
            A += Jg.T @ Jg
            b += Jg.T @ r
            Agv += Jg.T @ Jv
            Avv += Jv.T @ Jv
            bv += Jv.T @ r
        blocks.append((Agv, Avv, bv))
    return ssr, m, A, b, blocks


def _step(A: FloatArray, b: FloatArray, blocks: list[tuple[FloatArray, FloatArray, FloatArray]], lam: float
          ) -> tuple[FloatArray, list[FloatArray]]:
    """Damped Gauss-Newton step (global, per view) with the view blocks eliminated."""
    S = A + lam * np.diag(np.diag(A))
    rhs = -b.copy()
    inv = []
    for Agv, Avv, bv in blocks:
        Vi = np.linalg.inv(Avv + lam * np.diag(np.diag(Avv)) + 1e-12 * np.eye(6))
        inv.append(Vi)
        S -= Agv @ Vi @ Agv.T
        rhs += Agv @ Vi @ bv
    dg = np.asarray(np.linalg.lstsq(S, rhs, rcond=None)[0], np.float64)
    dv = [Vi @ (-bv - Agv.T @ dg) for Vi, (Agv, _, bv) in zip(inv, blocks, strict=True)]
    return dg, dv


def _levenberg_marquardt(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int],
                         iterations: int = 50) -> None:
    lam = 1e-3
    ssr, _, A, b, blocks = _normal_equations(state, views, masks, active)
    for _ in range(iterations):
        g0, (rv0, tv0) = state.global_vec(), state.copy_views()
        dg, dv = _step(A, b, blocks, lam)
        state.set_global(g0 + dg)
        for k, d in zip(active, dv, strict=True):
            state.rv[k], state.tv[k] = rv0[k] + d[:3], tv0[k] + d[3:]
        new = _normal_equations(state, views, masks, active)
        if np.isfinite(new[0]) and new[0] <= ssr:
            converged = ssr - new[0] < 1e-10 * max(ssr, 1e-12)
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


def _residuals(state: _State, views: Sequence[StereoObservation], k: int
               ) -> tuple[FloatArray | None, FloatArray | None]:
    out: list[FloatArray | None] = []
    for cam, obs in enumerate((views[k].left, views[k].right)):
        if obs is None:
            out.append(None)
            continue
        r, _, _ = _camera_terms(state, cam, obs, np.ones(len(obs.ids), bool), k)
        out.append(r.reshape(-1, 2))
    return out[0], out[1]


def _robust_threshold(values: FloatArray, k_mad: float = 5.0, k_median: float = 2.0, floor: float = 0.3) -> float:
    med = float(np.median(values))
    return max(med + k_mad * 1.4826 * float(np.median(np.abs(values - med))), k_median * med, floor)


def _reject(state: _State, views: Sequence[StereoObservation], masks: _Masks, active: list[int], *,
            view_thr: float | None, corner_k: float, corner_floor_px: float,
            max_view_error_px: float | None) -> tuple[bool, float]:
    """Drop outlier corners and views (in place); returns (anything changed?, the view RMS threshold px).

    A view's RMS is over the inlier corners of both cameras; the threshold is ``max_view_error_px`` or a
    robust one (median + 5 MAD-sigmas, at least 2x the median and 0.3 px) fixed at the first round."""
    res = {k: _residuals(state, views, k) for k in active}
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
    S = A.copy()
    for Agv, Avv, _ in blocks:
        S -= Agv @ np.linalg.pinv(Avv) @ Agv.T
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


def _names(lens: LensModel) -> list[str]:
    intr = ["fx", "fy", "cx", "cy", *(lens.coef_names[i] for i in lens.free)]
    return [f"{side} {n}" for side in ("left", "right") for n in intr] + ["rx", "ry", "rz", "tx", "ty", "tz"]


def solve_joint(views: Sequence[StereoObservation], lens: LensModel, init: JointInit, *, max_rounds: int = 6,
                corner_k: float = 5.0, corner_floor_px: float = 0.3,
                max_view_error_px: float | None = None) -> JointSolution:
    """Refine everything together from ``init`` (see the module docstring); ``init.rvecs[k]`` / ``tvecs[k]``
    is view k's board pose in the left camera. Views may miss one camera or show different corners.

    Raises:
        CalibrationError: fewer than 5 views, or the solve diverged (non-finite parameters).
    """
    if len(views) < _MIN_VIEWS:
        raise CalibrationError(f"only {len(views)} views for the joint solve, at least {_MIN_VIEWS} needed",
                               hint="record more views with the board visible in both cameras")
    state = _State(lens, init)
    masks: _Masks = [[None if o is None else np.ones(len(o.ids), bool) for o in (v.left, v.right)] for v in views]
    active = list(range(len(views)))
    view_thr: float | None = None
    for _ in range(max_rounds):
        _levenberg_marquardt(state, views, masks, active)
        changed, view_thr = _reject(state, views, masks, active, view_thr=view_thr, corner_k=corner_k,
                                    corner_floor_px=corner_floor_px, max_view_error_px=max_view_error_px)
        if not changed:
            break
    else:
        _levenberg_marquardt(state, views, masks, active)
    if not np.all(np.isfinite(state.global_vec())):
        raise CalibrationError("the joint calibration solve diverged (non-finite parameters)",
                               hint="check the views: the board must be fully visible and sharp in both cameras")
    names = _names(lens)
    cov, unobservable, sigma = _covariance(state, views, masks, active, names)
    per_view = np.full((len(views), 2), np.nan)
    residuals = []
    sq, n = 0.0, 0
    dropped = 0
    for k in range(len(views)):
        res = _residuals(state, views, k)
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
        corners_dropped=dropped, view_threshold_px=float(view_thr) if view_thr is not None else float("nan"))
