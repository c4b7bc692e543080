"""The honest figures of the corner-id paths (``--target``, ``--lens fisheye``): repeated views merged, and
for one camera the held-out error with the jackknife std beside the covariance's.

- **Repeats**: a view whose corners (the same ids) lie within :data:`s2r.calib.solve.views.REPEAT_PX` (median)
  of an earlier view's (in each camera that saw the board) is a board held still; it is merged into that view
  so the standard deviations count each board pose once.
- **One camera**: :func:`s2r.calib.solve.honesty.mono_resample.mono_heldout` over the solved views (partial views,
  either lens), the training solve's corner rule applied to held-out corners where the solve drops corners.
- **A pair (joint solve)**: the stereo path's folds (:mod:`s2r.calib.solve.honesty.resample`: joint solve of the
  training views warm-started from the full one; one board pose per held-out view fitted to both cameras) on
  the views matched by corner id, with the jackknife std of every parameter of ``PARAMETERS`` beside the
  covariance's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from s2r.calib.solve.honesty.heldout import StereoHeldout, observations_heldout
from s2r.calib.solve.honesty.mono_resample import MonoHeldout, mono_heldout, reported_std
from s2r.calib.solve.solvers.observations import StereoObservation
from s2r.calib.solve.solvers.pair import PairSolution
from s2r.calib.solve.solvers.targetcal import CORNER_OUTLIER_FACTOR, MonoFit, Observation
from s2r.calib.solve.views import REPEAT_PX, repeat_distance, repeat_of
from s2r.lens.models import LensModel
from s2r.profile import DroppedView

__all__ = ["merge_repeat_observations", "merge_repeat_pairs", "mono_fit_heldout", "pair_heldout"]


def _distance(a: Observation | None, b: Observation | None) -> float:
    """Median corner distance (px) of two views of the same corner ids; inf when they differ (0 when both None)."""
    if a is None or b is None:
        return 0.0 if a is None and b is None else float("inf")
    if a.ids.shape != b.ids.shape or not np.array_equal(a.ids, b.ids):
        return float("inf")
    return repeat_distance(a.img, b.img)


def merge_repeat_pairs(names: Sequence[str], left: Sequence[Observation | None],
                       right: Sequence[Observation | None], *, tol_px: float = REPEAT_PX
                       ) -> tuple[list[int], list[DroppedView]]:
    """Indices of the views to keep (the first of each group of near-identical views; a view no camera saw is
    kept for its own reason) and a DroppedView per repeat naming the view it repeats."""
    keep: list[int] = []
    repeats: list[DroppedView] = []
    for i in range(len(names)):
        if left[i] is not None or right[i] is not None:
            dist = [max(_distance(left[i], left[k]), _distance(right[i], right[k])) for k in keep]
            j = int(np.argmin(dist)) if dist else -1
            if j >= 0 and dist[j] < tol_px:
                repeats.append(repeat_of(names[i], names[keep[j]], dist[j]))
                continue
        keep.append(i)
    return keep, repeats


def merge_repeat_observations(views: Sequence[Observation]) -> tuple[list[Observation], list[DroppedView]]:
    """One camera's views without repeats of an earlier view, and a DroppedView per repeat."""
    keep, repeats = merge_repeat_pairs([v.name for v in views], views, [None] * len(views))
    return [views[i] for i in keep], repeats


def mono_fit_heldout(fit: MonoFit, size: tuple[int, int], *, lens: str, distortion: str,
                     max_error_px: float | None, jobs: int, prune_corners: bool
                     ) -> tuple[MonoFit, MonoHeldout | None]:
    """The held-out error and jackknife of a camera's fit (its kept views), and the fit with fx, fy, cx, cy's
    std replaced by the larger of covariance and jackknife."""
    used = [fit.views[i] for i in fit.keep]
    held, _ = mono_heldout([v.obj for v in used], [v.img for v in used], fit.solution, size, distortion=distortion,
                           max_error_px=max_error_px, jobs=jobs, lens=lens,
                           corner_factor=CORNER_OUTLIER_FACTOR if prune_corners else None)
    if held is None:
        return fit, None
    return replace(fit, solution=replace(fit.solution, std=reported_std(fit.solution.std, held))), held


def pair_heldout(joint_obs: Sequence[StereoObservation], sol: PairSolution, lens: LensModel, *,
                 max_error_px: float | None, jobs: int) -> StereoHeldout | None:
    """The stereo held-out error and both std devs of a joint solve ``sol`` of ``joint_obs`` (its used views
    ``sol.keep``, in the order of its board poses); None with too few views for two folds."""
    return observations_heldout([joint_obs[i] for i in sol.keep], sol, lens, max_error_px=max_error_px, jobs=jobs)
