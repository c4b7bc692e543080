"""The relative-rotation error from several reasonable estimators, with a sigma that covers their spread.

A single fit's residual covariance is far too small on a real rig: the lens model's small errors, the detector's
localisation and the scene's layout each move the answer by more than that (on OpenCV's real webcam set, SIFT
and ORB matches differ by 0.14 deg in yaw while each fit claims 0.02 deg). So the rotation is estimated several
ways, all from the same frames:

- SIFT matches, with and without the lens nuisance terms (:func:`s2r.drift.model.lens_nuisance`), about the
  camera's centre; SIFT with the terms under the ``translation`` reading of the turn;
- ORB matches (another detector), with and without the terms;

each with its own sigma (the larger of its residual covariance and its jackknife over frames, or image regions
for fewer than four frames). The reported rotation is the inverse-variance mean of the centre-model estimators.
Sigma, per axis (radians): ``sqrt(sigma_sift^2 + spread^2 + lens_floor^2)`` with ``sigma_sift`` the SIFT-with-
lens-terms estimator's own, ``spread`` the largest distance of any estimator from the reported value beyond that
estimator's own sigma (a disagreement its own noise does not explain), and ``lens_floor`` the tangential-
distortion uncertainty that reads as yaw. Every estimator lies within ``sigma + its own sigma`` of the result.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from s2r.drift.model import fit_rotation
from s2r.profile import StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["TANGENTIAL_SIGMA", "Estimate", "MatchSet", "estimate_rotation"]

FloatArray = NDArray[np.float64]
#: Typical uncertainty of a calibrated lens' decentering coefficients (p1, p2): a few 1e-4 (REFERENCE.md).
TANGENTIAL_SIGMA = 2.5e-4


@dataclass(frozen=True)
class MatchSet:
    """(N, 2) rectified left and right px of one detector's gated matches, and each match's group (frame index,
    or image region) for the jackknife."""

    left: FloatArray
    right: FloatArray
    groups: NDArray[np.int_]

    @property
    def count(self) -> int:
        """Number of matches."""
        return len(self.left)


@dataclass(frozen=True)
class Estimate:
    """The reported rotation ``omega`` (3,) rad, its honest ``sigma`` (3,) rad and the parts it is made of:
    ``formal`` (residual covariance), ``resampled`` (jackknife, or None), ``spread`` (largest estimator
    distance), every estimator by name, and ``source`` in words."""

    omega: FloatArray
    sigma: FloatArray
    formal: FloatArray
    resampled: FloatArray | None
    spread: FloatArray
    estimators: dict[str, FloatArray]
    source: str


def lens_floor(profile: StereoProfile) -> FloatArray:
    """(3,) rad of sigma that lens-model error adds: yaw only, and only for a lens with distortion.

    Yaw's vertical disparity (``x y``) is the decentering term p2's pattern to first order; a calibration
    leaves p2 uncertain by about :data:`TANGENTIAL_SIGMA`, which reads as ``2 p2`` rad of yaw.
    """
    distorted = not (profile.left.distortion.is_zero and profile.right.distortion.is_zero)
    return np.array([0.0, 2.0 * TANGENTIAL_SIGMA if distorted else 0.0, 0.0])


def _jackknife(matches: MatchSet, fit: Callable[[FloatArray, FloatArray], FloatArray]) -> FloatArray | None:
    """Jackknife sigma (rad) of ``fit(left, right) -> omega`` over ``matches.groups``; None with under 3 groups."""
    labels = np.unique(matches.groups)
    if len(labels) < 3:
        return None
    estimates = []
    for label in labels:
        keep = matches.groups != label
        if keep.sum() >= 10:
            omega = fit(matches.left[keep], matches.right[keep])
            if np.all(np.isfinite(omega)):
                estimates.append(omega)
    if len(estimates) < 3:
        return None
    values = np.array(estimates)
    n = len(values)
    return np.asarray(np.sqrt((n - 1) / n * np.sum((values - values.mean(axis=0)) ** 2, axis=0)), np.float64)


@dataclass(frozen=True)
class _Fitted:
    omega: FloatArray
    formal: FloatArray
    resampled: FloatArray | None

    @property
    def sigma(self) -> FloatArray:
        return self.formal if self.resampled is None else np.fmax(self.formal, self.resampled)


def _fitted(profile: StereoProfile, rect: StereoRectification, matches: MatchSet, *, model: str, nuisance: bool
            ) -> _Fitted:
    def fit(left: FloatArray, right: FloatArray) -> FloatArray:
        return fit_rotation(profile, rect, left, right, model=model, nuisance=nuisance).omega

    full = fit_rotation(profile, rect, matches.left, matches.right, model=model, nuisance=nuisance)
    formal = np.sqrt(np.clip(np.diag(full.covariance), 0, None))
    resampled = _jackknife(matches, fit) if np.all(np.isfinite(full.omega)) else None
    return _Fitted(full.omega, formal, resampled)


def _estimators(profile: StereoProfile, rect: StereoRectification, sift: MatchSet, orb: MatchSet | None,
                min_matches: int) -> dict[str, _Fitted]:
    """Every estimator (omega, formal and jackknife sigma, rad) by name."""
    found = {"sift+lens": _fitted(profile, rect, sift, model="centre", nuisance=True),
             "sift": _fitted(profile, rect, sift, model="centre", nuisance=False),
             "sift+lens translation": _fitted(profile, rect, sift, model="translation", nuisance=True)}
    if orb is not None and orb.count >= min_matches:
        found["orb+lens"] = _fitted(profile, rect, orb, model="centre", nuisance=True)
        found["orb"] = _fitted(profile, rect, orb, model="centre", nuisance=False)
    return {k: v for k, v in found.items() if np.all(np.isfinite(v.omega)) and np.all(np.isfinite(v.sigma))}


def estimate_rotation(profile: StereoProfile, rect: StereoRectification, sift: MatchSet, orb: MatchSet | None, *,
                      min_matches: int) -> Estimate:
    """The rotation error (rad, about the right camera's axes) and its sigma from the matches (module docstring);
    NaN throughout when it cannot be estimated."""
    fitted = _estimators(profile, rect, sift, orb, min_matches)
    if "sift+lens" not in fitted:
        nan = np.full(3, np.nan)
        return Estimate(nan, nan, nan, None, nan, {k: v.omega for k, v in fitted.items()}, "not estimated")
    centre = [v for k, v in fitted.items() if "translation" not in k]
    weights = np.array([1.0 / np.maximum(v.sigma, 1e-7) ** 2 for v in centre])
    omega = np.sum(weights * np.array([v.omega for v in centre]), axis=0) / np.sum(weights, axis=0)
    excess = np.array([np.fmax(np.abs(v.omega - omega) - v.sigma, 0.0) for v in fitted.values()])
    spread = excess.max(axis=0)
    main = fitted["sift+lens"]
    floor = lens_floor(profile)
    sigma = np.sqrt(main.sigma**2 + spread**2 + floor**2)
    parts = ["formal (residual-scaled)" if main.resampled is None or np.all(main.formal >= main.resampled)
             else "jackknife",
             f"spread of {len(fitted)} estimators beyond their own sigma ({', '.join(fitted)})"]
    if floor[1] > 0:
        parts.append("lens floor on yaw")
    return Estimate(np.asarray(omega, np.float64), sigma, main.formal, main.resampled, spread,
                    {k: v.omega for k, v in fitted.items()}, " + ".join(parts))
