"""The relative-rotation error that explains vertical disparity after rectification, fitted robustly.

Convention (also written into every JSON result): the rig really has ``R_true = dR @ R_profile``, ``dR`` a
small rotation about the RIGHT camera's optical axes (x right, y down, z forward), given as the rotation
vector ``omega = (pitch about x, yaw about y, roll about z)`` in radians. The correction that a fixed profile
applies is ``dR`` itself (``R_fixed = dR @ R_profile``).

Two physical readings of "the right camera turned" differ by a small translation and are both fitted:

- ``centre``: the camera turned about its own optical centre (``T_true = dR @ T_profile``): the rectified
  right image moves by a pure rotation, so vertical disparity does not depend on depth;
- ``translation``: the profile's ``T`` still holds (``T_true = T_profile``), which moves the centre by
  ``-(omega x T)`` and adds a depth-dependent term.

Both are linear near zero and both are fitted; :mod:`s2r.drift.check` reports their mean, and their
half-difference enters sigma (it is small unless near points dominate the scene).

Each match is a point: its rectified left pixel and disparity give a homogeneous 3D point in the rectified left
frame; the profile (rotated by ``dR``) then predicts the rectified right row. Residual = measured right row -
prediction (pixels). The Jacobian is taken by central differences, so any lens model and rectification work.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.profile import StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["MODELS", "RotationFit", "fit_rotation", "lens_nuisance", "predict_right", "robust_scale"]

FloatArray = NDArray[np.float64]
MODELS = ("centre", "translation")
_EPS_RAD = 1e-5
_HUBER_K = 1.5
#: Prior sigmas of the lens nuisance terms (dimensionless, :func:`lens_nuisance`'s order): what a board calibration
#: leaves uncertain between two cameras: focal ratio about 2e-3 (1 px at f 500), radial k1 about 5e-3, decentering
#: p1 a few 1e-4 (REFERENCE.md). Fitted free, the terms trade against the rotation on real lenses: on OpenCV's
#: webcam set ORB's matches moved yaw by 0.3 deg; this ridge keeps them to what a calibration can get wrong.
LENS_PRIOR = np.array([2e-3, 5e-3, 2.5e-4])


@dataclass(frozen=True)
class RotationFit:
    """``omega`` (3,) rad about the right optical axes (x, y, z), its formal covariance (3, 3) rad^2, the robust
    residual scale (px) and the model (``centre`` or ``translation``)."""

    omega: FloatArray
    covariance: FloatArray
    scale_px: float
    model: str


def _rotation(omega: FloatArray) -> FloatArray:
    """3x3 rotation matrix of the rotation vector ``omega`` (3,) rad (OpenCV's Rodrigues: cv2 is loaded here
    anyway, SciPy's rotations would add ~0.3 s of imports to every check)."""
    return np.asarray(cv2.Rodrigues(np.asarray(omega, np.float64).reshape(3, 1))[0], np.float64)


def _points(rect: StereoRectification, left: FloatArray, disparity: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Homogeneous points in the LEFT optical frame: (N, 3) directions and (N,) inverse depths (1/m scale)."""
    P1 = rect.P1
    ray = np.column_stack([(left[:, 0] - P1[0, 2]) / P1[0, 0], (left[:, 1] - P1[1, 2]) / P1[1, 1],
                           np.ones(len(left))])
    inv_depth = np.clip(disparity, 0.0, None) / (rect.fx_px * rect.baseline_m)  # 1/Z along the rectified axis
    return ray @ rect.R1, inv_depth  # R1^T @ ray, row-wise


def predict_right(profile: StereoProfile, rect: StereoRectification, left: FloatArray, disparity: FloatArray,
                  omega: FloatArray, *, model: str) -> FloatArray:
    """(N, 2) rectified right pixels predicted for a rig turned by ``omega`` (rad, right optical axes)."""
    direction, inv_depth = _points(rect, left, disparity)
    dR = _rotation(omega)
    T = profile.T.reshape(3)
    in_right = direction @ profile.R.T + np.outer(inv_depth, T)  # R X + T w (homogeneous)
    if model == "centre":
        turned = in_right @ dR.T
    elif model == "translation":
        turned = (direction @ profile.R.T) @ dR.T + np.outer(inv_depth, T)
    else:
        raise ValueError(f"unknown model {model!r}; one of {MODELS}")
    rectified = turned @ rect.R2.T
    P2 = rect.P2
    with np.errstate(divide="ignore", invalid="ignore"):
        x = P2[0, 0] * rectified[:, 0] / rectified[:, 2] + P2[0, 2]
        y = P2[1, 1] * rectified[:, 1] / rectified[:, 2] + P2[1, 2]
    return np.column_stack([x, y])


def robust_scale(residuals: FloatArray) -> float:
    """1.4826 x the median absolute deviation about zero (pixels); a Gaussian's sigma for clean data."""
    return float(1.4826 * np.median(np.abs(residuals))) if len(residuals) else float("nan")


class _Rows:
    """The right rows :func:`predict_right` gives for fixed matches, for many rotations at once.

    What does not depend on ``omega`` (the matches' points in the right camera's frame, the profile's ``T``
    term) is computed once; each rotation then costs one (N, 3) x (3, 2) product. Used by the fit, whose
    Gauss-Newton step needs the rows at ``omega`` and at ``omega +/- eps`` on each axis (7 rotations) every
    iteration.
    """

    def __init__(self, profile: StereoProfile, rect: StereoRectification, left: FloatArray,
                 disparity: FloatArray, model: str) -> None:
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}; one of {MODELS}")
        direction, inv_depth = _points(rect, left, disparity)
        moved = np.outer(inv_depth, profile.T.reshape(3))
        self.turned = direction @ profile.R.T + (moved if model == "centre" else 0.0)  # turned by dR
        self.fixed = (np.zeros((len(left), 2)) if model == "centre"  # not turned (translation model)
                      else moved @ rect.R2[1:3].T)
        self.R2 = rect.R2
        self.f, self.c = float(rect.P2[1, 1]), float(rect.P2[1, 2])

    def rows(self, omegas: FloatArray) -> FloatArray:
        """(N, K) predicted rectified right rows (px) for (K, 3) rotation vectors ``omegas`` (rad)."""
        M = self.R2 @ np.array([_rotation(w) for w in omegas])  # (K, 3, 3): rectified from unturned
        yz = self.turned @ M[:, 1:3, :].transpose(2, 0, 1).reshape(3, -1)  # (N, 2K): rows y, z per rotation
        y = yz[:, 0::2] + self.fixed[:, :1]
        z = yz[:, 1::2] + self.fixed[:, 1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(self.f * y / z + self.c, np.float64)

    def rows_and_jacobian(self, omega: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(N,) rows at ``omega`` and (N, 3) d(row)/d(omega), px/rad, by central differences."""
        steps = np.vstack([np.zeros(3), _EPS_RAD * np.eye(3), -_EPS_RAD * np.eye(3)])
        rows = self.rows(omega + steps)
        return rows[:, 0], (rows[:, 1:4] - rows[:, 4:7]) / (2 * _EPS_RAD)


def lens_nuisance(rect: StereoRectification, left: FloatArray) -> FloatArray:
    """(N, 3) vertical-disparity patterns (px per unit) of what a calibration gets slightly wrong besides the
    rotation: a vertical scale between the cameras (``y``), a radial-distortion difference (``y r^2``) and a
    decentering one (``x^2 + 3 y^2``, the p1 term), in normalised rectified-left coordinates times f.

    They are fitted alongside the rotation so that lens-model error does not masquerade as pitch or roll. The
    p2 pattern (``2 x y``) is the yaw pattern itself to first order: yaw's sigma carries it instead.
    """
    P1 = rect.P1
    x = (left[:, 0] - P1[0, 2]) / P1[0, 0]
    y = (left[:, 1] - P1[1, 2]) / P1[1, 1]
    r2 = x * x + y * y
    return float(P1[1, 1]) * np.column_stack([y, y * r2, x * x + 3 * y * y])


def fit_rotation(profile: StereoProfile, rect: StereoRectification, left: FloatArray, right: FloatArray, *,
                 model: str, iterations: int = 8, nuisance: bool = True) -> RotationFit:
    """Gauss-Newton with Huber weights (re-scaled each iteration) on the right rows of (N, 2) matches.

    With ``nuisance`` the :func:`lens_nuisance` patterns are fitted too, each held near zero by a Gaussian prior
    of :data:`LENS_PRIOR` (their effect leaves ``omega``'s covariance through the joint inverse). Matches the
    profile cannot project (a point behind a camera of a strongly turned rectification) carry no weight; a
    system that cannot be solved gives NaN, never a guess.
    """
    disparity = left[:, 0] - right[:, 0] + rect.doffs_px
    extra = lens_nuisance(rect, left) if nuisance else np.zeros((len(left), 0))
    params = np.zeros(3 + extra.shape[1])
    nan = RotationFit(np.full(3, np.nan), np.full((3, 3), np.nan), float("nan"), model)
    A = np.zeros((len(params), len(params)))
    scale = 1e-3

    predictor = _Rows(profile, rect, left, disparity, model)
    for _ in range(iterations):
        rows, J_rot = predictor.rows_and_jacobian(params[:3])
        residual = np.asarray(right[:, 1] - (rows + extra @ params[3:]), np.float64)
        J = np.hstack([J_rot, extra])
        usable = np.isfinite(residual) & np.isfinite(J).all(axis=1)
        if usable.sum() < len(params) + 1:
            return nan
        residual, J = np.where(usable, residual, 0.0), np.where(usable[:, None], J, 0.0)
        scale = max(robust_scale(residual[usable]), 1e-3)
        u = np.abs(residual) / (_HUBER_K * scale)
        weights = np.where(u <= 1.0, 1.0, 1.0 / np.maximum(u, 1e-12)) * usable
        weights[np.abs(residual) > 6.0 * scale] = 0.0  # gross mismatches carry no weight at all
        prior = np.concatenate([np.zeros(3), scale**2 / LENS_PRIOR[:extra.shape[1]] ** 2])  # ridge on lens terms
        A = J.T @ (J * weights[:, None]) + np.diag(prior)
        try:
            step = np.linalg.lstsq(A, J.T @ (weights * residual) - prior * params, rcond=None)[0]
        except np.linalg.LinAlgError:
            return nan
        params = params + step
        if np.max(np.abs(step[:3])) < 1e-9:
            break
    try:
        covariance = np.asarray(scale**2 * np.linalg.pinv(A), np.float64)[:3, :3]  # A: the last iteration's
    except np.linalg.LinAlgError:
        return nan
    return RotationFit(params[:3].copy(), covariance, scale, model)
