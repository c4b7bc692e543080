"""Intel's depth-quality metrics on a planar target, per frame (numpy only).

Definitions follow Intel's Depth Quality Tool (librealsense ``tools/depth-quality/rs-depth-quality.cpp``) and its
camera depth testing methodology, computed on one depth image's region of interest (ROI; depth in metres along
the optical axis of the camera whose pixel grid it is in; rays ``(x, y, 1)`` are that camera's undistorted
normalised coordinates, so a pixel's point is ``P = z (x, y, 1)``):

- ``fill_rate_pct``: valid pixels (finite, > 0) over ROI pixels, x 100.
- ``plane_fit_rms_pct``: after dropping the nearest and farthest 0.5 % of the points (by z, as Intel sorts them),
  RMS of the points' perpendicular distances to the fitted plane, as a percentage of the distance.
- ``subpixel_rms_px``: over the same points, RMS of ``f B / z - f B / z_plane`` (pixels), ``z_plane`` the fitted
  plane's depth on the pixel's ray: the matcher's disparity error. (Intel's tool takes the point's perpendicular
  foot on the plane instead: the same on the fronto-parallel wall it is made for, but low by cos^2 of the tilt on
  a tilted board.)
- ``z_accuracy_pct``: median over the same points of the signed error of the FITTED plane's depth on each pixel's
  ray against the ground truth, ``(z_fit - z_true) / z_true`` x 100 (positive: the plane fit lies behind the
  truth).
- ``distance_m``: median ground-truth depth over the ROI (a wall's given distance, or the measured median).

Mismatches are not noise, and are kept out of every RMS (:mod:`s2r.quality.mismatch`): pixels whose disparity
lies half a pattern square or more off the ground-truth plane (a chessboard matched a period off), then pixels
beyond a robust band around the plane fitted to the rest. ``outlier_pct`` is their share of the valid pixels.

A frame is scored on its inliers, or not scored with the reason (``FrameQuality.not_scored``): too few valid
pixels, mismatches dominating, a wall that is not a plane, or a figure no depth camera can produce, which
therefore cannot be a measurement (:func:`s2r.quality.sanity.insane_reason`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.quality.mismatch import planarity_problem, robust_plane, truth_mismatches
from s2r.quality.plane import MIN_FIT_PIXELS, Plane, fit_plane, plane_depth
from s2r.quality.sanity import insane_reason

__all__ = ["MIN_FIT_PIXELS", "FrameQuality", "Plane", "fit_plane", "frame_quality", "not_scored", "plane_depth",
           "temporal_noise_pct", "trim_by_depth"]


FloatArray = NDArray[np.float64]
#: Share of a frame's valid pixels off the plane (%) above which its note names the mismatches (excluded from the
#: RMS figures): Gaussian noise puts none there, a chessboard matched one period off 7-20 % (the real OpenCV set).
MISMATCH_NOTE_PCT = 5.0
#: Share of the valid pixels off the plane (%) above which mismatches dominate and the frame is not scored.
MAX_OUTLIER_PCT = 50.0
#: Share of points Intel drops at EACH end (by depth) before its RMS figures: 1/200 = 0.5 %.
TRIM_FRACTION = 1.0 / 200.0


@dataclass(frozen=True)
class FrameQuality:
    """Intel's metrics of one frame (see the module docstring); None where not measured.

    ``not_scored`` is empty for a frame scored on its inliers, else the reason it is not (its RMS figures and Z
    accuracy are then None; distance, fill rate and outlier share stay when they were measured).
    ``inlier_pixels`` counts the valid pixels the figures are computed on (before Intel's 0.5 % trims).
    """

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
    not_scored: str = ""
    inlier_pixels: int | None = None

    @property
    def scored(self) -> bool:
        """True when the frame's figures are measurements on its inliers."""
        return not self.not_scored

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON (with ``scored``)."""
        return {**asdict(self), "scored": self.scored}


def not_scored(quality: FrameQuality, reason: str) -> FrameQuality:
    """``quality`` marked not scored for ``reason``: Z accuracy and both RMS figures dropped (never printed)."""
    reasons = "; ".join(filter(None, [quality.not_scored, reason]))
    return replace(quality, z_accuracy_pct=None, plane_fit_rms_pct=None, subpixel_rms_px=None, not_scored=reasons)


def trim_by_depth(z: FloatArray) -> NDArray[np.intp]:
    """Indices of ``z`` (N,) kept after Intel's trim: sorted by depth, ``N // 200`` dropped at each end."""
    order = np.argsort(z, kind="stable")
    cut = int(z.size * TRIM_FRACTION)
    return order[cut:z.size - cut]


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def _distance(truth_z: FloatArray | None, distance_m: float | None, depth: FloatArray,
              valid: NDArray[np.bool_]) -> float | None:
    if truth_z is not None and np.isfinite(truth_z).any():
        return float(np.nanmedian(truth_z))
    if distance_m is not None:
        return float(distance_m)
    return float(np.median(depth[valid])) if valid.any() else None


def frame_quality(image: str, depth_m: FloatArray, rays: FloatArray, *, fb_px_m: float,
                  truth: Plane | None = None, distance_m: float | None = None, period_px: float | None = None,
                  require_plane: bool = False) -> FrameQuality:
    """Intel's metrics of one frame's ROI on its inliers (module docstring), or the frame not scored with why.

    Args:
        image: the frame's name (reported as is).
        depth_m: (N,) measured depth of the ROI pixels, metres; NaN, inf or <= 0 mean no data.
        rays: (N, 2) undistorted normalised coordinates ``(x, y)`` of the same pixels.
        fb_px_m: focal length (px) times baseline (m) of the depth's camera pair, for the disparity conversion.
        truth: the ground-truth plane in the same camera frame (a board's PnP pose), if known.
        distance_m: a known target distance (flat wall, metres along the optical axis) when there is no plane.
        period_px: the target's pattern period (a chessboard square) in pixels along the image rows; with
            ``truth``, disparities half of it or more off the true plane are mismatches.
        require_plane: refuse (not scored) a region that is not one plane (flat-wall mode).
    """
    depth = np.asarray(depth_m, dtype=np.float64)
    valid = np.isfinite(depth) & (depth > 0)
    n_roi, n_valid = int(depth.size), int(valid.sum())
    truth_z = plane_depth(truth, rays) if truth is not None else None
    dist = _distance(truth_z, distance_m, depth, valid)
    base = FrameQuality(image, dist, None, None, None, 100.0 * n_valid / n_roi if n_roi else None, n_roi, n_valid,
                        truth.tilt_deg() if truth is not None else None)
    if n_valid < MIN_FIT_PIXELS or dist is None:
        return not_scored(base, f"too few valid pixels: {n_valid} in the region (a plane fit needs {MIN_FIT_PIXELS})")
    z, xy = depth[valid], rays[valid]
    zt = truth_z[valid] if truth_z is not None else None
    keep = truth_mismatches(z, zt, fb_px_m=fb_px_m, period_px=period_px)
    fit = robust_plane(z, xy, fb_px_m=fb_px_m, keep=~keep)
    inliers = fit.inliers
    outlier_pct = 100.0 * (n_valid - int(inliers.sum())) / n_valid
    base = replace(base, outlier_pct=outlier_pct, inlier_pixels=int(inliers.sum()))
    if outlier_pct > MAX_OUTLIER_PCT:
        return not_scored(base, f"mismatches dominate: {outlier_pct:.0f} % of the valid pixels lie off the plane")
    if inliers.sum() < MIN_FIT_PIXELS:
        return not_scored(base, f"too few valid pixels: {int(inliers.sum())} inliers remain of {n_valid} valid "
                                f"(a plane fit needs {MIN_FIT_PIXELS})")
    if require_plane:
        problem = planarity_problem(z, xy, fit, fb_px_m=fb_px_m)
        if problem:
            return not_scored(base, f"the region is not a plane: {problem}")
    accuracy, rms, subpixel = _figures(z[inliers], xy[inliers], None if zt is None else zt[inliers], fit.plane,
                                       fb_px_m=fb_px_m, distance_m=dist, wall_m=distance_m)
    note = (f"{outlier_pct:.0f} % of the valid pixels are mismatches (off the plane), excluded from the RMS "
            "figures" if outlier_pct > MISMATCH_NOTE_PCT else "")
    scored = replace(base, note=note, z_accuracy_pct=accuracy, plane_fit_rms_pct=rms, subpixel_rms_px=subpixel)
    reason = insane_reason(scored)
    return not_scored(scored, f"figure not a measurement: {reason}") if reason else scored


def _figures(z: FloatArray, xy: FloatArray, zt: FloatArray | None, plane: Plane, *, fb_px_m: float,
             distance_m: float, wall_m: float | None) -> tuple[float | None, float, float]:
    """Intel's three plane figures on the inliers (trimmed 0.5 % at each end by depth): Z accuracy (%), plane-fit
    RMS (%) and sub-pixel RMS (px)."""
    kept = trim_by_depth(z)
    z, xy = z[kept], xy[kept]
    n = plane.n
    points = np.column_stack([xy * z[:, None], z])
    dist2plane = points @ n - plane.offset_m
    z_fit = plane_depth(plane, xy)
    subpixel = _rms((fb_px_m / z - fb_px_m / z_fit)[np.isfinite(z_fit)])
    accuracy: float | None = None
    if zt is not None:
        zt = zt[kept]
        ok = np.isfinite(zt) & np.isfinite(z_fit)
        accuracy = float(np.median((z_fit[ok] - zt[ok]) / zt[ok])) * 100.0 if ok.any() else None
    elif wall_m is not None:
        ok = np.isfinite(z_fit)
        accuracy = float(np.median(z_fit[ok] - wall_m)) / wall_m * 100.0 if ok.any() else None
    return accuracy, _rms(dist2plane) / distance_m * 100.0, subpixel


def temporal_noise_pct(depths: Sequence[FloatArray], distance_m: float | None = None) -> float | None:
    """Intel's temporal noise of one static pose, in percent.

    Per ROI pixel over the frames, with no-data samples (NaN, zero) dropped: the standard deviation (ddof 1)
    divided by the pixel's median depth; then the median over the ROI pixels seen at least twice, x 100. With
    few frames this median of standard deviations reads low (about 0.67 sigma at two frames, 0.98 sigma at 40:
    Intel's tool uses 40). ``distance_m`` is not used (kept for callers of the earlier signature).

    Args:
        depths: per frame, (N,) depth of the SAME ROI pixels (metres, NaN no data); at least two frames.
    """
    del distance_m
    if len(depths) < 2:
        return None
    stack = np.stack([np.where(np.isfinite(d) & (d > 0), d, np.nan) for d in depths]).astype(np.float64)
    keep = np.isfinite(stack).sum(axis=0) >= 2
    if not keep.any():
        return None
    per_pixel = np.nanstd(stack[:, keep], axis=0, ddof=1) / np.nanmedian(stack[:, keep], axis=0)
    return float(np.median(per_pixel)) * 100.0
