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

from s2r.calib.solve.solvers.jointterms import Blocks, JointInit, Masks, State, all_residuals, normal_equations, prepare
from s2r.calib.solve.solvers.observations import StereoObservation
from s2r.errors import CalibrationError
from s2r.lens.models import LensModel

__all__ = ["START_DAMPING", "WARM_DAMPING", "JointInit", "JointSolution", "solve_joint"]

FloatArray = NDArray[np.float64]
#: Per view index, the residuals (N, 2) px of all its corners per camera (None where a camera saw nothing).
Residuals = dict[int, tuple[FloatArray | None, FloatArray | None]]
_MIN_VIEWS = 5
#: The starting Marquardt damping (share of the normal equations' diagonal) of a solve from OpenCV's
#: per-camera calibration. The rig's parameters are strongly correlated (focal length with distance, centre
#: with tilt): a damping of 1e-3, the textbook start, dominates those directions, each step gains only what it
#: lets through, and the solve crawls while the damping falls 10x per step (13 normal-equation evaluations on a
#: 40-pair rig, 7 from 1e-6, the same answer to 1e-5 px; 53 against 38 on a real set). A step that raises the
#: error still raises the damping 10x, so a poor start costs a few rejected steps, not a wrong answer.
START_DAMPING = 1e-6
#: ... and of a solve started next to its answer (a resampling fold or the bent board, from the full
#: solution): plain Gauss-Newton steps, 1-2 of them (5-6 from 1e-3, the same answer to 1e-4 px).
WARM_DAMPING = 1e-9
#: A step taken at this damping or less is close enough to Gauss-Newton that the decrease it predicts is a
#: convergence test.
NEAR_GAUSS_NEWTON = 1e-3


@dataclass(frozen=True)
class JointSolution:
    """The solved rig with uncertainties.

    ``names`` of the global parameters (``left fx`` ... ``right k2`` ... ``rx ry rz tx ty tz``), ``cov`` their
    covariance (inf on the diagonal for ``unobservable`` ones), ``sigma_px`` the residual std of one
    coordinate, ``rms_px`` the RMS corner error (both coordinates), ``per_view_px`` (n_views, 2) RMS per
    camera (nan where a camera saw nothing), ``used`` which input views survived, ``inliers`` per view and
    camera the kept-corner masks, ``residuals`` per view and camera (N, 2) px of ALL corners,
    ``view_threshold_px`` the view outlier threshold (RMS over both cameras); ``converged`` False when the last
    Levenberg-Marquardt run stopped at its step limit with the error still falling (the answer then depends
    on the starting point).
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
    converged: bool = True

    def std(self, name: str) -> float:
        """Standard deviation of a global parameter (inf when unobservable)."""
        return float(np.sqrt(self.cov[self.names.index(name), self.names.index(name)]))

    def translation_cov(self) -> FloatArray:
        """Covariance (3x3, m^2) of T."""
        return np.asarray(self.cov[-3:, -3:], np.float64)

    def rotation_cov(self) -> FloatArray:
        """Covariance (3x3, rad^2) of the pair's rotation vector."""
        return np.asarray(self.cov[-6:-3, -6:-3], np.float64)


def _step(A: FloatArray, b: FloatArray, blocks: Blocks, lam: float) -> tuple[FloatArray, FloatArray]:
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


def _levenberg_marquardt(state: State, views: Sequence[StereoObservation], masks: Masks, active: list[int],
                         iterations: int = 50, rel_tol: float = 1e-10, damping: float = START_DAMPING) -> bool:
    """Refine ``state`` in place; False when ``iterations`` steps ran out with the error still falling (a step
    no damping can make lower the error counts as converged: the solve is at a minimum or stuck there)."""
    lam = damping
    data = prepare(views, masks, active)
    ssr, _, A, b, blocks = normal_equations(state, views, masks, active, data)
    for _ in range(iterations):
        g0, (rv0, tv0) = state.global_vec(), state.copy_views()
        dg, dv = _step(A, b, blocks, lam)
        if lam <= NEAR_GAUSS_NEWTON and -(float(b @ dg) + float(np.sum(blocks[2] * dv))) < rel_tol * max(ssr, 1e-12):
            return True  # a near-Gauss-Newton step that predicts a fall below the tolerance: converged here
        state.set_global(g0 + dg)
        for k, d in zip(active, dv, strict=True):
            state.rv[k], state.tv[k] = rv0[k] + d[:3], tv0[k] + d[3:]
        new = normal_equations(state, views, masks, active, data)
        if np.isfinite(new[0]) and new[0] <= ssr:
            converged = ssr - new[0] < rel_tol * max(ssr, 1e-12)
            ssr, _, A, b, blocks = new
            lam = max(lam / 10, 1e-9)
            if converged:
                return True
        else:
            state.set_global(g0)
            state.rv, state.tv = rv0, tv0
            lam *= 10
            if lam > 1e8:
                return True
    return False


