"""Whether a solved lens model folds over inside the image: a loud check on what the fit figures cannot see.

OpenCV's pinhole distortion moves a point at undistorted normalised radius ``r`` (``sqrt(x^2 + y^2)`` with
``x = X / Z``, ``y = Y / Z`` in the camera's optical frame) to the distorted radius

    r_d(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)

(plumb_bob: k4 = k5 = k6 = 0; the tangential p1 p2 are small and left out here). A camera's model is only usable
where ``r_d`` still grows with ``r``. Where it stops growing (or the denominator reaches zero) the model folds
over: two rays land on one pixel, and a pixel beyond the fold has no undistorted ray at all, so undistortion
and rectification maps go wrong there. The fit cannot see this when no board reached that part of the image:
its residuals, held-out error and even the lens-model comparison are measured where the boards were.

On seven real sets the default k1k2p1p2 fits never fold inside the image (the closest at 103 % of the way to
the farthest corner), while ``--distortion rational`` folds at 41-93 % of the way on three of six single-camera
fits (its numerator and denominator nearly cancel, with coefficients of 50-750), unseen by every other figure.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from s2r.profile import Camera

__all__ = ["FOLD_MODELS", "corner_radius", "fold_radius", "fold_warnings"]

#: The profile distortion models whose radial mapping is checked (the equidistant fisheye model is another
#: mapping and is not).
FOLD_MODELS = ("plumb_bob", "rational_polynomial")
#: Undistorted normalised radius searched for a fold: tan(76 deg), past any pinhole camera's field of view.
_R_SEARCH = 4.0
_SAMPLES = 40_000


def fold_radius(coefficients: Sequence[float], r_search: float = _R_SEARCH) -> float | None:
    """The distorted normalised radius at which the radial mapping stops growing (or its denominator reaches
    zero), for OpenCV coefficients ``k1 k2 p1 p2 [k3 [k4 k5 k6]]``; None when it grows all the way to the
    undistorted radius ``r_search``."""
    k = [float(c) for c in coefficients] + [0.0] * 8
    k1, k2, k3, k4, k5, k6 = k[0], k[1], k[4], k[5], k[6], k[7]
    r = np.linspace(0.0, r_search, _SAMPLES)
    r2 = r * r
    num = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    den = 1 + r2 * (k4 + r2 * (k5 + r2 * k6))
    with np.errstate(divide="ignore", invalid="ignore"):
        rd = r * num / den
    bad = (np.diff(rd) <= 0) | (den[1:] <= 0) | ~np.isfinite(rd[1:])
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    return float(rd[i])


def corner_radius(cam: Camera) -> float:
    """The largest distorted normalised radius of the image's four corner pixels (``(u - cx) / fx`` etc.)."""
    us = np.array([0.0, cam.width_px - 1.0])
    vs = np.array([0.0, cam.height_px - 1.0])
    x, y = (us - cam.cx_px) / cam.fx_px, (vs - cam.cy_px) / cam.fy_px
    return float(np.max(np.hypot(x[:, None], y[None, :])))


def fold_warnings(cameras: Sequence[tuple[str, Camera]]) -> list[str]:
    """One line per camera (``(label, camera)``, label e.g. ``left``) whose lens model folds over inside its
    image, saying how far out and what to do; [] when none does (or the model is not a pinhole polynomial)."""
    out = []
    for label, cam in cameras:
        if cam.distortion.model not in FOLD_MODELS:
            continue
        fold, corner = fold_radius(cam.distortion.coefficients), corner_radius(cam)
        if fold is None or fold >= corner:
            continue
        out.append(f"{label} camera: the {cam.distortion.model} lens model folds over at {100 * fold / corner:.0f} % "
                   "of the way from the image centre to its farthest corner (two rays land on one pixel, so pixels "
                   f"beyond cannot be undistorted or rectified); {_remedy(cam.distortion.coefficients)}")
    return out


def _remedy(coefficients: Sequence[float]) -> str:
    """What to do: drop the higher terms a fit extrapolated (k3, or the rational k4 k5 k6), else cover the
    corners (a lens whose two-term model folds inside the image is wide: the fisheye model may suit it)."""
    if any(float(c) != 0.0 for c in coefficients[4:]):
        return "use fewer lens terms (--distortion k1k2p1p2) or add views with the board near the image corners"
    return "add views with the board near the image corners; a lens this wide may need --lens fisheye"
