"""Fisheye (OpenCV equidistant, k1..k4) calibration solves: each camera alone, then the pair.

- Mono: ``cv2.fisheye.calibrate`` (RECOMPUTE_EXTRINSIC, FIX_SKEW) on views of any size (partial views
  welcome); per-view RMS and the intrinsics' covariance from the Jacobian of ``cv2.fisheye.projectPoints``
  (``cov = sigma^2 (J^T J)^-1`` with the board poses eliminated by Schur complements).
- Stereo: ``cv2.fisheye.stereoCalibrate`` needs the same number of points in every view, so it fails on
  partial views (REFERENCE.md). The pair is solved here instead with both cameras' intrinsics fixed (as the
  pinhole path does with CALIB_FIX_INTRINSIC): scipy's Levenberg-Marquardt-type ``least_squares`` over the
  right camera's pose and one board pose per view, residuals from ``cv2.fisheye.projectPoints`` in pixels.
- Baseline uncertainty: first-order, two-step as :func:`s2r.calib.solve.solvers.cvsolve.baseline_covariance`:
  ``cov_E = sigma^2 A_EE^-1 + S cov_K S^T``.

Points: ``obj`` board corners (N, 3) float32 metres per view; image corners (N, 2) float32 pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from s2r.calib.solve.solvers.cvsolve import MonoSolution, StereoSolution
from s2r.errors import CalibrationError

__all__ = ["FisheyeMono", "fisheye_baseline_covariance", "solve_mono_fisheye", "solve_stereo_fisheye"]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]
_FLAGS = cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW
_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
_STEP = 1e-6


@dataclass(frozen=True)
class FisheyeMono:
    """A fisheye camera solve: the solution (D = k1..k4) and the covariance (8x8) of fx fy cx cy k1..k4."""

    solution: MonoSolution
    cov: FloatArray


def _project(obj: Points, rvec: FloatArray, tvec: FloatArray, K: FloatArray, D: FloatArray
             ) -> tuple[FloatArray, FloatArray]:
    pts, jac = cv2.fisheye.projectPoints(np.asarray(obj, np.float64).reshape(-1, 1, 3), rvec.reshape(3, 1),
                                        tvec.reshape(3, 1), K, D.reshape(4, 1))
    return np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(jac, np.float64)


def _schur(Jg: FloatArray, Jv: FloatArray) -> FloatArray:
    B = Jg.T @ Jv
    return np.asarray(Jg.T @ Jg - B @ np.linalg.pinv(Jv.T @ Jv) @ B.T, np.float64)


def _try(objs: list[FloatArray], imgs: list[FloatArray], size: tuple[int, int], K: FloatArray, D: FloatArray,
         flags: int) -> tuple[float, Any, Any, Any, Any] | None:
    try:
        out = cv2.fisheye.calibrate(objs, imgs, size, K.copy(), D.copy(), flags=flags, criteria=_CRITERIA)
    except cv2.error:
        return None
    rms = float(out[0])
    return (rms, *out[1:]) if np.isfinite(rms) else None


def _calibrate_staged(objs: list[FloatArray], imgs: list[FloatArray], size: tuple[int, int]
                      ) -> tuple[Any, Any, Any, Any]:
    """``cv2.fisheye.calibrate`` from OpenCV's own start, and from a start solved with k2..k4 fixed (its
    free solve can run off to a wrong minimum on few or small views); the lower RMS wins."""
    K0 = np.array([[size[0] / np.pi, 0, (size[0] - 1) / 2], [0, size[0] / np.pi, (size[1] - 1) / 2], [0, 0, 1.0]])
    tries = [_try(objs, imgs, size, K0, np.zeros(4), _FLAGS)]
    staged = _try(objs, imgs, size, K0, np.zeros(4),
                  _FLAGS | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_FIX_K4)
    if staged is not None:
        tries.append(_try(objs, imgs, size, np.asarray(staged[1], np.float64), np.asarray(staged[2], np.float64),
                          _FLAGS | cv2.CALIB_USE_INTRINSIC_GUESS))
    ok = [t for t in tries if t is not None]
    if not ok:
        raise CalibrationError("OpenCV fisheye calibration failed on every start",
                               hint="add views with the board at different angles and distances")
    best = min(ok, key=lambda t: t[0])
    return best[1], best[2], best[3], best[4]


def solve_mono_fisheye(obj: Sequence[Points], img: Sequence[Points], size: tuple[int, int]) -> FisheyeMono:
    """Calibrate one fisheye camera from board views (``size`` = (width, height) px)."""
    objs = [np.asarray(o, np.float64).reshape(1, -1, 3) for o in obj]
    imgs = [np.asarray(p, np.float64).reshape(1, -1, 2) for p in img]
    K_cv, D_cv, rvecs, tvecs = _calibrate_staged(objs, imgs, size)
    K: FloatArray = np.asarray(K_cv, np.float64)
    D: FloatArray = np.asarray(D_cv, np.float64).reshape(4)
    rv = tuple(np.asarray(r, np.float64).reshape(3) for r in rvecs)
    tv = tuple(np.asarray(t, np.float64).reshape(3) for t in tvecs)
    info = np.zeros((8, 8))
    ssr, m, per_view = 0.0, 0, []
    for o, p, r, t in zip(obj, img, rv, tv, strict=True):
        proj, jac = _project(o, r, t, K, D)
        res = proj - np.asarray(p, np.float64).reshape(-1, 2)
        per_view.append(float(np.sqrt(np.mean(np.sum(res**2, axis=1)))))
        ssr += float(np.sum(res**2))
        m += res.size
        info += _schur(jac[:, :8], jac[:, 8:14])
    sigma2 = ssr / max(1, m - 8 - 6 * len(obj))
    cov = sigma2 * np.linalg.pinv(info)
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    sol = MonoSolution(K=K, D=D, rms_px=float(np.sqrt(ssr / max(1, m // 2))), per_view_px=np.array(per_view),
                       std=std, rvecs=rv, tvecs=tv)
    return FisheyeMono(solution=sol, cov=np.asarray(cov, np.float64))


def _rt(vec: FloatArray) -> tuple[FloatArray, FloatArray]:
    return vec[:3], vec[3:6]


def _right_pose(rv: FloatArray, tv: FloatArray, r_lr: FloatArray, t_lr: FloatArray) -> tuple[FloatArray, FloatArray]:
    r3, t3 = cv2.composeRT(rv.reshape(3, 1), tv.reshape(3, 1), r_lr.reshape(3, 1), t_lr.reshape(3, 1))[:2]
    return np.asarray(r3, np.float64).reshape(3), np.asarray(t3, np.float64).reshape(3)


def _intrinsics(vec: FloatArray) -> tuple[FloatArray, FloatArray]:
    fx, fy, cx, cy = vec[:4]
    return np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]]), vec[4:8].copy()


@dataclass(frozen=True)
class _Problem:
    obj: Sequence[Points]
    img_l: Sequence[Points]
    img_r: Sequence[Points]

    def residuals(self, params: FloatArray, intr: FloatArray) -> FloatArray:
        """Pixels: left then right residuals of every view; ``params`` = (r_lr, T, pose_1, ..., pose_n)."""
        K1, D1 = _intrinsics(intr[:8])
        K2, D2 = _intrinsics(intr[8:])
        r_lr, t_lr = _rt(params[:6])
        out = []
        for i, (o, pl, pr) in enumerate(zip(self.obj, self.img_l, self.img_r, strict=True)):
            rv, tv = _rt(params[6 + 6 * i:12 + 6 * i])
            out.append((_project(o, rv, tv, K1, D1)[0] - pl.reshape(-1, 2)).ravel())
            r3, t3 = _right_pose(rv, tv, r_lr, t_lr)
            out.append((_project(o, r3, t3, K2, D2)[0] - pr.reshape(-1, 2)).ravel())
        return np.concatenate(out)

    def sparsity(self) -> lil_matrix:
        n_rows = sum(4 * len(o) for o in self.obj)
        sp = lil_matrix((n_rows, 6 + 6 * len(self.obj)), dtype=int)
        row = 0
        for i, o in enumerate(self.obj):
            rows = slice(row, row + 4 * len(o))
            sp[rows, 6 + 6 * i:12 + 6 * i] = 1
            sp[row + 2 * len(o):row + 4 * len(o), :6] = 1
            row += 4 * len(o)
        return sp


def _initial(left: MonoSolution, right: MonoSolution, idx_l: Sequence[int], idx_r: Sequence[int]) -> FloatArray:
    """Start: the right-from-left motion as the median of per-view motions of the mono solves' poses."""
    rs, ts = [], []
    for i, j in zip(idx_l, idx_r, strict=True):
        Rl, Rr = cv2.Rodrigues(left.rvecs[i])[0], cv2.Rodrigues(right.rvecs[j])[0]
        R = Rr @ Rl.T
        rs.append(np.asarray(cv2.Rodrigues(R)[0], np.float64).reshape(3))
        ts.append(right.tvecs[j] - R @ left.tvecs[i])
    poses = np.concatenate([np.concatenate([left.rvecs[i], left.tvecs[i]]) for i in idx_l])
    return np.concatenate([np.median(rs, axis=0), np.median(ts, axis=0), poses])


