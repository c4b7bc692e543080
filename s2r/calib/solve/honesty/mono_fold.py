"""One fold of the single-camera resampling (:mod:`s2r.calib.solve.honesty.mono_resample`): a worker function.

Training: the fold's views solved from the full solution's intrinsics (warm start, loose stopping rule;
pinhole: ``cv2.calibrateCameraExtended`` with CALIB_USE_INTRINSIC_GUESS, fisheye: ``cv2.fisheye.calibrate``
likewise; a failed warm start is retried from scratch), then the full solve's view rule (views above the
robust threshold of the first solve dropped, solved again). Held out: one board pose per view with the fold's
intrinsics fixed (``solvePnP`` then Levenberg-Marquardt on the pixel error), each corner's squared error.
A held-out view beyond the training threshold is left out of the inlier figure, as the training solve leaves
out its own; with ``corner_factor`` (boards identified corner by corner, whose solve drops single corners) so
is a held-out corner beyond ``corner_factor`` x the training corners' median error (at least 0.3 px).

Points: board points (N, 3) float32 metres, image points (N, 2) float32 px; K 3x3 px; D OpenCV order.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.cvsolve import DISTORTION_CHOICES, INIT_CRITERIA, outlier_threshold

__all__ = ["MonoFoldOutcome", "MonoFoldTask", "run_mono_fold"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]
_ROUNDS = 4
_CORNER_FLOOR_PX = 0.3
_FISHEYE_FLAGS = cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW


@dataclass(frozen=True)
class MonoFoldTask:
    """One fold: training and held-out views, the warm start (K, D), the ``--distortion`` choice (pinhole),
    the lens (``pinhole`` or ``fisheye``), the image size (w, h) px, the fixed view threshold
    (``--max-error``) and the corner rule's factor (None: whole views only)."""

    train_obj: tuple[Points, ...]
    train_img: tuple[Points, ...]
    test_obj: tuple[Points, ...]
    test_img: tuple[Points, ...]
    K: FloatArray
    D: FloatArray
    distortion: str
    size: tuple[int, int]
    max_error_px: float | None
    lens: str = "pinhole"
    corner_factor: float | None = None


@dataclass(frozen=True)
class MonoFoldOutcome:
    """A fold's training intrinsics (fx, fy, cx, cy px; and K, D) and its held-out corners' squared errors
    (px^2): ``sq_inlier`` of the corners the training rules keep, ``sq_all`` of every held-out corner;
    ``failed`` says why the fold has none."""

    params: FloatArray
    sq_inlier: FloatArray
    sq_all: FloatArray
    failed: str = ""
    K: FloatArray | None = None
    D: FloatArray | None = None


def _project(obj: Points, rv: FloatArray, tv: FloatArray, K: FloatArray, D: FloatArray, lens: str
             ) -> tuple[FloatArray, FloatArray]:
    """Pixels (N, 2) and the Jacobian (2N, 6) with respect to the pose (rvec, tvec)."""
    o = np.asarray(obj, np.float64).reshape(-1, 1, 3)
    if lens == "fisheye":
        pts, jac = cv2.fisheye.projectPoints(o, rv.reshape(3, 1), tv.reshape(3, 1), K, D.reshape(4, 1))
        return np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(jac, np.float64)[:, 8:14]
    pts, jac = cv2.projectPoints(o, rv.reshape(3, 1), tv.reshape(3, 1), K, D)
    return np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(jac, np.float64)[:, 0:6]


def _calibrate(obj: Sequence[Points], img: Sequence[Points], task: MonoFoldTask,
               start: tuple[FloatArray, FloatArray] | None) -> tuple[FloatArray, FloatArray, list[FloatArray]]:
    """K, D and each view's corner errors (px) of one training solve, warm-started from ``start`` when given."""
    if task.lens == "fisheye":
        if start is None:
            from s2r.calib.solve.solvers.fisheye import solve_mono_fisheye  # scipy: loaded only for a fisheye lens

            sol = solve_mono_fisheye(obj, img, task.size).solution
            K, D, rvecs, tvecs = sol.K, sol.D, list(sol.rvecs), list(sol.tvecs)
        else:
            out = cv2.fisheye.calibrate([np.asarray(o, np.float64).reshape(1, -1, 3) for o in obj],
                                        [np.asarray(p, np.float64).reshape(1, -1, 2) for p in img], task.size,
                                        start[0].copy(), start[1].reshape(4, 1).copy(),
                                        flags=_FISHEYE_FLAGS | cv2.CALIB_USE_INTRINSIC_GUESS, criteria=INIT_CRITERIA)
            K, D = np.asarray(out[1], np.float64), np.asarray(out[2], np.float64).reshape(4)
            rvecs, tvecs = [np.asarray(r, np.float64) for r in out[3]], [np.asarray(t, np.float64) for t in out[4]]
    else:
        flags, ncoef = DISTORTION_CHOICES[task.distortion]
        K0, D0 = np.eye(3), np.zeros(ncoef)
        if start is not None:
            K0 = start[0].copy()
            src = start[1].reshape(-1)[:ncoef]
            D0[:src.size] = src
        res = cv2.calibrateCamera(list(obj), [p.reshape(-1, 1, 2) for p in img], task.size, K0, D0,
                                  flags=flags | (0 if start is None else cv2.CALIB_USE_INTRINSIC_GUESS),
                                  criteria=INIT_CRITERIA)
        K, D = np.asarray(res[1], np.float64), np.asarray(res[2], np.float64).reshape(-1)
        rvecs, tvecs = [np.asarray(r, np.float64) for r in res[3]], [np.asarray(t, np.float64) for t in res[4]]
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D))):
        raise cv2.error("non-finite calibration")
    errors = [np.linalg.norm(_project(o, r.reshape(3), t.reshape(3), K, D, task.lens)[0] - p.reshape(-1, 2), axis=1)
              for o, p, r, t in zip(obj, img, rvecs, tvecs, strict=True)]
    return K, D, errors


