"""Calibration solves: each camera alone, then the pair, with outlier views and uncertainties.

- Mono: ``cv2.calibrateCameraExtended`` (standard deviations of the intrinsics, per-view RMS).
- Stereo: ``cv2.stereoCalibrateExtended`` with CALIB_FIX_INTRINSIC (as ROS camera_calibration), or
  with CALIB_USE_INTRINSIC_GUESS for a joint refinement of everything.
- Outliers: a view whose RMS exceeds a robust threshold (median + 5 MAD-sigmas, at least 2x the median
  and at least ``floor_px``), or a fixed ``max_error_px``, is dropped and the solve repeated.
- Baseline uncertainty: first-order propagation through the Jacobian of the full stereo problem (both
  cameras' free intrinsics, the extrinsics and every board pose) at the solution,
  ``cov = sigma^2 (J^T J)^-1`` with ``sigma^2`` the residual variance; the board poses are eliminated
  with a Schur complement. It accounts for the intrinsics' uncertainty even when they were held fixed.

Points: ``obj`` board corners (N, 3) float32 metres; image corners (N, 2) float32 pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.observations import BoardObservation
from s2r.errors import CalibrationError
from s2r.lens.models import DEFAULT_LENS, LENS_MODELS, LensModel

__all__ = [
    "DISTORTION_CHOICES",
    "MonoSolution",
    "StereoSolution",
    "baseline_covariance",
    "distortion_flags",
    "extrinsics_covariance",
    "outlier_threshold",
    "solve_mono",
    "solve_mono_observations",
    "solve_stereo",
]

FloatArray = NDArray[np.float64]
Points = NDArray[np.float32]

#: ``--distortion`` choices (see :mod:`s2r.lens.models`): OpenCV flags and the number of coefficients kept.
DISTORTION_CHOICES: dict[str, tuple[int, int]] = {k: (m.cv_flags, m.n_coef) for k, m in LENS_MODELS.items()}
#: Indices of the free distortion coefficients per choice.
FREE_DISTORTION: dict[str, tuple[int, ...]] = {k: m.free for k, m in LENS_MODELS.items()}
_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-9)
#: Looser stopping rule for a solve that only initialises the joint refinement (which converges it anyway).
INIT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-6)


def distortion_flags(distortion: str) -> int:
    """OpenCV calibration flags for a ``--distortion`` choice."""
    if distortion not in DISTORTION_CHOICES:
        raise CalibrationError(f"unknown distortion model {distortion!r}", field="--distortion",
                               hint=f"choose one of {', '.join(DISTORTION_CHOICES)}")
    return DISTORTION_CHOICES[distortion][0]


@dataclass(frozen=True)
class MonoSolution:
    """One camera: K (3x3 px), D (OpenCV order), RMS and per-view RMS (px), intrinsics std
    ``(fx, fy, cx, cy, d0, d1, ...)`` in the same units, board poses (board frame in the camera frame, m)."""

    K: FloatArray
    D: FloatArray
    rms_px: float
    per_view_px: FloatArray
    std: FloatArray
    rvecs: tuple[FloatArray, ...]
    tvecs: tuple[FloatArray, ...]


@dataclass(frozen=True)
class StereoSolution:
    """The pair: ``X_right = R X_left + T`` (metres), RMS and per-view RMS (n, 2) px, possibly refined K/D."""

    R: FloatArray
    T: FloatArray
    rms_px: float
    per_view_px: FloatArray
    K1: FloatArray
    D1: FloatArray
    K2: FloatArray
    D2: FloatArray
    rvecs: tuple[FloatArray, ...]
    tvecs: tuple[FloatArray, ...]


def solve_mono(obj: Sequence[Points], img: Sequence[Points], size: tuple[int, int], *,
               distortion: str = DEFAULT_LENS, criteria: tuple[int, int, float] = _CRITERIA) -> MonoSolution:
    """Calibrate one camera from board views (``size`` = (width, height) px); ``criteria``: OpenCV's
    stopping rule (default tight; :data:`INIT_CRITERIA` for an initialisation)."""
    flags = distortion_flags(distortion)
    ncoef = DISTORTION_CHOICES[distortion][1]
    try:
        rms, K, D, rvecs, tvecs, std_i, _, per_view = cv2.calibrateCameraExtended(
            list(obj), [p.reshape(-1, 1, 2) for p in img], size, np.eye(3), np.zeros(ncoef), flags=flags,
            criteria=criteria)
    except cv2.error as exc:
        raise CalibrationError(f"OpenCV calibration failed: {str(exc).strip().splitlines()[-1]}",
                               hint="add more views with the board at different angles") from None
    D = np.asarray(D, np.float64).reshape(-1)[:ncoef]
    std_i = np.asarray(std_i, np.float64).reshape(-1)
    std = np.concatenate([std_i[:4], std_i[4:4 + ncoef]])
    std[~np.isfinite(std)] = np.inf  # OpenCV gives NaN for parameters the views do not constrain
    return MonoSolution(K=np.asarray(K, np.float64), D=D, rms_px=float(rms),
                        per_view_px=np.asarray(per_view, np.float64).reshape(-1), std=std,
                        rvecs=tuple(np.asarray(r, np.float64).reshape(3) for r in rvecs),
                        tvecs=tuple(np.asarray(t, np.float64).reshape(3) for t in tvecs))


def solve_stereo(obj: Sequence[Points], img_l: Sequence[Points], img_r: Sequence[Points], size: tuple[int, int],
                 left: MonoSolution, right: MonoSolution, *, distortion: str = DEFAULT_LENS,
                 refine_joint: bool = False) -> StereoSolution:
    """Solve the extrinsics with both cameras' intrinsics fixed (or refined jointly with ``refine_joint``)."""
    flags = distortion_flags(distortion)
    flags |= cv2.CALIB_USE_INTRINSIC_GUESS if refine_joint else cv2.CALIB_FIX_INTRINSIC
    try:
        out = cv2.stereoCalibrateExtended(
            list(obj), [p.reshape(-1, 1, 2) for p in img_l], [p.reshape(-1, 1, 2) for p in img_r],
            left.K.copy(), left.D.copy(), right.K.copy(), right.D.copy(), size, np.eye(3), np.zeros(3),
            flags=flags, criteria=_CRITERIA)
    except cv2.error as exc:
        raise CalibrationError(f"OpenCV stereo calibration failed: {str(exc).strip().splitlines()[-1]}",
                               hint="check that left and right images show the same board") from None
    rms, K1, D1, K2, D2, R, T, _E, _F, rvecs, tvecs, per_view = out
    ncoef = len(left.D)
    return StereoSolution(
        R=np.asarray(R, np.float64), T=np.asarray(T, np.float64).reshape(3), rms_px=float(rms),
        per_view_px=np.asarray(per_view, np.float64).reshape(-1, 2),
        K1=np.asarray(K1, np.float64), D1=np.asarray(D1, np.float64).reshape(-1)[:ncoef],
        K2=np.asarray(K2, np.float64), D2=np.asarray(D2, np.float64).reshape(-1)[:ncoef],
        rvecs=tuple(np.asarray(r, np.float64).reshape(3) for r in rvecs),
        tvecs=tuple(np.asarray(t, np.float64).reshape(3) for t in tvecs))