def solve_stereo_fisheye(obj: Sequence[Points], img_l: Sequence[Points], img_r: Sequence[Points],
                         left: MonoSolution, right: MonoSolution, *, idx_l: Sequence[int],
                         idx_r: Sequence[int]) -> StereoSolution:
    """The pair's motion (``X_right = R X_left + T``, metres) with both fisheye cameras' intrinsics fixed.

    ``obj``/``img_l``/``img_r``: corners seen by both cameras, per view; ``idx_l``/``idx_r``: each view's
    index in the left / right mono solves (their board poses start the solve)."""
    prob = _Problem(obj, img_l, img_r)
    intr = np.concatenate([_params(left), _params(right)])
    x0 = _initial(left, right, idx_l, idx_r)
    try:
        res = least_squares(prob.residuals, x0, args=(intr,), jac_sparsity=prob.sparsity(), method="trf",
                            x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200)
    except (ValueError, np.linalg.LinAlgError) as exc:
        raise CalibrationError(f"fisheye stereo solve failed: {exc}",
                               hint="check that left and right images show the same board") from None
    r_lr, t_lr = _rt(res.x[:6])
    per_view, row = [], 0
    for o in obj:
        n = 2 * len(o)
        rl, rr = res.fun[row:row + n], res.fun[row + n:row + 2 * n]
        per_view.append([float(np.sqrt(np.mean(rl**2) * 2)), float(np.sqrt(np.mean(rr**2) * 2))])
        row += 2 * n
    rvecs = tuple(res.x[6 + 6 * i:9 + 6 * i].copy() for i in range(len(obj)))
    tvecs = tuple(res.x[9 + 6 * i:12 + 6 * i].copy() for i in range(len(obj)))
    return StereoSolution(R=np.asarray(cv2.Rodrigues(r_lr)[0], np.float64), T=t_lr.copy(),
                          rms_px=float(np.sqrt(np.mean(res.fun**2) * 2)), per_view_px=np.array(per_view),
                          K1=left.K, D1=left.D, K2=right.K, D2=right.D, rvecs=rvecs, tvecs=tvecs)


