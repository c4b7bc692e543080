"""Intel's depth-quality metrics on a planar target, per frame (numpy only).

Definitions follow Intel's camera depth testing methodology and Depth Quality Tool, computed on the valid pixels
of a region of interest (ROI) of one depth image (metres along the optical axis of the camera whose pixel grid
the depth is in; rays ``(x, y, 1)`` are that camera's undistorted normalised coordinates):

- ``z_accuracy_pct``: median signed depth error against the GROUND-TRUTH plane, ``median((Z - Z_true) / Z_true)``
  in percent (equal to ``median(Z - Z_true) / distance`` on a fronto-parallel target).
- ``plane_fit_rms_pct``: RMS of the residuals to the BEST-FIT plane of the measured points (not the ground
  truth), as a percentage of the distance. Residuals are taken along the depth axis (``Z - Z_fit`` on each pixel's
  ray), the quantity a depth image carries noise in, so a depth image with noise of standard deviation
  ``s * Z`` gives ``s`` in percent whatever the target's tilt.
- ``subpixel_rms_px``: the same residuals in disparity pixels, ``f B dZ / Z_fit^2`` per pixel, then RMS.
- ``fill_rate_pct``: share of ROI pixels with a valid depth (finite, > 0).
- ``distance_m``: median ground-truth depth over the ROI (or the measured median without a ground truth).

The plane is fitted by total least squares (SVD of the centred points), then refitted once on the pixels within
5 robust sigmas (1.4826 MAD of the depth residuals) so that gross mismatches do not tilt it; the RMS keeps EVERY
valid pixel, as Intel's does, so mismatches and flying pixels show in the figure. ``outlier_pct`` says how many
valid pixels lie beyond those 5 sigmas (none in Gaussian noise): a large plane-fit RMS with outliers is
mismatching, not noise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["FrameQuality", "Plane", "fit_plane", "frame_quality", "plane_depth", "temporal_noise_pct"]

FloatArray = NDArray[np.float64]
#: Fewest valid ROI pixels for a plane fit (fewer: the frame is scored for fill rate only).
MIN_FIT_PIXELS = 50


@dataclass(frozen=True)
class Plane:
    """A plane ``normal . P = offset_m`` in a camera frame (metres), ``normal`` a unit vector with
    ``offset_m > 0`` (the camera lies on the side the normal points away from)."""

    normal: tuple[float, float, float]
    offset_m: float

    @property
    def n(self) -> FloatArray:
        """The unit normal as a (3,) array."""
        return np.asarray(self.normal, dtype=np.float64)

    def tilt_deg(self) -> float:
        """Angle between the plane's normal and the optical axis, degrees (0 = fronto-parallel)."""
        return float(np.degrees(np.arccos(min(1.0, abs(self.n[2])))))


@dataclass(frozen=True)
class FrameQuality:
    """Intel's metrics of one frame (see the module docstring); None where not measurable."""

    image: str
    distance_m: float | None
    z_accuracy_pct: float | None
    plane_fit_rms_pct: float | None
    subpixel_rms_px: float | None
    fill_rate_pct: float | None
    roi_pixels: int
    valid_pixels: int
    tilt_deg: float | None = None
    pose_group: int | None = None
    outlier_pct: float | None = None
    note: str = ""

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


#: Share of a frame's valid pixels off the plane (%) above which the frame's note says its RMS measures
#: mismatches: Gaussian noise puts none beyond 5 sigmas, a chessboard's repeating squares matched one period
#: off put 10 % there (the real set's left08 at 160-208 disparities).
MISMATCH_NOTE_PCT = 5.0


