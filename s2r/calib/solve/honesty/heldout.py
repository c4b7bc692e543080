"""The honest figures of a stereo calibration: stereo held-out error, both standard deviations, model check.

Built on the fold solves of :mod:`s2r.calib.solve.honesty.resample` (K interleaved folds over the used pairs). Every
parameter of ``PARAMETERS`` gets two standard deviations: the residual-scaled covariance of the full solve and
the jackknife over the folds. The larger is reported (and written to the profile), and the figures say which
it is: on real sets the jackknife is often 2-5x the covariance (board shape, lens model), while on a clean
synthetic rig both agree. The lens models are compared on the same folds by their stereo held-out error.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.honesty.models import ModelComparison, ModelScore, judge_models
from s2r.calib.solve.honesty.resample import (
    PARAMETERS,
    FoldOutcome,
    FoldTask,
    jackknife_std,
    run_folds,
    split_folds,
    trim_blunders,
)
from s2r.calib.solve.solvers.joint import JointInit
from s2r.calib.solve.solvers.observations import StereoObservation, chessboard_observation
from s2r.calib.solve.solvers.pair import PairSolution
from s2r.lens.models import LENS_MODELS, LensModel

__all__ = ["BEND_SIGMAS", "MAX_BLUNDER_SHARE", "HeldoutFigures", "ParameterStd", "StereoHeldout", "bend_significant",
           "observations_heldout", "stereo_heldout"]

FloatArray = NDArray[np.float64]
Corners = NDArray[np.float32]
#: Most pairs (evenly spaced) on which the lens models are compared: the comparison needs the models' relative
#: held-out errors, not every pair, and this bounds its cost (the chosen model's held-out error and jackknife
#: use every pair).
MAX_COMPARE_VIEWS = 16
#: A board bend within this many (covariance) std of flat on both axes is not tested on held-out pairs: it
#: cannot lower the held-out error by more than the noise, and the test costs four more fold solves.
BEND_SIGMAS = 2.0
#: Detector blunders are rare (0-1 % of the held-out corners on six real sets, 2.3 % at most): when more than
#: this share of the held-out corners falls beyond the blunder threshold, the model misfits them (8.6 % on an
#: ill-posed real set, where the trimmed figure read 60 % under the all-corner one), so the verdict judges the
#: held-out error over all corners and a warning says why.
MAX_BLUNDER_SHARE = 0.05


@dataclass(frozen=True)
class ParameterStd:
    """One parameter's value and both standard deviations (px; baseline in m; rotation in degrees; None when
    unknown); ``reported`` is the larger, ``source`` names it (``covariance`` or ``jackknife``)."""

    name: str
    value: float
    covariance: float | None
    jackknife: float | None

    @property
    def reported(self) -> float | None:
        """The larger of the two (the one known when only one is)."""
        known = [v for v in (self.covariance, self.jackknife) if v is not None]
        return max(known) if known else None

    @property
    def source(self) -> str:
        """Which standard deviation is reported."""
        if self.jackknife is not None and (self.covariance is None or self.jackknife > self.covariance):
            return "jackknife"
        return "covariance" if self.covariance is not None else "none"

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"value": self.value, "std_covariance": self.covariance, "std_jackknife": self.jackknife,
                "std": self.reported, "std_source": self.source}


@dataclass(frozen=True)
class HeldoutFigures:
    """The held-out error over ``folds`` folds (px, per corner, both coordinates): over the corners kept
    (``heldout_px``, the verdict's figure) and over all (``heldout_all_px``); ``corners_rejected`` of
    ``corners_total`` left out; per fold; and the standard deviations of the parameters."""

    folds: int
    heldout_px: float
    heldout_all_px: float
    corners_rejected: int
    corners_total: int
    folds_px: tuple[float, ...]
    stds: tuple[ParameterStd, ...]
    failed: tuple[str, ...] = ()

    def std(self, name: str) -> ParameterStd:
        """The entry of parameter ``name``."""
        return next(s for s in self.stds if s.name == name)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"folds": self.folds, "heldout_px": self.heldout_px, "heldout_all_px": self.heldout_all_px,
                "corners_rejected": self.corners_rejected, "corners_total": self.corners_total,
                "folds_px": list(self.folds_px), "failed_folds": list(self.failed),
                "parameters": {s.name: s.as_dict() for s in self.stds}}


@dataclass(frozen=True)
class StereoHeldout(HeldoutFigures):
    """The stereo held-out error (:class:`HeldoutFigures`; corners left out as detector blunders, see
    :func:`s2r.calib.solve.honesty.resample.trim_blunders`; parameters ``PARAMETERS``) and per camera the folds'
    intrinsics (K, D) (for the projection uncertainty)."""

    fold_intrinsics: tuple[tuple[tuple[FloatArray, FloatArray], ...], ...] = ()

    @property
    def blunder_share(self) -> float:
        """The share of the held-out corners left out as detector blunders (0..1)."""
        return self.corners_rejected / self.corners_total if self.corners_total else 0.0

    @property
    def judged_over_all(self) -> bool:
        """Whether the verdict judges the all-corner figure (more than :data:`MAX_BLUNDER_SHARE` left out)."""
        return self.blunder_share > MAX_BLUNDER_SHARE

    @property
    def verdict_px(self) -> float:
        """The held-out error the verdict judges (px): ``heldout_px``, or ``heldout_all_px`` when
        :attr:`judged_over_all` (see :meth:`blunder_warning`)."""
        return self.heldout_all_px if self.judged_over_all else self.heldout_px

    def blunder_warning(self) -> list[str]:
        """One line when more held-out corners were left out than detector blunders explain."""
        if not self.judged_over_all:
            return []
        return [f"{self.corners_rejected} of {self.corners_total} held-out corners ({100 * self.blunder_share:.1f} %) "
                f"lie beyond the detector-blunder threshold: more than a detector misplaces, so the model misfits "
                f"them; the verdict judges the held-out error over all corners ({self.heldout_all_px:.3f} px, "
                f"{self.heldout_px:.3f} px without them)"]


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _tasks(obs: Sequence[StereoObservation], sol: PairSolution, lens: LensModel, folds: list[list[int]],
           max_error_px: float | None, *, score_only: bool = False) -> list[FoldTask]:
    n = lens.n_coef

    def fit(d: FloatArray) -> FloatArray:
        out = np.zeros(n)
        src = np.asarray(d, np.float64).reshape(-1)
        out[:min(n, len(src))] = src[:n]
        return out

    tasks = []
    for test in folds:
        train = [i for i in range(len(obs)) if i not in set(test)]
        init = JointInit(sol.K1, fit(sol.D1), sol.K2, fit(sol.D2), sol.R, sol.T,
                         [sol.rvecs[i] for i in train], [sol.tvecs[i] for i in train], warp=sol.warp_m)
        tasks.append(FoldTask(lens, tuple(obs[i] for i in train), tuple(obs[i] for i in test), init,
                              tuple(sol.rvecs[i] for i in test), tuple(sol.tvecs[i] for i in test), max_error_px,
                              warp=sol.warp_m is not None,
                              masks=[list(sol.inliers[i]) for i in train] if sol.inliers else None,
                              score_only=score_only))
    return tasks


def _rms(parts: Sequence[FloatArray]) -> float:
    sq = np.concatenate(parts) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(sq))) if sq.size else float("nan")


def _summary(outcomes: Sequence[FoldOutcome], sol: PairSolution) -> StereoHeldout:
    outcomes = trim_blunders(outcomes)
    good = [o for o in outcomes if not o.failed]
    jk = jackknife_std(outcomes, sol.R)
    values = [sol.K1[0, 0], sol.K1[1, 1], sol.K1[0, 2], sol.K1[1, 2], sol.K2[0, 0], sol.K2[1, 1], sol.K2[0, 2],
              sol.K2[1, 2], float(np.linalg.norm(sol.T)),
              float(np.degrees(np.linalg.norm(np.asarray(_rotvec(sol.R)))))]
    cov = [*sol.std_left[:4], *sol.std_right[:4], sol.baseline_std_m, sol.rotation_std_deg]
    stds = tuple(ParameterStd(name, float(v), _finite(float(c)), _finite(float(j)))
                 for name, v, c, j in zip(PARAMETERS, values, cov, jk, strict=True))
    n_in = sum(o.sq_inlier.size for o in good)
    n_all = sum(o.sq_all.size for o in good)
    intr = (tuple((o.K1, o.D1) for o in good if o.D1 is not None),
            tuple((o.K2, o.D2) for o in good if o.D2 is not None))
    return StereoHeldout(len(outcomes), _rms([o.sq_inlier for o in good]), _rms([o.sq_all for o in good]),
                         n_all - n_in, n_all, tuple(_rms([o.sq_inlier]) for o in good), stds,
                         tuple(o.failed for o in outcomes if o.failed), intr)


def _rotvec(R: FloatArray) -> FloatArray:
    return np.asarray(cv2.Rodrigues(np.asarray(R, np.float64))[0], np.float64).reshape(3)


def _comparison(scored: dict[str, Sequence[FoldOutcome]], chosen: str) -> ModelComparison:
    scores = []
    for name, every in scored.items():
        outs = trim_blunders(every)
        folds_px = tuple(_rms([o.sq_inlier]) if not o.failed else float("inf") for o in outs)
        total = _rms([o.sq_inlier for o in outs if not o.failed]) if all(not o.failed for o in outs) else float("inf")
        scores.append(ModelScore(name, total, folds_px, name == chosen))
    return judge_models(scores, chosen, "stereo held-out pairs")


def _observations(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners], obj: Corners
                  ) -> list[StereoObservation]:
    return [StereoObservation(n, chessboard_observation(obj, a), chessboard_observation(obj, b))
            for n, a, b in zip(names, left, right, strict=True)]


def stereo_heldout(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners], obj: Corners,
                   sol: PairSolution, *, lens: LensModel, compare: Sequence[str] = tuple(LENS_MODELS),
                   max_error_px: float | None = None, jobs: int = 1,
                   warp_solve: Callable[[], PairSolution] | None = None
                   ) -> tuple[StereoHeldout | None, ModelComparison | None, StereoHeldout | None, PairSolution | None]:
    """Held-out error and both std devs of the solved pair ``sol`` (its used views ``left``/``right``, in the
    order of ``sol.rvecs``), the lens models of ``compare`` scored on the same folds (None without one
    other model; on at most ``MAX_COMPARE_VIEWS`` evenly spaced pairs, every model on the same ones), and the
    same figures with the board's bend solved, and that solve (``warp_solve``, run in the pool beside the folds;
    its folds start from ``sol`` with a flat board, and run only when :func:`bend_significant`; else the third
    item is None) when given. All None when there are too few views for two folds."""
    obs = _observations(names, left, right, obj)
    folds = split_folds(len(obs))
    if not folds:
        return None, None, None, None
    others = [m for m in compare if m != lens.name and m in LENS_MODELS]
    tasks = _tasks(obs, sol, lens, folds, max_error_px)
    sub = np.unique(np.linspace(0, len(obs) - 1, min(len(obs), MAX_COMPARE_VIEWS)).round().astype(int))
    small = len(sub) < len(obs) and bool(others)
    sub_sol, sub_obs = (_subset(sol, sub), [obs[i] for i in sub]) if small else (sol, obs)
    sub_folds = split_folds(len(sub_obs)) if small else folds
    for m in ([lens.name] if small else []) + others:
        tasks += _tasks(sub_obs, sub_sol, LENS_MODELS[m], sub_folds, max_error_px, score_only=True)
    flat = replace(sol, warp_m=np.zeros(2))

    def warp_tasks(warped: PairSolution | None) -> list[FoldTask]:
        return _tasks(obs, flat, lens, folds, max_error_px) if warped is not None and bend_significant(warped) else []

    outcomes, warped, w_outcomes = run_folds(tasks, jobs=jobs, side=warp_solve, then=warp_tasks)
    k = len(folds)
    result = _summary(outcomes[:k], sol)
    w_result = _summary(w_outcomes, warped) if warped is not None and w_outcomes else None
    if not others or not sub_folds:
        return result, None, w_result, warped
    rest = outcomes[k:] if small else outcomes  # the chosen model's own folds double as its score
    ks = len(sub_folds)
    scored = {m: rest[ks * i:ks * (i + 1)] for i, m in enumerate([lens.name, *others])}
    order = [m for m in LENS_MODELS if m in scored]
    return result, _comparison({m: scored[m] for m in order}, lens.name), w_result, warped


def observations_heldout(obs: Sequence[StereoObservation], sol: PairSolution, lens: LensModel, *,
                         max_error_px: float | None, jobs: int) -> StereoHeldout | None:
    """Held-out error and both std devs of the joint solve ``sol`` of ``obs`` (its used views, in the order of
    its board poses; any corner layout, e.g. a ``--target`` matched by corner id), with no lens-model
    comparison; None with too few views for two folds."""
    folds = split_folds(len(obs))
    if not folds:
        return None
    outcomes, _, _ = run_folds(_tasks(obs, sol, lens, folds, max_error_px), jobs=jobs)
    return _summary(outcomes, sol)


def bend_significant(warped: PairSolution, k: float = BEND_SIGMAS) -> bool:
    """Whether the solved board bend differs from flat by more than ``k`` of its (covariance) std on either
    axis (or its std is unknown): only then is the bent board tested on held-out pairs."""
    if warped.warp_m is None:
        return False
    std = warped.warp_std_m if warped.warp_std_m is not None else np.full(2, np.nan)
    return bool(np.any(~np.isfinite(std)) or np.any(np.abs(warped.warp_m) > k * std))


def _subset(sol: PairSolution, idx: NDArray[np.int_]) -> PairSolution:
    """``sol`` with only the board poses of views ``idx`` (the warm start of the lens-model comparison)."""
    return replace(sol, rvecs=tuple(sol.rvecs[i] for i in idx), tvecs=tuple(sol.tvecs[i] for i in idx),
                   inliers=tuple(sol.inliers[i] for i in idx) if sol.inliers else ())
