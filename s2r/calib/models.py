"""Which lens model fits: held-out reprojection error of each candidate model (leave-views-out).

The used views are split into ``folds`` interleaved groups. For each fold and camera, OpenCV's
``calibrateCamera`` (the model's flags) solves the other views; each held-out view's board pose is then
fitted alone (``solvePnP`` with those intrinsics, then refined) and its corners' reprojection error
measured. A model that explains the training views by fitting noise (too many terms) or misses real
distortion (too few) shows a larger held-out error. Nothing is switched: the chosen model is marked and a
warning names a model that is clearly better (held-out RMS more than 5 % lower, and lower in all folds
but at most one).

Units: pixels (RMS over the held-out corners of both cameras, both coordinates).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.lens import LENS_MODELS

__all__ = ["ModelComparison", "ModelScore", "compare_models"]

Corners = NDArray[np.float32]
#: Most views used for the comparison (evenly spaced), to bound its time on long recordings.
MAX_CV_VIEWS = 40
CLEARLY_BETTER = 0.95


@dataclass(frozen=True)
class ModelScore:
    """One model: held-out RMS (px) overall and per fold, and whether it is the model used."""

    model: str
    heldout_px: float
    folds_px: tuple[float, ...]
    chosen: bool


@dataclass(frozen=True)
class ModelComparison:
    """Every candidate's score (chosen one marked), the best model and a warning when it is clearly better."""

    scores: tuple[ModelScore, ...]
    best: str
    warning: str | None

    def as_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"models": [vars(s) for s in self.scores], "best": self.best, "warning": self.warning}


def _heldout_sq(obj: Corners, train: Sequence[Corners], test: Sequence[Corners], size: tuple[int, int],
                flags: int, n_coef: int) -> NDArray[np.float64]:
    """Squared corner errors (px^2, one per corner) of the held-out views of one camera."""
    try:
        _, K, D, _, _ = cv2.calibrateCamera([obj] * len(train), [t.reshape(-1, 1, 2) for t in train], size, None,
                                            np.zeros(n_coef), flags=flags)
    except cv2.error:
        return np.array([np.inf])
    out = []
    for pts in test:
        ok, rv, tv = cv2.solvePnP(obj, pts.reshape(-1, 1, 2), K, D)
        if not ok:
            return np.array([np.inf])
        rv, tv = cv2.solvePnPRefineLM(obj, pts.reshape(-1, 1, 2), K, D, rv, tv)
        proj = cv2.projectPoints(obj, rv, tv, K, D)[0].reshape(-1, 2)
        out.append(np.sum((proj - pts.reshape(-1, 2)) ** 2, axis=1))
    return np.concatenate(out)


def compare_models(left: Sequence[Corners], right: Sequence[Corners], obj: Corners, size: tuple[int, int], *,
                   chosen: str, folds: int = 5, models: Sequence[str] = tuple(LENS_MODELS)) -> ModelComparison:
    """Held-out RMS of each model over ``folds`` leave-views-out folds of the views ``left[i]``/``right[i]``."""
    n = len(left)
    idx = np.linspace(0, n - 1, min(n, MAX_CV_VIEWS)).round().astype(int)
    idx = np.unique(idx)
    k = max(2, min(folds, len(idx) // 3))
    groups = [idx[f::k] for f in range(k)]
    scores = []
    for name in models:
        lens = LENS_MODELS[name]
        per_fold, all_sq = [], []
        for g in groups:
            train = [i for i in idx if i not in set(g.tolist())]
            sq = np.concatenate([
                _heldout_sq(obj, [cam[i] for i in train], [cam[i] for i in g], size, lens.cv_flags, lens.n_coef)
                for cam in (left, right)])
            per_fold.append(float(np.sqrt(np.mean(sq))))
            all_sq.append(sq)
        scores.append(ModelScore(name, float(np.sqrt(np.mean(np.concatenate(all_sq)))), tuple(per_fold),
                                 name == chosen))
    best = min(scores, key=lambda s: s.heldout_px)
    mine = next((s for s in scores if s.chosen), None)
    warning = None
    if mine is not None and best is not mine and best.heldout_px < CLEARLY_BETTER * mine.heldout_px:
        wins = sum(b < c for b, c in zip(best.folds_px, mine.folds_px, strict=True))
        if wins >= len(groups) - 1:
            warning = (f"held-out views favour --distortion {best.model}: {best.heldout_px:.3f} px against "
                       f"{mine.heldout_px:.3f} px for {chosen} (lower in {wins} of {len(groups)} folds); "
                       f"consider rerunning with --distortion {best.model}")
    return ModelComparison(tuple(scores), best.model, warning)