def plane_depth(plane: Plane, rays: FloatArray) -> FloatArray:
    """Depth (metres along the optical axis) where each ray ``(N, 2)`` normalised ``(x, y)`` meets ``plane``;
    NaN where the ray is parallel to it or meets it behind the camera."""
    n = plane.n
    denom = rays[:, 0] * n[0] + rays[:, 1] * n[1] + n[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = plane.offset_m / denom
    return np.where(np.isfinite(z) & (z > 0), z, np.nan)


def fit_plane(points: FloatArray) -> Plane:
    """Total-least-squares plane through ``(N, 3)`` points (metres), N >= 3."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    normal = vt[2]
    offset = float(normal @ centre)
    if offset < 0:
        normal, offset = -normal, -offset
    return Plane((float(normal[0]), float(normal[1]), float(normal[2])), offset)


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def frame_quality(image: str, depth_m: FloatArray, rays: FloatArray, *, fb_px_m: float,
                  truth: Plane | None = None, distance_m: float | None = None) -> FrameQuality:
    """Intel's metrics of one frame's ROI.

    Args:
        image: the frame's name (reported as is).
        depth_m: (N,) measured depth of the ROI pixels, metres; NaN, inf or <= 0 mean no data.
        rays: (N, 2) undistorted normalised coordinates ``(x, y)`` of the same pixels.
        fb_px_m: focal length (px) times baseline (m) of the depth's camera pair, for the disparity conversion.
        truth: the ground-truth plane in the same camera frame (a board's PnP pose), if known.
        distance_m: a known target distance (flat wall, metres along the optical axis) when there is no plane.
    """
    depth = np.asarray(depth_m, dtype=np.float64)
    valid = np.isfinite(depth) & (depth > 0)
    n_roi, n_valid = int(depth.size), int(valid.sum())
    fill = 100.0 * n_valid / n_roi if n_roi else None
    truth_z = plane_depth(truth, rays) if truth is not None else None
    if truth_z is not None and np.isfinite(truth_z).any():
        dist: float | None = float(np.nanmedian(truth_z))
    elif distance_m is not None:
        dist = float(distance_m)
    else:
        dist = float(np.median(depth[valid])) if n_valid else None
    tilt = truth.tilt_deg() if truth is not None else None
    if n_valid < MIN_FIT_PIXELS or dist is None:
        return FrameQuality(image, dist, None, None, None, fill, n_roi, n_valid, tilt,
                            note=f"only {n_valid} valid pixels in the region")
    z, xy = depth[valid], rays[valid]
    accuracy = None
    if truth_z is not None:
        zt = truth_z[valid]
        ok = np.isfinite(zt)
        accuracy = float(np.median((z[ok] - zt[ok]) / zt[ok])) * 100.0 if ok.any() else None
    elif distance_m is not None:
        accuracy = float(np.median(z - distance_m)) / distance_m * 100.0
    fitted, outliers = _robust_fit(z, xy)
    ok = np.isfinite(fitted)
    dz = z[ok] - fitted[ok]
    rms_pct = _rms(dz) / dist * 100.0
    subpixel = _rms(fb_px_m * dz / np.square(fitted[ok]))
    outlier_pct = 100.0 * outliers / n_valid
    note = (f"{outlier_pct:.0f} % of the valid pixels are mismatches (beyond 5 robust sigmas of the plane): the "
            "RMS figures measure them, not noise" if outlier_pct > MISMATCH_NOTE_PCT else "")
    return FrameQuality(image, dist, accuracy, rms_pct, subpixel, fill, n_roi, n_valid, tilt,
                        outlier_pct=outlier_pct, note=note)


def _robust_fit(z: FloatArray, xy: FloatArray) -> tuple[FloatArray, int]:
    """Fitted plane depth at each pixel (TLS, then one refit inside 5 robust sigmas) and the outlier count."""
    points = np.column_stack([xy * z[:, None], z])
    fitted = plane_depth(fit_plane(points), xy)
    resid = z - fitted
    finite = np.isfinite(resid)
    mad = float(np.median(np.abs(resid[finite] - np.median(resid[finite])))) if finite.any() else 0.0
    inliers = finite & (np.abs(resid) <= max(5 * 1.4826 * mad, 1e-9))
    if inliers.sum() >= MIN_FIT_PIXELS and inliers.sum() < finite.sum():
        fitted = plane_depth(fit_plane(points[inliers]), xy)
    return fitted, int(finite.sum() - inliers.sum())


def temporal_noise_pct(depths: Sequence[FloatArray], distance_m: float) -> float | None:
    """Temporal noise of one static pose: each ROI pixel's standard deviation across frames (pixels valid in at
    least two frames), pooled over the ROI, as a percentage of ``distance_m``.

    Intel takes the median of the per-pixel standard deviations over many frames; with few frames that median is
    biased low (0.67 sigma at two frames), so the per-pixel unbiased variances are pooled instead,
    ``sqrt(mean(var))``, which equals Intel's figure for many frames of Gaussian noise and stays unbiased for two.

    Args:
        depths: per frame, (N,) depth of the SAME ROI pixels (metres, NaN no data); at least two frames.
    """
    if len(depths) < 2:
        return None
    stack = np.stack([np.where(np.isfinite(d) & (d > 0), d, np.nan) for d in depths]).astype(np.float64)
    keep = np.isfinite(stack).sum(axis=0) >= 2
    if not keep.any():
        return None
    var = np.nanvar(stack[:, keep], axis=0, ddof=1)
    return float(np.sqrt(np.mean(var))) / distance_m * 100.0
