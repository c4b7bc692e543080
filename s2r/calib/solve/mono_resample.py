"""Resampling over views for one camera (``--mono``): a held-out error and jackknife standard deviations.

The used views are split into ``K`` interleaved folds (view i in fold ``i mod K``, as the stereo path:
:func:`s2r.calib.solve.resample.split_folds`). For each fold, OpenCV's ``calibrateCameraExtended`` solves the
other views, started from the full solution's intrinsics (CALIB_USE_INTRINSIC_GUESS) with a loose stopping
rule, and applies the full solve's view rule: a training view whose RMS exceeds the robust threshold of the
fold's first solve (:func:`s2r.calib.solve.cvsolve.outlier_threshold`, or ``--max-error``) is dropped and the
fold solved again. Then:

- **Held-out error**: each held-out view gets one board pose fitted with the fold's intrinsics fixed
  (``solvePnP``, then ``solvePnPRefineLM``). A held-out view beyond the training solve's threshold is treated
  as the training solve treats its own views: left out of the inlier figure (counted in the figure over all
  corners, with how many corners were left out). Reported: RMS per corner (px, both coordinates).
- **Jackknife standard deviations** of fx, fy, cx, cy (px; delete-a-group jackknife,
  ``var = (K-1)/K * sum_f (theta_f - mean)^2``). Unlike the residual-scaled covariance of
  ``calibrateCameraExtended`` they see systematic error (board shape, lens model).

Views may be partial (a ``--target`` board): each view carries its own board points (N, 3) float32 m and
image points (N, 2) float32 px. The folds run in s2r's process pool (:func:`s2r.executor.local_pool`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.cvsolve import DISTORTION_CHOICES, INIT_CRITERIA, MonoSolution, outlier_threshold
from s2r.calib.solve.heldout import ParameterStd
from s2r.calib.solve.resample import FOLDS, split_folds
from s2r.executor import local_pool

__all__ = ["MONO_PARAMETERS", "MonoFoldOutcome", "MonoFoldTask", "MonoHeldout", "jackknife", "mono_heldout",
           "reported_std", "run_mono_fold"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]
T = TypeVar("T")
#: Parameters whose jackknife std is reported, in this order (px).
MONO_PARAMETERS = ("fx", "fy", "cx", "cy")
_ROUNDS = 4


@dataclass(frozen=True)
class MonoFoldTask:
    """One fold: training and held-out views (board points, image points), the warm start (K 3x3 px, D),
    the ``--distortion`` choice, the image size (w, h) px and the fixed view threshold (``--max-error``)."""

    train_obj: tuple[Points, ...]
    train_img: tuple[Points, ...]
    test_obj: tuple[Points, ...]
    test_img: tuple[Points, ...]
    K: FloatArray
    D: FloatArray
    distortion: str
    size: tuple[int, int]
    max_error_px: float | None


@dataclass(frozen=True)
class MonoFoldOutcome:
    """A fold's training intrinsics (fx, fy, cx, cy px) and its held-out corners' squared errors (px^2):
    ``sq_inlier`` of the views within the training threshold, ``sq_all`` of every held-out corner; ``failed``
    says why the fold has none."""

    params: FloatArray
    sq_inlier: FloatArray
    sq_all: FloatArray
    failed: str = ""


@dataclass(frozen=True)
class MonoHeldout:
    """The held-out error over ``folds`` folds (px per corner): over the inlier views' corners (``heldout_px``,
    the verdict's figure) and over all (``heldout_all_px``); ``corners_rejected`` of ``corners_total`` left out
    by the training solve's view rule; per fold; fx, fy, cx, cy with both standard deviations."""

    folds: int
    heldout_px: float
    heldout_all_px: float
    corners_rejected: int
    corners_total: int
    folds_px: tuple[float, ...]
    stds: tuple[ParameterStd, ...]
    failed: tuple[str, ...] = ()

    def std(self, name: str) -> ParameterStd:
        """The entry of one of ``MONO_PARAMETERS``."""
        return next(s for s in self.stds if s.name == name)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"folds": self.folds, "heldout_px": self.heldout_px, "heldout_all_px": self.heldout_all_px,
                "corners_rejected": self.corners_rejected, "corners_total": self.corners_total,
                "folds_px": list(self.folds_px), "failed_folds": list(self.failed),
                "parameters": {s.name: s.as_dict() for s in self.stds}}


