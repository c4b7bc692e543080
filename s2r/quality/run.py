"""Depth quality of a recording, Intel's way: per frame on a chessboard's PnP plane (or a flat wall), per bin.

Sources of depth, each in the pixel grid of the image the board is detected in:

- stereo pairs through :class:`s2r.depth.StereoPipeline` with any preset: the board is detected in the RECTIFIED
  left image and its pose solved with the rectified intrinsics (no distortion), so depth, ROI and plane share
  the rectified left camera's frame; ``f B`` is the rectified focal length times the baseline;
- device depth registered to the left image (a D435's depth is in its left infrared camera's frame): the board
  is detected in the raw left image, its pose solved with the profile's left intrinsics and distortion;
  ``f B`` is the left focal length times the profile's baseline.

A frame is scored on its inliers (:func:`s2r.quality.metrics.frame_quality`) or listed as not scored with the
reason: no board found, the board partly outside the matcher's depth range (stereo: the board's whole depth span
must lie inside what the disparity range sees, or SGBM returns mismatches there: a board nearer than the range is
matched again with the range widened for that frame, said in its note with the range used, and refused only when no
range the matcher supports reaches it), too few valid pixels, mismatches
dominating, a figure that cannot be a measurement. The per-bin summary uses scored frames only.

Temporal noise: frames whose board corners lie within ``REPEAT_PX`` (RMS) of an earlier frame's form one static
pose; each pose scored at least twice gives Intel's temporal noise on that pose's region.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.quality.board import BoardView, find_board, normalised_rays, roi_mask, roi_quad
from s2r.quality.metrics import FrameQuality, frame_quality, not_scored, plane_depth, temporal_noise_pct
from s2r.quality.sanity import MAX_TEMPORAL_NOISE_PCT, sane_value
from s2r.quality.summary import DEFAULT_BINS_M, BinQuality, datasheet_figures, summarise_bins
from s2r.quality.temporal import REPEAT_PX, StaticPoses

__all__ = ["REPEAT_PX", "DepthView", "FrameImage", "QualityResult", "frame_image", "measure_board_views",
           "measure_wall_views", "range_problem", "widened_range"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
#: Largest width (pixels) of the images kept per frame for the report.
THUMB_WIDTH_PX = 320


@dataclass(frozen=True)
class DepthView:
    """One frame to score: its name, the 8-bit grey image the board is detected in (H, W), the depth in the same
    pixel grid (H, W) float32 metres (NaN no data), that grid's intrinsics K (3x3 px) and distortion D.

    Stereo views also carry the matcher's ``disparity_range`` (min_disparity, num_disparities px) and ``rematch``,
    which matches the same pair again with another num_disparities (a board nearer than the range sees is then
    scored with a range widened for that frame)."""

    name: str
    grey: NDArray[np.uint8] | None
    depth_m: NDArray[np.float32]
    K: FloatArray
    D: FloatArray
    disparity_range: tuple[int, int] | None = None
    rematch: Callable[[int], DepthView] | None = None


@dataclass(frozen=True)
class FrameImage:
    """Report material of one frame, downscaled by ``scale`` (<= 1): its grey image (h, w) uint8 or None, its depth
    (h, w) float32 metres (NaN no data) and the ROI's corners (4, 2) in those pixels (None without a board)."""

    name: str
    grey: NDArray[np.uint8] | None
    depth_m: NDArray[np.float32]
    roi: FloatArray | None
    scale: float


def frame_image(view: DepthView, roi: NDArray[Any] | None) -> FrameImage:
    """``view`` downscaled (every k-th pixel) to at most ``THUMB_WIDTH_PX`` wide, with its ROI corners (pixels)."""
    step = max(1, int(np.ceil(view.depth_m.shape[1] / THUMB_WIDTH_PX)))
    grey = None if view.grey is None else np.ascontiguousarray(view.grey[::step, ::step])
    quad = None if roi is None else (np.asarray(roi, np.float64) + 0.5) / step - 0.5
    return FrameImage(view.name, grey, np.ascontiguousarray(view.depth_m[::step, ::step]), quad, 1.0 / step)