def _robust_threshold(values: FloatArray, k_mad: float = 5.0, k_median: float = 2.0, floor: float = 0.3) -> float:
    med = float(np.median(values))
    return max(med + k_mad * 1.4826 * float(np.median(np.abs(values - med))), k_median * med, floor)


def _reject(state: State, views: Sequence[StereoObservation], masks: Masks, active: list[int], *,
            view_thr: float | None, corner_k: float, corner_floor_px: float,
            max_view_error_px: float | None) -> tuple[bool, float, Residuals]:
    """Drop outlier corners and views (in place); returns (anything changed?, the view RMS threshold px, the
    residuals of every corner of the views active on entry).

    A view's RMS is over the inlier corners of both cameras; the threshold is ``max_view_error_px`` or a
    robust one (median + 5 MAD-sigmas, at least 2x the median and 0.3 px) fixed at the first round."""
    res = all_residuals(state, views, active)
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
    return changed, view_thr, res


def _covariance(state: State, views: Sequence[StereoObservation], masks: Masks, active: list[int],
                names: list[str]) -> tuple[FloatArray, tuple[str, ...], float]:
    ssr, m, A, _, blocks = normal_equations(state, views, masks, active)
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


def _start_masks(views: Sequence[StereoObservation], given: Masks | None) -> Masks:
    """Copies of ``given`` where they fit the views (same corner count), else every corner kept."""
    out: Masks = []
    for k, v in enumerate(views):
        row: list[NDArray[np.bool_] | None] = []
        for c, o in enumerate((v.left, v.right)):
            m = None if given is None or k >= len(given) else given[k][c]
            row.append(None if o is None else m.copy() if m is not None and m.shape == (len(o.ids),)
                       else np.ones(len(o.ids), bool))
        out.append(row)
    return out


def _names(lens: LensModel, warp: bool = False) -> list[str]:
    intr = ["fx", "fy", "cx", "cy", *(lens.coef_names[i] for i in lens.free)]
    return [f"{side} {n}" for side in ("left", "right") for n in intr] + (["warp x", "warp y"] if warp else []) \
        + ["rx", "ry", "rz", "tx", "ty", "tz"]


def solve_joint(views: Sequence[StereoObservation], lens: LensModel, init: JointInit, *, max_rounds: int = 6,
                corner_k: float = 5.0, corner_floor_px: float = 0.3,
                max_view_error_px: float | None = None, rel_tol: float = 1e-10,
                covariance: bool = True, warp: bool = False, masks: Masks | None = None,
                max_iterations: int = 50, damping: float = START_DAMPING) -> JointSolution:
    """Refine everything together from ``init`` (see the module docstring); ``init.rvecs[k]`` / ``tvecs[k]``
    is view k's board pose in the left camera. Views may miss one camera or show different corners.
    ``rel_tol``: LM stops when the sum of squares falls by less than this share (resampling solves, started
    from the full solution, use a looser one); ``covariance`` False skips the covariance (NaN; they need
    none); ``warp`` also solves the board's bend (two parameters, metres, see ``State.warp_basis``; the
    initial one from ``init.warp``); ``masks`` the starting inlier masks per view and camera (a warm start
    from an earlier solve of these views: its rejected corners stay out; default every corner);
    ``max_iterations`` the LM steps per round (a warm start near the answer needs two or three);
    ``damping`` the starting Marquardt damping (:data:`WARM_DAMPING` for a warm start next to the answer).

    Raises:
        CalibrationError: fewer than 5 views, or the solve diverged (non-finite parameters).
    """
    if len(views) < _MIN_VIEWS:
        raise CalibrationError(f"only {len(views)} views for the joint solve, at least {_MIN_VIEWS} needed",
                               hint="record more views with the board visible in both cameras")
    state = State(lens, init, warp=warp, views=views)
    masks = _start_masks(views, masks)
    active = list(range(len(views)))
    view_thr: float | None = None
    final: Residuals | None = None
    for _ in range(max_rounds):
        converged = _levenberg_marquardt(state, views, masks, active, iterations=max_iterations, rel_tol=rel_tol,
                                         damping=damping)
        changed, view_thr, res = _reject(state, views, masks, active, view_thr=view_thr, corner_k=corner_k,
                                         corner_floor_px=corner_floor_px, max_view_error_px=max_view_error_px)
        if not changed:
            final = res if len(res) == len(views) else None  # the state these residuals came from is final
            break
    else:
        converged = _levenberg_marquardt(state, views, masks, active, iterations=max_iterations, rel_tol=rel_tol,
                                         damping=damping)
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
    every = final if final is not None else all_residuals(state, views, list(range(len(views))))
    for k in range(len(views)):
        residuals.append(every[k])
        for c, r in enumerate(every[k]):
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
        warp=state.warp.copy(), converged=converged)