def _rms(err: FloatArray) -> float:
    return float(np.sqrt(np.mean(err ** 2)))


def _train(task: MonoFoldTask) -> tuple[FloatArray, FloatArray, float, float]:
    """The fold's intrinsics after the full solve's view rule, that rule's threshold (px) and the corner
    threshold (px; inf without a corner rule)."""
    obj, img = list(task.train_obj), list(task.train_img)
    try:
        K, D, err = _calibrate(obj, img, task, (task.K, task.D))
    except cv2.error:  # a warm start that fails is retried from scratch, as the full solve started
        K, D, err = _calibrate(obj, img, task, None)
    thr = outlier_threshold(np.array([_rms(e) for e in err]), max_error_px=task.max_error_px)
    for _ in range(_ROUNDS):
        bad = {j for j, e in enumerate(err) if _rms(e) > thr}
        if not bad or len(obj) - len(bad) < 5:
            break
        obj = [o for j, o in enumerate(obj) if j not in bad]
        img = [p for j, p in enumerate(img) if j not in bad]
        K, D, err = _calibrate(obj, img, task, (K, D))
    corner = float("inf") if task.corner_factor is None else \
        max(task.corner_factor * float(np.median(np.concatenate(err))), _CORNER_FLOOR_PX)
    return K, D, thr, corner


def _pose(obj: Points, img: Points, K: FloatArray, D: FloatArray, lens: str) -> tuple[FloatArray, FloatArray] | None:
    """The board pose of one view with K, D fixed: solvePnP, then Levenberg-Marquardt on the pixel error."""
    o, p = np.asarray(obj, np.float64).reshape(-1, 1, 3), np.asarray(img, np.float64).reshape(-1, 1, 2)
    solve = cv2.fisheye.solvePnP if lens == "fisheye" else cv2.solvePnP
    ok, rv, tv = solve(o, p, K, D.reshape(-1, 1) if lens == "fisheye" else D)
    if not ok:
        return None
    x, lam = np.concatenate([np.asarray(rv, np.float64).reshape(3), np.asarray(tv, np.float64).reshape(3)]), 1e-3
    proj, jac = _project(obj, x[:3], x[3:], K, D, lens)
    res = (proj - p.reshape(-1, 2)).reshape(-1)
    for _ in range(20):
        A, b = jac.T @ jac, jac.T @ res
        step = -np.linalg.solve(A + lam * np.diag(np.diag(A)) + 1e-12 * np.eye(6), b)
        new_proj, new_jac = _project(obj, x[:3] + step[:3], x[3:] + step[3:], K, D, lens)
        new_res = (new_proj - p.reshape(-1, 2)).reshape(-1)
        if new_res @ new_res < res @ res:
            done = res @ res - new_res @ new_res < 1e-10 * max(float(res @ res), 1e-12)
            x, res, jac, lam = x + step, new_res, new_jac, lam / 10
            if done:
                break
        else:
            lam *= 10
    return x[:3], x[3:]


def run_mono_fold(task: MonoFoldTask) -> MonoFoldOutcome:
    """Solve one fold's training views and measure its held-out views."""
    try:
        K, D, thr, corner = _train(task)
    except (cv2.error, np.linalg.LinAlgError) as exc:
        return MonoFoldOutcome(np.full(4, np.nan), np.zeros(0), np.zeros(0), failed=str(exc).strip()[-200:])
    inl, every = [], [np.zeros(0)]
    for obj, img in zip(task.test_obj, task.test_img, strict=True):
        pose = _pose(obj, img, K, D, task.lens)
        if pose is None:  # no pose at all (solvePnP failed): nothing to measure
            continue
        sq = np.sum((_project(obj, pose[0], pose[1], K, D, task.lens)[0] - img.reshape(-1, 2)) ** 2, axis=1)
        every.append(sq)
        if float(np.sqrt(np.mean(sq))) <= thr:
            inl.append(sq[np.sqrt(sq) <= corner])
    return MonoFoldOutcome(np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2]]),
                           np.concatenate(inl) if inl else np.zeros(0), np.concatenate(every), K=K, D=D)
