"""Which lens model fits: held-out reprojection error of each candidate model (leave-views-out).

The used views are split into ``folds`` interleaved groups. For each fold and camera, OpenCV's
``calibrateCamera`` (the model's flags) solves the other views; each held-out view's board pose is then
fitted alone (``solvePnP`` with those intrinsics, then refined) and its corners' reprojection error
measured. Each training solve starts from the full solution's intrinsics (``guess``, the joint solve's K
and D with the terms the model does not free set to zero; CALIB_USE_INTRINSIC_GUESS) with a loose stopping
rule, and the solves run in a thread pool (OpenCV releases the GIL), so the comparison costs about as much
as one calibration instead of dozens. A model that explains the training views by fitting noise (too many
terms) or misses real distortion (too few) shows a larger held-out error. Nothing is switched: the chosen
model is marked and a warning names a model that is clearly better (held-out RMS more than 5 % lower, and
lower in all folds but at most one).

Units: pixels (RMS over the held-out corners of both cameras, both coordinates).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.lens.models import LENS_MODELS

__all__ = ["ModelComparison", "ModelScore", "compare_models", "judge_models"]

Corners = NDArray[np.float32]
#: Most views used for the comparison (evenly spaced), to bound its time: 12 views in 4 folds, each model
#: trained on 9 views per fold. Measured on the real OpenCV set: held-out RMS 0.2276 / 0.2332 / 0.2272 / 0.2280 px
#: (k1k2p1p2 / k1k2 / plumb_bob / rational) against 0.2229 / 0.2282 / 0.2223 / 0.2237 with 20 views, the same
#: order; on the 40-pair 1280x720 bench set the comparison costs about 0.4 s less, which is what brings the
#: whole first run level with the plain OpenCV loop.
MAX_CV_VIEWS = 12
CLEARLY_BETTER = 0.95
#: Stopping rule of the warm-started training solves (iterations, parameter change).
_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-7)
Guess = tuple[NDArray[np.float64], NDArray[np.float64]]


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


def _start(guess: Guess | None, model: str) -> tuple[NDArray[np.float64] | None, NDArray[np.float64], int]:
    """Starting K, D (the model's coefficient count; terms it keeps fixed are zero) and extra flags.

    A rational guess (8 terms) gives only K to the polynomial models: its k1..k3 are tied to the denominator
    (they reach tens while numerator and denominator cancel) and would start them far off."""
    lens = LENS_MODELS[model]
    D = np.zeros(lens.n_coef)
    if guess is None:
        return None, D, 0
    src = np.asarray(guess[1], np.float64).reshape(-1)
    if len(src) <= len(D):
        for i in lens.free:
            if i < len(src):
                D[i] = src[i]
    return np.array(guess[0], np.float64), D.reshape(1, -1), cv2.CALIB_USE_INTRINSIC_GUESS


def _heldout_sq(obj: Corners, train: Sequence[Corners], test: Sequence[Corners], size: tuple[int, int],
                model: str, guess: Guess | None) -> NDArray[np.float64]:
    """Squared corner errors (px^2, one per corner) of the held-out views of one camera (inf when the model
    cannot be solved or a held-out pose not fitted); a failed warm start is retried from scratch."""
    K0, D0, extra = _start(guess, model)
    try:
        _, K, D, _, _ = cv2.calibrateCamera([obj] * len(train), [t.reshape(-1, 1, 2) for t in train], size, K0,
                                            D0, flags=LENS_MODELS[model].cv_flags | extra, criteria=_CRITERIA)
        return _test_errors(obj, test, np.asarray(K, np.float64), np.asarray(D, np.float64))
    except cv2.error:
        if guess is None:
            return np.array([np.inf])
    return _heldout_sq(obj, train, test, size, model, None)


def _test_errors(obj: Corners, test: Sequence[Corners], K: NDArray[np.float64], D: NDArray[np.float64]
                 ) -> NDArray[np.float64]:
    """Squared corner errors (px^2) of views each fitted alone (solvePnP + LM refinement) with fixed K, D."""
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D))):
        raise cv2.error("non-finite calibration")
    out = []
    for pts in test:
        ok, rv, tv = cv2.solvePnP(obj, pts.reshape(-1, 1, 2), K, D)
        if not ok:
            return np.array([np.inf])
        rv, tv = cv2.solvePnPRefineLM(obj, pts.reshape(-1, 1, 2), K, D, rv, tv)
        proj = cv2.projectPoints(obj, rv, tv, K, D)[0].reshape(-1, 2)
        out.append(np.sum((proj - pts.reshape(-1, 2)) ** 2, axis=1))
    return np.concatenate(out)


def compare_models(left: Sequence[Corners], right: Sequence[Corners] | None, obj: Corners, size: tuple[int, int], *,
                   chosen: str, folds: int = 5, models: Sequence[str] = tuple(LENS_MODELS),
                   guess: tuple[Guess, Guess] | None = None, threads: int | None = None) -> ModelComparison:
    """Held-out RMS of each model over ``folds`` leave-views-out folds of the views ``left[i]``/``right[i]``.

    ``right`` None: one camera (``--mono``). ``guess``: the left and right camera's (K, D) from the full
    solve, to start each training solve from; ``threads``: parallel solves (default: the cores, at most 4).
    """
    cams = [left] if right is None else [left, right]
    n = len(left)
    idx = np.linspace(0, n - 1, min(n, MAX_CV_VIEWS)).round().astype(int)
    idx = np.unique(idx)
    k = max(2, min(folds, len(idx) // 3))
    groups = [idx[f::k] for f in range(k)]
    jobs = [(name, f, c) for name in models for f in range(k) for c in range(len(cams))]

    def run(job: tuple[str, int, int]) -> NDArray[np.float64]:
        name, f, c = job
        cam = cams[c]
        held = set(groups[f].tolist())
        train = [cam[i] for i in idx if i not in held]
        return _heldout_sq(obj, train, [cam[i] for i in groups[f]], size, name, None if guess is None else guess[c])

    with ThreadPoolExecutor(max_workers=threads or min(4, os.cpu_count() or 1)) as pool:
        results = dict(zip(jobs, pool.map(run, jobs), strict=True))
    scores = []
    for name in models:
        per_fold, all_sq = [], []
        for f in range(k):
            sq = np.concatenate([results[(name, f, c)] for c in range(len(cams))])
            per_fold.append(float(np.sqrt(np.mean(sq))))
            all_sq.append(sq)
        scores.append(ModelScore(name, float(np.sqrt(np.mean(np.concatenate(all_sq)))), tuple(per_fold),
                                 name == chosen))
    return judge_models(scores, chosen, "held-out views")


def judge_models(scores: Sequence[ModelScore], chosen: str, evidence: str) -> ModelComparison:
    """The best of ``scores`` (each model's held-out error on the same folds) and a warning when it is clearly
    better than the ``chosen`` model: below :data:`CLEARLY_BETTER` times its error and lower in all folds but at
    most one. ``evidence`` names what was held out (``held-out views``, ``stereo held-out pairs``)."""
    best = min(scores, key=lambda s: s.heldout_px)
    mine = next((s for s in scores if s.chosen), None)
    warning = None
    if mine is not None and best is not mine and best.heldout_px < CLEARLY_BETTER * mine.heldout_px:
        wins = sum(b < c for b, c in zip(best.folds_px, mine.folds_px, strict=True))
        if wins >= len(best.folds_px) - 1:
            warning = (f"{evidence} favour --distortion {best.model}: {best.heldout_px:.3f} px against "
                       f"{mine.heldout_px:.3f} px for {chosen} (lower in {wins} of {len(best.folds_px)} folds); "
                       f"consider rerunning with --distortion {best.model}")
    return ModelComparison(tuple(scores), best.model, warning)