@dataclass
class QualityResult:
    """Every frame's metrics, the per-bin summary, temporal noise per repeated pose and the datasheet figures."""

    profile: str
    source: str
    fb_px_m: float
    frames: list[FrameQuality]
    bins: list[BinQuality]
    temporal: list[dict[str, Any]] = field(default_factory=list)
    datasheet: dict[str, Any] | None = None
    poses: list[FloatArray | None] = field(default_factory=list)
    images: list[FrameImage] = field(default_factory=list)

    @property
    def scored(self) -> list[FrameQuality]:
        """The frames scored on their inliers."""
        return [f for f in self.frames if f.scored]

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON (``frames`` with Intel's metric names, ``bins`` the per-bin summary)."""
        return {"profile": self.profile, "source": self.source, "fb_px_m": self.fb_px_m,
                "frames": [f.as_dict() for f in self.frames], "bins": [b.as_dict() for b in self.bins],
                "temporal": self.temporal, "datasheet": self.datasheet}


def _period_px(corners: NDArray[np.float32], pattern: tuple[int, int]) -> float:
    """A chessboard square's size in pixels: the median distance between neighbouring inner corners."""
    cols, rows = pattern
    grid = np.asarray(corners, np.float64).reshape(rows, cols, 2)
    steps = np.concatenate([np.linalg.norm(np.diff(grid, axis=1), axis=2).ravel(),
                            np.linalg.norm(np.diff(grid, axis=0), axis=2).ravel()])
    return float(np.median(steps))


def _score_board(view: DepthView, board: BoardView, pattern: tuple[int, int], fb: float
                 ) -> tuple[FrameQuality, NDArray[np.bool_], tuple[float, float] | None]:
    """The frame's metrics on the board's ROI, the ROI mask, and the board's (nearest, farthest) depth in metres
    over the ROI from its PnP plane (None when the plane misses the ROI). A plane's depth over the convex ROI is
    extreme at the ROI's corners, so the span comes from those four rays."""
    h, w = view.depth_m.shape
    mask = roi_mask(board.corners, pattern, (w, h))
    ys, xs = np.nonzero(mask)
    rays = normalised_rays(np.column_stack([xs, ys]).astype(np.float64), view.K, view.D)
    quality = frame_quality(view.name, view.depth_m[mask].astype(np.float64), rays, fb_px_m=fb, truth=board.plane,
                            period_px=_period_px(board.corners, pattern))
    corner_z = plane_depth(board.plane, normalised_rays(roi_quad(board.corners, pattern).astype(np.float64),
                                                        view.K, view.D))
    finite = corner_z[np.isfinite(corner_z)]
    span = (float(finite.min()), float(finite.max())) if finite.size else None
    return quality, mask, span


def range_problem(span_m: tuple[float, float] | None, visible_m: tuple[float, float] | None, *,
                  fb_px_m: float | None = None) -> str:
    """Why a board spanning ``span_m`` (nearest, farthest metres) is not inside the matcher's ``visible_m`` (near,
    far metres), or ""; with ``fb_px_m`` (f B, px m) the disparity range a too-near board needs is named.

    The whole board's depth span counts, not its median distance: a board tilted towards the camera can sit at
    a median inside the range while its near edge needs more disparities than the matcher searches, and
    there SGBM returns mismatches that read as enormous noise rather than as "too near".
    """
    if visible_m is None or span_m is None:
        return ""
    near, far = visible_m
    if span_m[0] < near:
        need = "" if fb_px_m is None else f" so the search reaches {int(np.ceil(fb_px_m / span_m[0]))} px"
        return (f"board partly nearer than the matcher sees: its nearest part at {span_m[0]:.3f} m, the matcher "
                f"from {near:.3f} m (raise num_disparities{need} / lower matcher.min_depth_m)")
    if span_m[1] > far:
        return (f"board partly beyond the matcher's range: its farthest part at {span_m[1]:.2f} m, the matcher to "
                f"{far:.1f} m (lower min_disparity / raise matcher.max_depth_m)")
    return ""


def _check_shapes(view: DepthView) -> None:
    if view.grey is not None and view.grey.shape[:2] != view.depth_m.shape:
        g, d = view.grey.shape, view.depth_m.shape
        raise DepthError(f"depth is {d[1]}x{d[0]} but its left image is {g[1]}x{g[0]}", path=view.name,
                         hint="the depth must be registered to the left image's pixel grid (D435: left infrared)")


def _log_not_scored(frames: Sequence[FrameQuality], source: str) -> None:
    """One INFO line per frame not scored, one WARNING line counting them (naming ``source``)."""
    skipped = [f for f in frames if not f.scored]
    for f in skipped:  # a figure that could not be a measurement is said loudly; the usual reasons quietly
        level = logging.WARNING if "not a measurement" in f.not_scored else logging.INFO
        log.log(level, "%s: not scored: %s", f.image, f.not_scored)
    if skipped:
        log.warning("%s: %d of %d frames not scored (each with its reason in the table): %s", source, len(skipped),
                    len(frames), ", ".join(f.image for f in skipped))


def widened_range(view: DepthView, near_m: float, fb_px_m: float) -> int | None:
    """The num_disparities (px, a multiple of 16) that sees down to ``near_m`` with a 5 % margin, or None when the
    view cannot be matched again or no range the matcher supports (``min_disparity + num_disparities`` under the
    image width) reaches it."""
    if view.rematch is None or view.disparity_range is None or near_m <= 0:
        return None
    low, _ = view.disparity_range
    need = max(16, int(np.ceil((fb_px_m / (0.95 * near_m) + 1 - low) / 16.0)) * 16)
    return need if low + need < view.depth_m.shape[1] else None


def _widened(view: DepthView, board: BoardView, pattern: tuple[int, int], fb: float,
             span: tuple[float, float] | None, visible_m: tuple[float, float], problem: str
             ) -> tuple[FrameQuality, NDArray[np.bool_]] | str:
    """The frame scored again with a disparity range that sees the board's nearest part, or why it cannot be."""
    assert view.disparity_range is not None and span is not None and view.rematch is not None
    need = widened_range(view, span[0], fb)
    if need is None:
        low = view.disparity_range[0]
        most = (view.depth_m.shape[1] - low - 1) // 16 * 16
        return (f"{problem}; no range the matcher supports sees it (at most {most} px in a "
                f"{view.depth_m.shape[1]} px wide image reaches {fb / max(low + most - 1, 1):.3f} m)")
    again = view.rematch(need)
    quality, mask, span_again = _score_board(again, board, pattern, fb)
    near = fb / max(view.disparity_range[0] + need - 1, 1)
    still = range_problem(span_again, (near, visible_m[1]), fb_px_m=fb)
    if still:
        return f"{problem}; widened to {need} px it is still outside: {still}"
    note = (f"disparity range widened to {need} px for this frame (the board from {span[0]:.3f} m; the matcher's "
            f"{view.disparity_range[1]} px sees from {visible_m[0]:.3f} m)")
    return replace(quality, note="; ".join(filter(None, [quality.note, note]))), mask


def _board_frame(view: DepthView, pattern: tuple[int, int], square_m: float, fb: float,
                 visible_m: tuple[float, float] | None, poses: StaticPoses
                 ) -> tuple[FrameQuality, BoardView | None]:
    board = None if view.grey is None else find_board(view.grey, view.K, view.D, pattern, square_m)
    if board is None:
        return FrameQuality(view.name, None, None, None, None, None, 0, 0,
                            not_scored=f"no {pattern[0]}x{pattern[1]} chessboard found"), None
    quality, mask, span = _score_board(view, board, pattern, fb)
    problem = range_problem(span, visible_m, fb_px_m=fb)
    if problem and visible_m is not None and span is not None and span[0] < visible_m[0] \
            and view.rematch is not None:
        widened = _widened(view, board, pattern, fb, span, visible_m, problem)
        if isinstance(widened, str):
            problem = widened
        else:
            (quality, mask), problem = widened, ""
    if problem:
        quality = not_scored(quality, problem)
    group = poses.add(board.corners, mask, view.depth_m, quality.distance_m or board.plane.offset_m,
                      scored=quality.scored)
    return replace(quality, pose_group=group), board


def measure_board_views(profile: StereoProfile, views: Iterable[DepthView], *, pattern: tuple[int, int],
                        square_m: float, fb_px_m: float, source: str, total: int | None = None,
                        bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M,
                        visible_m: tuple[float, float] | None = None,
                        progress: ProgressCallback | None = None, keep_images: int = 0) -> QualityResult:
    """Score every view on its chessboard (``pattern`` inner corners, ``square_m`` metres): see the module
    docstring. Every view is listed, scored or not scored with the reason, never dropped. ``visible_m`` (near,
    far metres) is the matcher's depth range (stereo); ``keep_images`` keeps that many frames' report images."""
    frames: list[FrameQuality] = []
    poses: list[FloatArray | None] = []
    images: list[FrameImage] = []
    static = StaticPoses()
    for i, view in enumerate(views):
        _check_shapes(view)
        quality, board = _board_frame(view, pattern, square_m, fb_px_m, visible_m, static)
        frames.append(quality)
        poses.append(None if board is None else board.T_cam_board)
        if len(images) < keep_images:
            images.append(frame_image(view, None if board is None else roi_quad(board.corners, pattern)))
        report(progress, i + 1, total or i + 1, "depth quality")
    if not any(f.distance_m is not None for f in frames):
        raise DepthError(f"no {pattern[0]}x{pattern[1]} chessboard found in any of {len(frames)} frames",
                         field="--pattern", hint="check --pattern (INNER corners, e.g. 9x6) and the images")
    _log_not_scored(frames, source)
    temporal = static.noise()
    return QualityResult(profile.name, source, fb_px_m, frames,
                         summarise_bins(frames, fb_px_m=fb_px_m, bins=bins,
                                        temporal=[(t["distance_m"], t["temporal_noise_pct"]) for t in temporal]),
                         temporal, datasheet_figures(profile), poses, images)


def central_roi(shape: tuple[int, int], fraction: float) -> NDArray[np.bool_]:
    """(H, W) mask of the central rectangle spanning ``fraction`` of the width and of the height."""
    if not 0.0 < fraction <= 1.0:
        raise DepthError(f"ROI fraction must be in (0, 1], got {fraction}", field="--roi", hint="e.g. 0.8")
    h, w = shape
    mh, mw = round(h * (1 - fraction) / 2), round(w * (1 - fraction) / 2)
    mask = np.zeros(shape, bool)
    mask[mh:h - mh, mw:w - mw] = True
    return mask


def _wall_temporal(frames: Sequence[FrameQuality], stack: Sequence[FloatArray], distance_m: float | None
                   ) -> list[dict[str, Any]]:
    scored = [s for f, s in zip(frames, stack, strict=True) if f.scored]
    if len(scored) < 2 or len({s.shape for s in scored}) != 1:
        return []
    dist = distance_m if distance_m is not None else float(np.median([f.distance_m for f in frames if f.scored
                                                                       and f.distance_m is not None]))
    noise = temporal_noise_pct(scored)
    if noise is None or not sane_value(noise, MAX_TEMPORAL_NOISE_PCT):
        return []
    return [{"pose_group": 0, "frames": len(scored), "distance_m": dist, "temporal_noise_pct": noise}]


def _wall_roi(view: DepthView, roi_fraction: float) -> tuple[NDArray[np.bool_], FloatArray, FloatArray]:
    mask = central_roi(view.depth_m.shape, roi_fraction)
    ys, xs = np.nonzero(mask)
    rays = normalised_rays(np.column_stack([xs, ys]).astype(np.float64), view.K, view.D)
    h, w = mask.shape
    mh, mw = round(h * (1 - roi_fraction) / 2), round(w * (1 - roi_fraction) / 2)
    quad = np.array([[mw, mh], [w - mw - 1, mh], [w - mw - 1, h - mh - 1], [mw, h - mh - 1]], np.float64)
    return mask, rays, quad


def measure_wall_views(profile: StereoProfile, views: Iterable[DepthView], *, fb_px_m: float, source: str,
                       roi_fraction: float = 0.8, distance_m: float | None = None,
                       bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M,
                       progress: ProgressCallback | None = None,
                       total: int | None = None, keep_images: int = 0) -> QualityResult:
    """Flat-wall mode (no board): plane fit, sub-pixel RMS and fill rate on the central ROI of every frame;
    Z accuracy against ``distance_m`` (metres along the optical axis, a fronto-parallel wall) when given.
    A region that is not one plane is not scored (:func:`s2r.quality.mismatch.planarity_problem`); when no frame
    is scored for that reason, the recording is refused. All frames are one static pose, so two or more scored
    frames also give the temporal noise."""
    frames: list[FrameQuality] = []
    stack: list[FloatArray] = []
    images: list[FrameImage] = []
    roi: tuple[NDArray[np.bool_], FloatArray, FloatArray] | None = None
    for i, view in enumerate(views):
        _check_shapes(view)
        if roi is None or roi[0].shape != view.depth_m.shape:
            roi = _wall_roi(view, roi_fraction)
        values = view.depth_m[roi[0]].astype(np.float64)
        frames.append(frame_quality(view.name, values, roi[1], fb_px_m=fb_px_m, distance_m=distance_m,
                                    require_plane=True))
        stack.append(values)
        if len(images) < keep_images:
            images.append(frame_image(view, roi[2]))
        report(progress, i + 1, total or i + 1, "depth quality")
    if not frames:
        raise DepthError("no frames to score", field="--depth", hint="pass depth images")
    if not any(f.scored for f in frames) and any("not a plane" in f.not_scored for f in frames):
        reason = next(f.not_scored for f in frames if "not a plane" in f.not_scored)
        raise DepthError(f"no frame's region is a plane ({frames[0].image}: {reason})", field="--wall",
                         hint="aim the camera at a flat wall, or pass a smaller --roi")
    _log_not_scored(frames, source)
    temporal = _wall_temporal(frames, stack, distance_m)
    return QualityResult(profile.name, source, fb_px_m, frames,
                         summarise_bins(frames, fb_px_m=fb_px_m, bins=bins,
                                        temporal=[(t["distance_m"], t["temporal_noise_pct"]) for t in temporal]),
                         temporal, datasheet_figures(profile), images=images)
