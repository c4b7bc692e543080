"""The relative-rotation error from several reasonable estimators, with a sigma that covers their spread.

A single fit's residual covariance is far too small on a real rig: the lens model's small errors, the detector's
localisation and the scene's layout each move the answer by more than that (on OpenCV's real webcam set, SIFT
and ORB matches differ by 0.14 deg in yaw while each fit claims 0.02 deg). So the rotation is estimated several
ways, all from the same frames:

- SIFT matches, with and without the lens nuisance terms (:func:`s2r.drift.model.lens_nuisance`), about the
  camera's centre; SIFT with the terms under the ``translation`` reading of the turn;
- ORB matches (another detector), with and without the terms;

and the reported rotation is the mean of the centre-model estimators. Sigma, per axis (radians):
``sqrt(max(formal, jackknife)^2 + spread^2 + lens_floor^2)`` with ``spread`` the largest distance of any
estimator from the reported value (so every estimator lies within one sigma), ``jackknife`` over frames (or image
regions for fewer than four frames) and ``lens_floor`` the tangential-distortion uncertainty that reads as yaw.
"""

from __future__ import annotations

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


def _jackknife(profile: StereoProfile, rect: StereoRectification, matches: MatchSet) -> FloatArray | None:
    """Jackknife sigma (rad) of the SIFT-with-lens-terms fit over ``matches.groups``; None with under 3 groups."""
    labels = np.unique(matches.groups)
    if len(labels) < 3:
        return None
    estimates = []
    for label in labels:
        keep = matches.groups != label
        if keep.sum() >= 10:
            omega = fit_rotation(profile, rect, matches.left[keep], matches.right[keep], model="centre").omega
            if np.all(np.isfinite(omega)):
                estimates.append(omega)
    if len(estimates) < 3:
        return None
    values = np.array(estimates)
    n = len(values)
    return np.asarray(np.sqrt((n - 1) / n * np.sum((values - values.mean(axis=0)) ** 2, axis=0)), np.float64)


def _estimators(profile: StereoProfile, rect: StereoRectification, sift: MatchSet, orb: MatchSet | None,
                min_matches: int) -> tuple[dict[str, FloatArray], FloatArray]:
    """Every estimator's omega (rad) by name, and the formal sigma (rad) of the SIFT fit with the lens terms."""
    main = fit_rotation(profile, rect, sift.left, sift.right, model="centre")
    found = {"sift+lens": main.omega,
             "sift": fit_rotation(profile, rect, sift.left, sift.right, model="centre", nuisance=False).omega,
             "sift+lens translation": fit_rotation(profile, rect, sift.left, sift.right, model="translation").omega}
    if orb is not None and orb.count >= min_matches:
        found["orb+lens"] = fit_rotation(profile, rect, orb.left, orb.right, model="centre").omega
        found["orb"] = fit_rotation(profile, rect, orb.left, orb.right, model="centre", nuisance=False).omega
    formal = np.sqrt(np.clip(np.diag(main.covariance), 0, None))
    return {k: v for k, v in found.items() if np.all(np.isfinite(v))}, formal


def estimate_rotation(profile: StereoProfile, rect: StereoRectification, sift: MatchSet, orb: MatchSet | None, *,
                      min_matches: int) -> Estimate:
    """The rotation error (rad, about the right camera's axes) and its sigma from the matches (module docstring);
    NaN throughout when it cannot be estimated."""
    estimators, formal = _estimators(profile, rect, sift, orb, min_matches)
    centre = [v for k, v in estimators.items() if "translation" not in k]
    if "sift+lens" not in estimators or not centre:
        nan = np.full(3, np.nan)
        return Estimate(nan, nan, nan, None, nan, estimators, "not estimated")
    omega = np.mean(centre, axis=0)
    spread = np.max(np.abs(np.array(list(estimators.values())) - omega), axis=0)
    resampled = _jackknife(profile, rect, sift)
    statistical = np.fmax(formal, resampled) if resampled is not None else formal
    floor = lens_floor(profile)
    sigma = np.sqrt(statistical**2 + spread**2 + floor**2)
    parts = ["formal (residual-scaled)" if resampled is None or np.all(formal >= resampled) else "jackknife",
             f"spread of {len(estimators)} estimators ({', '.join(estimators)})"]
    if floor[1] > 0:
        parts.append("lens floor on yaw")
    return Estimate(np.asarray(omega, np.float64), sigma, formal, resampled, spread, estimators, " + ".join(parts))