def _calibrate(obj: Sequence[Points], img: Sequence[Points], task: MonoFoldTask,
               start: tuple[FloatArray, FloatArray] | None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """K, D and per-view RMS (px) of one training solve, warm-started from ``start`` (K, D) when given."""
    flags, ncoef = DISTORTION_CHOICES[task.distortion]
    K0, D0 = np.eye(3), np.zeros(ncoef)
    if start is not None:
        K0 = start[0].copy()
        src = start[1].reshape(-1)[:ncoef]
        D0[:src.size] = src
    out = cv2.calibrateCameraExtended(list(obj), [p.reshape(-1, 1, 2) for p in img], task.size, K0, D0,
                                      flags=flags | (0 if start is None else cv2.CALIB_USE_INTRINSIC_GUESS),
                                      criteria=INIT_CRITERIA)
    K, D, per_view = np.asarray(out[1], np.float64), np.asarray(out[2], np.float64).reshape(-1), out[7]
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D))):
        raise cv2.error("non-finite calibration")
    return K, D, np.asarray(per_view, np.float64).reshape(-1)


def _train(task: MonoFoldTask) -> tuple[FloatArray, FloatArray, float]:
    """The fold's intrinsics after the full solve's view rule, and that rule's threshold (px)."""
    obj, img = list(task.train_obj), list(task.train_img)
    try:
        K, D, err = _calibrate(obj, img, task, (task.K, task.D))
    except cv2.error:  # a warm start that fails is retried from scratch, as the full solve started
        K, D, err = _calibrate(obj, img, task, None)
    thr = outlier_threshold(err, max_error_px=task.max_error_px)
    for _ in range(_ROUNDS):
        bad = set(np.flatnonzero(err > thr).tolist())
        if not bad or len(obj) - len(bad) < 5:
            break
        obj = [o for j, o in enumerate(obj) if j not in bad]
        img = [p for j, p in enumerate(img) if j not in bad]
        K, D, err = _calibrate(obj, img, task, (K, D))
    return K, D, thr


def _view_sq(obj: Points, img: Points, K: FloatArray, D: FloatArray) -> FloatArray:
    """Squared corner errors (px^2) of one view whose pose alone is fitted with K, D fixed (inf when no pose)."""
    pts = img.reshape(-1, 1, 2).astype(np.float64)
    o = obj.reshape(-1, 1, 3).astype(np.float64)
    ok, rv, tv = cv2.solvePnP(o, pts, K, D)
    if not ok:
        return np.full(len(obj), np.inf)
    rv, tv = cv2.solvePnPRefineLM(o, pts, K, D, rv, tv)
    proj = cv2.projectPoints(o, rv, tv, K, D)[0].reshape(-1, 2)
    return np.asarray(np.sum((proj - pts.reshape(-1, 2)) ** 2, axis=1), np.float64)


def run_mono_fold(task: MonoFoldTask) -> MonoFoldOutcome:
    """Solve one fold's training views and measure its held-out views (a worker function)."""
    try:
        K, D, thr = _train(task)
    except cv2.error as exc:
        return MonoFoldOutcome(np.full(4, np.nan), np.zeros(0), np.zeros(0), failed=str(exc).strip()[-200:])
    inl, every = [], []
    for obj, img in zip(task.test_obj, task.test_img, strict=True):
        sq = _view_sq(obj, img, K, D)
        every.append(sq)
        if float(np.sqrt(np.mean(sq))) <= thr:
            inl.append(sq)
    return MonoFoldOutcome(np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2]]),
                           np.concatenate(inl) if inl else np.zeros(0), np.concatenate(every))


