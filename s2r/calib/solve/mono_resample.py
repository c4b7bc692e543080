"""Resampling over views for one camera (``--mono``, ``--target --mono``, fisheye): a held-out error and
jackknife standard deviations.

The used views are split into ``K`` interleaved folds (view i in fold ``i mod K``, as the stereo path:
:func:`s2r.calib.solve.resample.split_folds`). Each fold (:mod:`s2r.calib.solve.mono_fold`) solves the other
views, warm-started from the full solution with a loose stopping rule and the full solve's outlier rules. Then:

- **Held-out error**: each held-out view gets one board pose fitted with the fold's intrinsics fixed; corners
  the training rules would leave out (a view beyond the robust view threshold; with a corner rule, a corner far
  beyond the median) are left out of the inlier figure and counted. Reported: RMS per corner (px, both
  coordinates), over the inliers (the verdict's figure) and over all corners.
- **Jackknife standard deviations** of fx, fy, cx, cy (px; delete-a-group jackknife,
  ``var = (K-1)/K * sum_f (theta_f - mean)^2``). Unlike the residual-scaled covariance they see systematic
  error (board shape, lens model). The larger of the two is reported and written to the profile.

Views may be partial (a ``--target`` board): each view carries its own board points (N, 3) float32 m and
image points (N, 2) float32 px. The folds run in s2r's process pool (:func:`s2r.executor.local_pool`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.cvsolve import MonoSolution
from s2r.calib.solve.heldout import ParameterStd
from s2r.calib.solve.mono_fold import MonoFoldOutcome, MonoFoldTask, run_mono_fold
from s2r.calib.solve.resample import FOLDS, split_folds
from s2r.executor import local_pool

__all__ = ["MONO_PARAMETERS", "MonoHeldout", "jackknife", "mono_heldout", "reported_std"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]
T = TypeVar("T")
#: Parameters whose jackknife std is reported, in this order (px).
MONO_PARAMETERS = ("fx", "fy", "cx", "cy")


@dataclass(frozen=True)
class MonoHeldout:
    """The held-out error over ``folds`` folds (px per corner): over the inlier views' corners (``heldout_px``,
    the verdict's figure) and over all (``heldout_all_px``); ``corners_rejected`` of ``corners_total`` left out
    by the training solve's view rule; per fold; fx, fy, cx, cy with both standard deviations; the folds'
    intrinsics (K, D) (for the projection uncertainty)."""

    folds: int
    heldout_px: float
    heldout_all_px: float
    corners_rejected: int
    corners_total: int
    folds_px: tuple[float, ...]
    stds: tuple[ParameterStd, ...]
    failed: tuple[str, ...] = ()
    fold_intrinsics: tuple[tuple[FloatArray, FloatArray], ...] = ()

    def std(self, name: str) -> ParameterStd:
        """The entry of one of ``MONO_PARAMETERS``."""
        return next(s for s in self.stds if s.name == name)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"folds": self.folds, "heldout_px": self.heldout_px, "heldout_all_px": self.heldout_all_px,
                "corners_rejected": self.corners_rejected, "corners_total": self.corners_total,
                "folds_px": list(self.folds_px), "failed_folds": list(self.failed),
                "parameters": {s.name: s.as_dict() for s in self.stds}}


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
                 side: Callable[[], T] | None = None, lens: str = "pinhole", corner_factor: float | None = None
                 ) -> tuple[MonoHeldout | None, T | None]:
    """The held-out error and both std devs of the solved camera ``sol`` (its used views ``obj``/``img``), and
    ``side()`` (e.g. the lens-model comparison) run in this process while the folds run in the pool. None (and
    ``side()``) when there are too few views for two folds. ``lens``: ``pinhole`` or ``fisheye``;
    ``corner_factor``: the solve's single-corner rule (see :mod:`s2r.calib.solve.mono_fold`)."""
    groups = split_folds(len(img), folds)
    if not groups:
        return None, None if side is None else side()
    tasks = []
    for test in groups:
        held = set(test)
        train = [i for i in range(len(img)) if i not in held]
        tasks.append(MonoFoldTask(tuple(obj[i] for i in train), tuple(img[i] for i in train),
                                  tuple(obj[i] for i in test), tuple(img[i] for i in test), sol.K, sol.D,
                                  distortion, size, max_error_px, lens, corner_factor))
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
                           tuple(o.failed for o in outcomes if o.failed),
                           tuple((o.K, o.D) for o in good if o.K is not None and o.D is not None))
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