def outlier_threshold(errors_px: FloatArray, *, max_error_px: float | None = None, k_mad: float = 5.0,
                      k_median: float = 2.0, floor_px: float = 0.3) -> float:
    """Per-view RMS above which a view is an outlier (pixels).

    ``max_error_px`` when given; otherwise ``max(median + k_mad * 1.4826 * MAD, k_median * median, floor_px)``.
    """
    if max_error_px is not None:
        return float(max_error_px)
    errors = np.asarray(errors_px, np.float64)
    med = float(np.median(errors))
    sigma = 1.4826 * float(np.median(np.abs(errors - med)))
    return max(med + k_mad * sigma, k_median * med, floor_px)


def _compose(rvec: FloatArray, tvec: FloatArray, r_lr: FloatArray, t_lr: FloatArray) -> tuple[FloatArray, ...]:
    parts = cv2.composeRT(rvec.reshape(3, 1), tvec.reshape(3, 1), r_lr.reshape(3, 1), t_lr.reshape(3, 1))
    return tuple(np.asarray(p, np.float64) for p in parts)


def _project(obj: Points, rvec: FloatArray, tvec: FloatArray, K: FloatArray,
             D: FloatArray) -> tuple[FloatArray, FloatArray]:
    pts, jac = cv2.projectPoints(obj.astype(np.float64).reshape(-1, 1, 3), rvec.reshape(3, 1), tvec.reshape(3, 1),
                                 K, D)
    return np.asarray(pts, np.float64).reshape(-1), np.asarray(jac, np.float64)


def _intrinsic_columns(jac: FloatArray, free: tuple[int, ...]) -> FloatArray:
    """Columns of projectPoints' Jacobian for fx, fy, cx, cy and the free distortion terms."""
    return np.hstack([jac[:, 6:10], jac[:, [10 + i for i in free]]])


def _schur(Jg: FloatArray, Jv: FloatArray) -> FloatArray:
    """Information of the global columns ``Jg`` with the view columns ``Jv`` eliminated (J^T J Schur)."""
    B = Jg.T @ Jv
    return np.asarray(Jg.T @ Jg - B @ np.linalg.solve(Jv.T @ Jv, B.T), np.float64)