def _params(sol: MonoSolution) -> FloatArray:
    return np.array([sol.K[0, 0], sol.K[1, 1], sol.K[0, 2], sol.K[1, 2], *sol.D])


def fisheye_baseline_covariance(obj: Sequence[Points], img_l: Sequence[Points], img_r: Sequence[Points],
                                stereo: StereoSolution, cov_left: FloatArray, cov_right: FloatArray
                                ) -> tuple[FloatArray, float]:
    """Covariance (3x3, m^2) of T and the residual sigma (px): ``sigma^2 A_EE^-1 + S cov_K S^T`` with the
    board poses eliminated, ``S`` the sensitivity of the extrinsics to both cameras' intrinsics (numerical
    Jacobian) and ``cov_K`` the mono solves' intrinsics covariances."""
    prob = _Problem(obj, img_l, img_r)
    intr = np.concatenate([_params_of(stereo.K1, stereo.D1), _params_of(stereo.K2, stereo.D2)])
    x = np.concatenate([np.asarray(cv2.Rodrigues(stereo.R)[0], np.float64).reshape(3), stereo.T,
                        *[np.concatenate([r, t]) for r, t in zip(stereo.rvecs, stereo.tvecs, strict=True)]])
    f0 = prob.residuals(x, intr)
    J = np.zeros((f0.size, 16 + x.size))
    for k in range(16):
        d = np.zeros(16)
        d[k] = _STEP * max(1.0, abs(intr[k]))
        J[:, k] = (prob.residuals(x, intr + d) - prob.residuals(x, intr - d)) / (2 * d[k])
    for k in range(x.size):
        d = np.zeros(x.size)
        d[k] = _STEP
        J[:, 16 + k] = (prob.residuals(x + d, intr) - prob.residuals(x - d, intr)) / (2 * _STEP)
    A = J.T @ J
    g, v = slice(0, 22), slice(22, None)
    A_g = A[g, g] - A[g, v] @ np.linalg.pinv(A[v, v]) @ A[v, g]
    sigma2 = float(f0 @ f0) / max(1, f0.size - x.size)
    ki, ei = slice(0, 16), slice(16, 22)
    A_ee_inv = np.linalg.pinv(A_g[ei, ei])
    S = -A_ee_inv @ A_g[ei, ki]
    cov_k = np.zeros((16, 16))
    cov_k[:8, :8], cov_k[8:, 8:] = cov_left, cov_right
    cov_e = sigma2 * A_ee_inv + S @ cov_k @ S.T
    return np.asarray(cov_e[3:, 3:], np.float64), float(np.sqrt(sigma2))


def _params_of(K: FloatArray, D: FloatArray) -> FloatArray:
    return np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *np.asarray(D).reshape(-1)[:4]])
