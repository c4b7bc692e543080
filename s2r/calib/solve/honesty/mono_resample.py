"""Resampling over views for one camera (``--mono``, ``--target --mono``, fisheye): a held-out error and
jackknife standard deviations.

The used views are split into ``K`` interleaved folds (view i in fold ``i mod K``, as the stereo path:
:func:`s2r.calib.solve.honesty.resample.split_folds`). Each fold (:mod:`s2r.calib.solve.honesty.mono_fold`) solves
the other views, warm-started from the full solution with a loose stopping rule and the full solve's outlier rules.
Then:

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

import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.honesty.heldout import HeldoutFigures, ParameterStd
from s2r.calib.solve.honesty.models import ModelComparison, ModelScore, judge_models
from s2r.calib.solve.honesty.mono_fold import MonoFoldOutcome, MonoFoldTask, run_mono_fold
from s2r.calib.solve.honesty.resample import FOLDS, split_folds
from s2r.calib.solve.solvers.cvsolve import MonoSolution
from s2r.executor import local_pool
from s2r.lens.models import LENS_MODELS

__all__ = ["MONO_PARAMETERS", "MonoHeldout", "jackknife", "mono_heldout", "reported_std"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]
#: Parameters whose jackknife std is reported, in this order (px).
MONO_PARAMETERS = ("fx", "fy", "cx", "cy")
#: Most views (evenly spaced) on which the lens models are compared (as the stereo path): the comparison needs
#: the models' relative held-out errors, and this bounds its cost; the chosen model's figures use every view.
MAX_COMPARE_VIEWS = 16


@dataclass(frozen=True)
class MonoHeldout(HeldoutFigures):
    """One camera's held-out error (:class:`s2r.calib.solve.honesty.heldout.HeldoutFigures`; corners left out by the
    training solve's view rule; parameters ``MONO_PARAMETERS``) and the folds' intrinsics (K, D) (for the
    projection uncertainty)."""

    fold_intrinsics: tuple[tuple[FloatArray, FloatArray], ...] = ()


def _run(tasks: Sequence[MonoFoldTask], jobs: int) -> list[MonoFoldOutcome]:
    """Every task over ``jobs`` processes of s2r's pool (in this process when 1)."""
    if jobs <= 1 or len(tasks) <= 1:
        return [run_mono_fold(t) for t in tasks]
    pool = local_pool(min(jobs, len(tasks)))
    try:
        return list(pool.map(run_mono_fold, tasks))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _start(D: FloatArray, model: str) -> FloatArray:
    """The chosen model's coefficients as a start for ``model``: the terms ``model`` frees, the others 0 (a
    rational start gives none to a polynomial model: its k1..k3 are tied to the denominator)."""
    lens = LENS_MODELS[model]
    out = np.zeros(lens.n_coef)
    src = np.asarray(D, np.float64).reshape(-1)
    if len(src) <= lens.n_coef:
        for i in lens.free:
            if i < len(src):
                out[i] = src[i]
    return out


def _tasks(obj: Sequence[Points], img: Sequence[Points], idx: Sequence[int], folds: int,
           fold_task: Callable[[Sequence[int], list[int]], MonoFoldTask]) -> list[MonoFoldTask]:
    """One task per fold over the views ``idx`` (interleaved): ``fold_task(train, test)`` of view indices."""
    out = []
    for test in split_folds(len(idx), folds):
        held = [idx[k] for k in test]
        out.append(fold_task([i for i in idx if i not in set(held)], held))
    return out


def _comparison(scored: dict[str, Sequence[MonoFoldOutcome]], chosen: str) -> ModelComparison:
    """Each model's held-out error on the same folds, the best one, and a warning when it is clearly better."""
    scores = []
    for name, outs in scored.items():
        ok = all(not o.failed for o in outs)
        scores.append(ModelScore(name, _rms([o.sq_inlier for o in outs]) if ok else float("inf"),
                                 tuple(_rms([o.sq_inlier]) if not o.failed else float("inf") for o in outs),
                                 name == chosen))
    return judge_models(scores, chosen, "held-out views")


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
                 compare: Sequence[str] = (), lens: str = "pinhole", corner_factor: float | None = None
                 ) -> tuple[MonoHeldout | None, ModelComparison | None]:
    """The held-out error and both std devs of the solved camera ``sol`` (its used views ``obj``/``img``), and
    the lens models of ``compare`` scored on the same folds (on at most ``MAX_COMPARE_VIEWS`` evenly spaced
    views, every model on the same ones; None without another model). None, None when there are too few views
    for two folds. ``lens``: ``pinhole`` or ``fisheye``; ``corner_factor``: the solve's single-corner rule (see
    :mod:`s2r.calib.solve.honesty.mono_fold`)."""
    n = len(img)
    if not split_folds(n, folds):
        return None, None

    def for_model(model: str) -> Callable[[Sequence[int], list[int]], MonoFoldTask]:
        D = sol.D if model == distortion else _start(sol.D, model)  # another model: its terms of the solution

        def fold_task(train: Sequence[int], test: list[int]) -> MonoFoldTask:
            return MonoFoldTask(tuple(obj[i] for i in train), tuple(img[i] for i in train),
                                tuple(obj[i] for i in test), tuple(img[i] for i in test), sol.K, D, model, size,
                                max_error_px, lens, corner_factor)
        return fold_task

    tasks = _tasks(obj, img, range(n), folds, for_model(distortion))
    k = len(tasks)
    others = [m for m in compare if m != distortion and m in LENS_MODELS] if lens == "pinhole" else []
    sub = [int(v) for v in np.unique(np.linspace(0, n - 1, min(n, MAX_COMPARE_VIEWS)).round())]
    small = len(sub) < n and bool(others)
    for m in ([distortion] if small else []) + others:
        tasks += _tasks(obj, img, sub, folds, for_model(m))
    outcomes = _run(tasks, jobs)
    mine, rest = outcomes[:k], outcomes[k:]
    good = [o for o in mine if not o.failed]
    jk = jackknife(mine)
    values = (sol.K[0, 0], sol.K[1, 1], sol.K[0, 2], sol.K[1, 2])
    stds = tuple(ParameterStd(name, float(v), _finite(float(c)), _finite(float(j)))
                 for name, v, c, j in zip(MONO_PARAMETERS, values, sol.std[:4], jk, strict=True))
    n_in, n_all = sum(o.sq_inlier.size for o in good), sum(o.sq_all.size for o in good)
    held_out = MonoHeldout(k, _rms([o.sq_inlier for o in good]), _rms([o.sq_all for o in good]), n_all - n_in,
                           n_all, tuple(_rms([o.sq_inlier]) for o in good), stds,
                           tuple(o.failed for o in mine if o.failed),
                           tuple((o.K, o.D) for o in good if o.K is not None and o.D is not None))
    if not others:
        return held_out, None
    ks = len(rest) // (len(others) + small)
    names = ([distortion] if small else []) + others
    scored = {m: rest[ks * i:ks * (i + 1)] for i, m in enumerate(names)}
    if not small:
        scored[distortion] = mine
    return held_out, _comparison({m: scored[m] for m in LENS_MODELS if m in scored}, distortion)


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