def baseline_covariance(obj: Sequence[Points], img_l: Sequence[Points], img_r: Sequence[Points],
                        stereo: StereoSolution, *, distortion: str = DEFAULT_LENS,
                        fixed_intrinsics: bool = True) -> tuple[FloatArray, float]:
    """Covariance (3x3, m^2) of the translation T and the residual sigma (px) of the stereo problem
    (the translation block of :func:`extrinsics_covariance`)."""
    cov, sigma = extrinsics_covariance(obj, img_l, img_r, stereo, distortion=distortion,
                                       fixed_intrinsics=fixed_intrinsics)
    return np.asarray(cov[3:, 3:], np.float64), sigma


def extrinsics_covariance(obj: Sequence[Points], img_l: Sequence[Points], img_r: Sequence[Points],
                          stereo: StereoSolution, *, distortion: str = DEFAULT_LENS,
                          fixed_intrinsics: bool = True) -> tuple[FloatArray, float]:
    """Covariance (6x6) of the pair's rotation vector (rad) and translation T (m), and the residual sigma (px).

    Parameters: free intrinsics of both cameras, rotation vector and T of the pair, and one 6-dof board
    pose per view (eliminated by Schur complements). Jointly refined (``fixed_intrinsics`` False):
    ``cov = sigma^2 (J^T J)^-1``. Two-step (intrinsics from the mono solves, then held fixed, as here by
    default): ``cov_E = sigma^2 A_EE^-1 + S cov_K S^T`` with ``S = -A_EE^-1 A_EK`` the sensitivity of the
    extrinsics to the intrinsics and ``cov_K`` the mono solves' intrinsics covariance.
    """
    free = FREE_DISTORTION[distortion]
    ni = 4 + len(free)
    ng = 2 * ni + 6
    A, A_l, A_r = np.zeros((ng, ng)), np.zeros((ni, ni)), np.zeros((ni, ni))
    r_lr = np.asarray(cv2.Rodrigues(stereo.R)[0], np.float64).reshape(3)
    ssr, m = 0.0, 0
    for obj_i, pl, pr, rv, tv in zip(obj, img_l, img_r, stereo.rvecs, stereo.tvecs, strict=True):
        proj_l, jl = _project(obj_i, rv, tv, stereo.K1, stereo.D1)
        r3, t3, dr3dr1, _dr3dt1, dr3dr2, _dr3dt2, dt3dr1, dt3dt1, dt3dr2, dt3dt2 = _compose(rv, tv, r_lr, stereo.T)
        proj_r, jr = _project(obj_i, r3, t3, stereo.K2, stereo.D2)
        n = proj_l.size
        Jg = np.zeros((2 * n, ng))
        Jv = np.zeros((2 * n, 6))
        Jg[:n, :ni] = _intrinsic_columns(jl, free)
        Jg[n:, ni:2 * ni] = _intrinsic_columns(jr, free)
        jr_r, jr_t = jr[:, 0:3], jr[:, 3:6]
        Jg[n:, 2 * ni:2 * ni + 3] = jr_r @ dr3dr2 + jr_t @ dt3dr2
        Jg[n:, 2 * ni + 3:] = jr_t @ dt3dt2
        Jv[:n, :] = jl[:, 0:6]
        Jv[n:, :3] = jr_r @ dr3dr1 + jr_t @ dt3dr1
        Jv[n:, 3:] = jr_t @ dt3dt1
        A += _schur(Jg, Jv)
        A_l += _schur(Jg[:n, :ni], jl[:, 0:6])
        A_r += _schur(Jg[n:, ni:2 * ni], jr[:, 0:6])
        ssr += float(np.sum((proj_l - pl.reshape(-1)) ** 2) + np.sum((proj_r - pr.reshape(-1)) ** 2))
        m += 2 * n
    sigma2 = ssr / max(1, m - ng - 6 * len(obj))
    if not fixed_intrinsics:
        cov = sigma2 * np.linalg.pinv(A)
        return np.asarray(cov[2 * ni:, 2 * ni:], np.float64), float(np.sqrt(sigma2))
    k, e = slice(0, 2 * ni), slice(2 * ni, ng)
    A_ee_inv = np.linalg.pinv(A[e, e])
    S = -A_ee_inv @ A[e, k]
    cov_k = np.zeros((2 * ni, 2 * ni))
    cov_k[:ni, :ni] = sigma2 * np.linalg.pinv(A_l)
    cov_k[ni:, ni:] = sigma2 * np.linalg.pinv(A_r)
    cov_e = sigma2 * A_ee_inv + S @ cov_k @ S.T
    return np.asarray(cov_e, np.float64), float(np.sqrt(sigma2))


def solve_mono_observations(views: Sequence[BoardObservation], size: tuple[int, int],
                            lens: LensModel, *, criteria: tuple[int, int, float] = _CRITERIA) -> MonoSolution:
    """:func:`solve_mono` of one camera's observations (views may show different corner subsets)."""
    return solve_mono([v.obj.astype(np.float32) for v in views], [v.img.astype(np.float32) for v in views], size,
                      distortion=lens.name, criteria=criteria)