def _run(tasks: Sequence[MonoFoldTask], jobs: int, side: Callable[[], T] | None) -> tuple[list[MonoFoldOutcome],
                                                                                          T | None]:
    """Every task over ``jobs`` processes (in this process when 1), and ``side()`` run here meanwhile."""
    if jobs <= 1 or len(tasks) <= 1:
        return [run_mono_fold(t) for t in tasks], None if side is None else side()
    pool = local_pool(min(jobs, len(tasks)))
    try:
        futures = [pool.submit(run_mono_fold, t) for t in tasks]
        extra = None if side is None else side()
        return [f.result() for f in futures], extra
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _rms(parts: Sequence[FloatArray]) -> float:
    sq = np.concatenate(parts) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(sq))) if sq.size else float("nan")


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def jackknife(outcomes: Sequence[MonoFoldOutcome]) -> FloatArray:
    """Delete-a-group jackknife std (px) of fx, fy, cx, cy over the folds (NaN with fewer than 2)."""
    good = [o.params for o in outcomes if not o.failed]
    k = len(good)
    if k < 2:
        return np.full(4, np.nan)
    theta = np.array(good)
    return np.asarray(np.sqrt((k - 1) / k * np.sum((theta - theta.mean(axis=0)) ** 2, axis=0)), np.float64)


def mono_heldout(obj: Sequence[Points], img: Sequence[Points], sol: MonoSolution, size: tuple[int, int], *,
                 distortion: str, max_error_px: float | None = None, jobs: int = 1, folds: int = FOLDS,
                 side: Callable[[], T] | None = None) -> tuple[MonoHeldout | None, T | None]:
    """The held-out error and both std devs of the solved camera ``sol`` (its used views ``obj``/``img``), and
    ``side()`` (e.g. the lens-model comparison) run in this process while the folds run in the pool. None (and
    ``side()``) when there are too few views for two folds."""
    groups = split_folds(len(img), folds)
    if not groups:
        return None, None if side is None else side()
    tasks = []
    for test in groups:
        held = set(test)
        train = [i for i in range(len(img)) if i not in held]
        tasks.append(MonoFoldTask(tuple(obj[i] for i in train), tuple(img[i] for i in train),
                                  tuple(obj[i] for i in test), tuple(img[i] for i in test), sol.K, sol.D,
                                  distortion, size, max_error_px))
    outcomes, extra = _run(tasks, jobs, side)
    good = [o for o in outcomes if not o.failed]
    jk = jackknife(outcomes)
    values = (sol.K[0, 0], sol.K[1, 1], sol.K[0, 2], sol.K[1, 2])
    stds = tuple(ParameterStd(n, float(v), _finite(float(c)), _finite(float(j)))
                 for n, v, c, j in zip(MONO_PARAMETERS, values, sol.std[:4], jk, strict=True))
    n_in = sum(o.sq_inlier.size for o in good)
    n_all = sum(o.sq_all.size for o in good)
    held_out = MonoHeldout(len(outcomes), _rms([o.sq_inlier for o in good]), _rms([o.sq_all for o in good]),
                           n_all - n_in, n_all, tuple(_rms([o.sq_inlier]) for o in good), stds,
                           tuple(o.failed for o in outcomes if o.failed))
    return held_out, extra


def reported_std(std: FloatArray, held: MonoHeldout | None) -> FloatArray:
    """``std`` (fx, fy, cx, cy, d...) with fx..cy replaced by the larger of covariance and jackknife (the
    unobservable, non-finite ones kept)."""
    out = np.asarray(std, np.float64).copy()
    if held is None:
        return out
    for i, name in enumerate(MONO_PARAMETERS):
        value = held.std(name).reported
        if value is not None and np.isfinite(out[i]):
            out[i] = value
    return out
