"""Resampling over pairs: the stereo held-out error and jackknife standard deviations (model error included).

The used pairs are split into ``K`` interleaved folds (pair i in fold ``i mod K``). For each fold the joint
solve (:func:`s2r.calib.solve.solvers.joint.solve_joint`, same outlier rules: corners beyond 5 robust sigmas, at least
0.3 px, and views beyond the robust view threshold) runs on the other pairs, started from the full solution
(warm start; converged, as the jackknife reads its parameters). Then:

- **Stereo held-out error**: with the fold's intrinsics and extrinsics fixed, each held-out pair gets ONE board
  pose fitted to both cameras' corners together. Corners farther than the median + 5 robust sigmas of every
  held-out corner's error (at least 0.3 px; :func:`trim_blunders`) are detector blunders, left out. Reported:
  RMS over the corners kept (px, per corner, both coordinates), RMS over all corners and how many were left
  out. The extrinsics are tested, which a per-camera held-out error never does.
- **Jackknife standard deviations** of fx, fy, cx, cy per camera, the baseline and the rotation (delete-a-group
  jackknife: ``var = (K-1)/K * sum_f (theta_f - mean)^2``). Unlike the residual-scaled covariance they see
  systematic error (board shape, lens model): estimates from view subsets that disagree by more than the
  noise explains.
- **Lens-model choice**: the same folds for every candidate model (warm-started from the chosen model's fit),
  scored by the stereo held-out error.

The fold solves run in parallel in s2r's process pool (:func:`s2r.cvpool.opencv_pool` over
:func:`s2r.executor.local_pool`, the one executor seam).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TypeVar

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.joint import NEAR_GAUSS_NEWTON, WARM_DAMPING, JointInit, JointSolution, solve_joint
from s2r.calib.solve.solvers.jointterms import Masks, all_residuals, normal_equations, prepare
from s2r.calib.solve.solvers.jointterms import State as SolveState
from s2r.calib.solve.solvers.observations import StereoObservation
from s2r.cvpool import opencv_pool_or_none
from s2r.errors import CalibrationError
from s2r.lens.models import LensModel

__all__ = ["BLUNDER_FLOOR_PX", "BLUNDER_SIGMAS", "FOLDS", "PARAMETERS", "FoldOutcome", "FoldTask", "jackknife_std",
           "run_fold", "run_folds", "split_folds", "trim_blunders"]


FloatArray = NDArray[np.float64]
T = TypeVar("T")
#: Folds of the held-out error and the jackknife (as the issue's checker: 4 interleaved folds).
FOLDS = 4
#: Parameters whose jackknife std is reported, in this order (px; the baseline in metres, rotation in degrees).
PARAMETERS = ("left fx", "left fy", "left cx", "left cy", "right fx", "right fy", "right cx", "right cy",
              "baseline", "rotation")
_MIN_TRAIN = 5
#: LM stopping rule and step limit of the fold solves whose parameters are read (the jackknife): converged.
#: Started from the full solution, they stop within 5-6 steps; a looser rule (1e-5, or 3 steps) leaves each fold
#: near the full solution and shrank the jackknife std 1.5-3x on real sets (lanhp left cx 3.2 against 5.8 px,
#: aaron left fx 3.9 against 10.4 px: mrcal's folds on the same corners give 3.5 and 10.4).
_FOLD_TOL = 1e-8
_FOLD_ITERATIONS = 50
#: The same for fold solves read only for their held-out error (the lens-model comparison): three LM steps
#: reach it within 0.1 % on three real sets (two steps read up to 0.6 % low, one step 1.4 % low), while the
#: rational model's poorly determined k4-k6 keep a converged solve crawling for 50 steps.
_SCORE_TOL = 1e-5
_SCORE_ITERATIONS = 3
#: Relative change of the sum of squares at which a held-out pose fit stops (the held-out error to ~1e-6).
_POSE_TOL = 1e-6


@dataclass(frozen=True)
class FoldTask:
    """One fold of one lens model: training and held-out views, a warm start (training poses and, in
    ``masks``, the full solve's inlier corners of the training views), the held-out views' starting poses
    (board in the left camera), and the outlier option of the full solve. ``score_only``: only the held-out
    error is read (not the training parameters), so the training solve may stop short of convergence."""

    lens: LensModel
    train: tuple[StereoObservation, ...]
    test: tuple[StereoObservation, ...]
    init: JointInit
    test_rvecs: tuple[FloatArray, ...]
    test_tvecs: tuple[FloatArray, ...]
    max_view_error_px: float | None
    warp: bool = False
    masks: Masks | None = None
    score_only: bool = False


@dataclass(frozen=True)
class FoldOutcome:
    """A fold's training estimate (K, D per camera, R, T) and its held-out corners' squared errors (px^2):
    ``sq_all`` of every corner, ``sq_inlier`` of the corners kept (every one until :func:`trim_blunders`);
    ``failed`` says why the fold has none."""

    K1: FloatArray
    K2: FloatArray
    R: FloatArray
    T: FloatArray
    sq_inlier: FloatArray
    sq_all: FloatArray
    failed: str = ""
    D1: FloatArray | None = None
    D2: FloatArray | None = None
    warp: FloatArray | None = None

    def params(self) -> FloatArray:
        """``PARAMETERS`` but the rotation: fx fy cx cy per camera (px) and the baseline (m)."""
        return np.array([self.K1[0, 0], self.K1[1, 1], self.K1[0, 2], self.K1[1, 2], self.K2[0, 0], self.K2[1, 1],
                         self.K2[0, 2], self.K2[1, 2], float(np.linalg.norm(self.T))])


def split_folds(n: int, folds: int = FOLDS) -> list[list[int]]:
    """Interleaved folds of ``n`` views (view i in fold ``i mod folds``); fewer folds when every training set
    would otherwise have fewer than 5 views; empty when even 2 folds cannot."""
    k = folds
    while k >= 2 and n - -(-n // k) < _MIN_TRAIN:
        k -= 1
    return [list(range(f, n, k)) for f in range(k)] if k >= 2 else []


def _fit_poses(state: SolveState, views: Sequence[StereoObservation], masks: list[list[NDArray[np.bool_] | None]]
               ) -> None:
    """Board poses of ``views`` (one per view, both cameras together) with the cameras and the pair fixed.

    Stops after a near-Gauss-Newton step that predicts a fall of the sum of squares below ``_POSE_TOL`` of it
    (taken without evaluating it: such a step lands the poses ~sqrt(tol) closer to their minimum, which moved
    held-out errors by up to 2e-3 px when it was skipped), or when a step changes the sum by less than that (up
    or down: at the minimum rounding decides the sign; raising the damping there only repeated the same
    evaluation up to 17 times)."""
    active = list(range(len(views)))
    data = prepare(views, masks, active)  # the corners do not change between steps
    lam = WARM_DAMPING
    ssr, _, _, _, (_, Avv, bv) = normal_equations(state, views, masks, active, data, poses_only=True)
    for _ in range(30):
        rv0, tv0 = state.copy_views()
        damp = lam * np.einsum("nii->ni", Avv)[:, :, None] * np.eye(6) + 1e-12 * np.eye(6)
        dv = -np.linalg.solve(Avv + damp, bv[:, :, None])[:, :, 0]
        for k in active:
            state.rv[k], state.tv[k] = rv0[k] + dv[k, :3], tv0[k] + dv[k, 3:]
        if lam <= NEAR_GAUSS_NEWTON and -float(np.sum(bv * dv)) < _POSE_TOL * max(ssr, 1e-12):
            return
        new_ssr, _, _, _, (_, new_Avv, new_bv) = normal_equations(state, views, masks, active, data,
                                                                   poses_only=True)
        if np.isfinite(new_ssr) and new_ssr <= ssr:
            done = ssr - new_ssr < _POSE_TOL * max(ssr, 1e-12)
            ssr, Avv, bv, lam = new_ssr, new_Avv, new_bv, max(lam / 10, 1e-9)
            if done:
                return
        else:
            state.rv, state.tv = rv0, tv0
            if np.isfinite(new_ssr) and new_ssr - ssr < _POSE_TOL * max(ssr, 1e-12):
                return
            lam *= 10
            if lam > 1e8:
                return


def _heldout(task: FoldTask, sol: JointSolution) -> FloatArray:
    """Squared corner errors (px^2) of every corner of the held-out views, one board pose per view fitted to
    both cameras' corners (all of them: which are blunders is decided over every fold, see :func:`trim_blunders`)."""
    init = JointInit(sol.K1, sol.D1, sol.K2, sol.D2, sol.R, sol.T, task.test_rvecs, task.test_tvecs,
                     warp=sol.warp)
    state = SolveState(task.lens, init, warp=task.warp, views=task.test)
    views = task.test
    masks: list[list[NDArray[np.bool_] | None]] = [
        [None if o is None else np.ones(len(o.ids), bool) for o in (v.left, v.right)] for v in views]
    _fit_poses(state, views, masks)
    res = all_residuals(state, views, list(range(len(views))))
    return np.concatenate([np.sum(r ** 2, axis=1) for pair in res.values() for r in pair if r is not None])


#: Held-out corners farther than the median + this many robust sigmas (1.4826 MAD) of every held-out corner's
#: error are detector blunders, left out of the held-out error (see :func:`trim_blunders`).
BLUNDER_SIGMAS = 5.0
#: ... but never a corner closer than this (px).
BLUNDER_FLOOR_PX = 0.3


def trim_blunders(outcomes: Sequence[FoldOutcome]) -> list[FoldOutcome]:
    """``outcomes`` with ``sq_inlier`` the held-out corners whose error (px) is within the median + 5 robust
    sigmas of every fold's held-out corner errors (at least 0.3 px): the corners a detector misplaced (the
    6.6 px corners of a real bag) are left out, nothing else.

    One rule over the pooled held-out errors, as an outside check of the held-out error trims them: a rule
    on the training residuals (smaller than any held-out error) left out twice as many held-out corners and read
    the held-out error up to 15 % low on real sets, and re-fitting the poses without the corners left out
    lowered it further on heavy-tailed sets."""
    errors = [np.sqrt(o.sq_all) for o in outcomes if not o.failed and o.sq_all.size]
    if not errors:
        return list(outcomes)
    e = np.concatenate(errors)
    med = float(np.median(e))
    thr = max(med + BLUNDER_SIGMAS * 1.4826 * float(np.median(np.abs(e - med))), BLUNDER_FLOOR_PX)
    return [o if o.failed else replace(o, sq_inlier=o.sq_all[o.sq_all <= thr * thr]) for o in outcomes]


def run_fold(task: FoldTask) -> FoldOutcome:
    """Solve one fold's training views and measure its held-out views (a worker function)."""
    nan = np.full((3, 3), np.nan)
    try:
        sol = solve_joint(task.train, task.lens, task.init, max_view_error_px=task.max_view_error_px,
                          rel_tol=_SCORE_TOL if task.score_only else _FOLD_TOL, covariance=False, warp=task.warp,
                          masks=task.masks, max_iterations=_SCORE_ITERATIONS if task.score_only else _FOLD_ITERATIONS,
                          damping=WARM_DAMPING)
    except (CalibrationError, np.linalg.LinAlgError, cv2.error) as exc:
        return FoldOutcome(nan, nan, nan, np.full(3, np.nan), np.zeros(0), np.zeros(0), failed=str(exc))
    sq_all = _heldout(task, sol)
    return FoldOutcome(sol.K1, sol.K2, sol.R, sol.T, sq_all, sq_all, D1=sol.D1, D2=sol.D2,
                       warp=sol.warp if task.warp else None)


def run_folds(tasks: Sequence[FoldTask], *, jobs: int, side: Callable[[], T] | None = None,
              then: Callable[[T], Sequence[FoldTask]] | None = None
              ) -> tuple[list[FoldOutcome], T | None, list[FoldOutcome]]:
    """Every task, over ``jobs`` processes of s2r's pool (in this process when ``jobs`` is 1); the result of
    ``side`` (a picklable call, submitted first so it runs beside the folds); and the outcomes of the tasks
    ``then`` makes of that result (submitted as soon as it is known, e.g. only when it is worth testing)."""
    with contextlib.ExitStack() as stack:
        pool = opencv_pool_or_none(min(jobs, len(tasks)), stack, "solving the folds")
        if pool is None:
            extra = None if side is None else side()
            more = [] if extra is None or then is None else then(extra)
            return [run_fold(t) for t in tasks], extra, [run_fold(t) for t in more]
        side_future = None if side is None else pool.submit(side)
        futures = [pool.submit(run_fold, t) for t in tasks]
        extra = None if side_future is None else side_future.result()
        more = [] if extra is None or then is None else then(extra)
        later = [pool.submit(run_fold, t) for t in more]
        return [f.result() for f in futures], extra, [f.result() for f in later]


def jackknife_std(outcomes: Sequence[FoldOutcome], R_full: FloatArray) -> FloatArray:
    """Delete-a-group jackknife std of ``PARAMETERS`` (px, m, deg) over the folds (NaN with fewer than 2)."""
    good = [o for o in outcomes if not o.failed]
    k = len(good)
    if k < 2:
        return np.full(len(PARAMETERS), np.nan)
    theta = np.array([o.params() for o in good])
    var = (k - 1) / k * np.sum((theta - theta.mean(axis=0)) ** 2, axis=0)
    dev = np.array([np.asarray(cv2.Rodrigues(o.R @ R_full.T)[0], np.float64).reshape(3) for o in good])
    rot_var = (k - 1) / k * float(np.sum((dev - dev.mean(axis=0)) ** 2))
    return np.concatenate([np.sqrt(var), [float(np.degrees(np.sqrt(rot_var)))]])
