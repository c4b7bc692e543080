"""Depth quality of a recording, Intel's way: per frame on a chessboard's PnP plane (or a flat wall), per bin.

Sources of depth, each in the pixel grid of the image the board is detected in:

- stereo pairs through :class:`s2r.depth.StereoPipeline` with any preset: the board is detected in the RECTIFIED
  left image and its pose solved with the rectified intrinsics (no distortion), so depth, ROI and plane share
  the rectified left camera's frame; ``f B`` is the rectified focal length times the baseline;
- device depth registered to the left image (a D435's depth is in its left infrared camera's frame): the board
  is detected in the raw left image, its pose solved with the profile's left intrinsics and distortion;
  ``f B`` is the left focal length times the profile's baseline.

Temporal noise: frames whose board corners lie within ``REPEAT_PX`` (RMS) of an earlier frame's form one static
pose; each pose seen at least twice gives Intel's temporal noise on that pose's region.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.quality.board import BoardView, find_board, normalised_rays, roi_mask, roi_quad
from s2r.quality.metrics import MISMATCH_NOTE_PCT, FrameQuality, frame_quality, plane_depth, temporal_noise_pct
from s2r.quality.summary import DEFAULT_BINS_M, BinQuality, datasheet_figures, summarise_bins

__all__ = ["REPEAT_PX", "DepthView", "QualityResult", "measure_board_views", "measure_wall_views"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
#: Board corners within this RMS distance (pixels) of an earlier frame's count as the same static pose.
REPEAT_PX = 0.5


@dataclass(frozen=True)
class DepthView:
    """One frame to score: its name, the 8-bit grey image the board is detected in (H, W), the depth in the same
    pixel grid (H, W) float32 metres (NaN no data), that grid's intrinsics K (3x3 px) and distortion D."""

    name: str
    grey: NDArray[np.uint8] | None
    depth_m: NDArray[np.float32]
    K: FloatArray
    D: FloatArray


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

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON (``frames`` with Intel's metric names, ``bins`` the per-bin summary)."""
        return {"profile": self.profile, "source": self.source, "fb_px_m": self.fb_px_m,
                "frames": [f.as_dict() for f in self.frames], "bins": [b.as_dict() for b in self.bins],
                "temporal": self.temporal, "datasheet": self.datasheet}


class _Repeats:
    """Groups frames by static pose and collects each pose's ROI depths for temporal noise."""

    def __init__(self) -> None:
        self.groups: list[tuple[NDArray[np.float32], NDArray[np.bool_], list[FloatArray], float]] = []

    def add(self, corners: NDArray[np.float32], mask: NDArray[np.bool_], depth: NDArray[np.float32],
            distance: float) -> int:
        for k, (ref, ref_mask, depths, _) in enumerate(self.groups):
            if ref.shape == corners.shape and np.sqrt(np.mean(np.sum((ref - corners) ** 2, axis=1))) < REPEAT_PX:
                depths.append(depth[ref_mask].astype(np.float64))
                return k
        self.groups.append((corners, mask, [depth[mask].astype(np.float64)], distance))
        return len(self.groups) - 1

    def noise(self) -> list[dict[str, Any]]:
        out = []
        for k, (_, _, depths, distance) in enumerate(self.groups):
            value = temporal_noise_pct(depths, distance)
            if value is not None:
                out.append({"pose_group": k, "frames": len(depths), "distance_m": distance,
                            "temporal_noise_pct": value})
        return out


def _score_board(view: DepthView, board: BoardView, pattern: tuple[int, int], fb: float
                 ) -> tuple[FrameQuality, NDArray[np.bool_], tuple[float, float] | None]:
    """The frame's metrics on the board's ROI, the ROI mask, and the board's (nearest, farthest) depth in metres
    over the ROI from its PnP plane (None when the plane misses the ROI). A plane's depth over the convex ROI is
    extreme at the ROI's corners, so the span comes from those four rays."""
    h, w = view.depth_m.shape
    mask = roi_mask(board.corners, pattern, (w, h))
    ys, xs = np.nonzero(mask)
    rays = normalised_rays(np.column_stack([xs, ys]).astype(np.float64), view.K, view.D)
    quality = frame_quality(view.name, view.depth_m[mask].astype(np.float64), rays, fb_px_m=fb, truth=board.plane)
    corner_z = plane_depth(board.plane, normalised_rays(roi_quad(board.corners, pattern).astype(np.float64),
                                                        view.K, view.D))
    finite = corner_z[np.isfinite(corner_z)]
    span = (float(finite.min()), float(finite.max())) if finite.size else None
    return quality, mask, span


def _range_note(quality: FrameQuality, span_m: tuple[float, float] | None,
                visible_m: tuple[float, float] | None) -> FrameQuality:
    """Warn (log and the frame's note) when any part of the board lies outside the matcher's depth range.

    The whole board's depth span counts, not its median distance: a board tilted towards the camera can sit at
    a median inside the range while its near edge needs more disparities than the matcher searches, and
    there SGBM returns mismatches that read as enormous noise rather than as "too near".
    """
    if visible_m is None or span_m is None:
        return quality
    near, far = visible_m
    if span_m[0] < near:
        where = f"its nearest part at {span_m[0]:.3f} m is nearer than the matcher sees ({near:.3f} m)"
    elif span_m[1] > far:
        where = f"its farthest part at {span_m[1]:.2f} m is beyond the matcher's {far:.1f} m"
    else:
        return quality
    note = (f"board {where}: its depth there is mismatched, not noisy "
            "(raise num_disparities / lower matcher.min_depth_m)")
    log.warning("%s: %s", quality.image, note)
    return FrameQuality(**{**quality.as_dict(), "note": "; ".join(filter(None, [note, quality.note]))})


def _check_shapes(view: DepthView) -> None:
    if view.grey is not None and view.grey.shape[:2] != view.depth_m.shape:
        g, d = view.grey.shape, view.depth_m.shape
        raise DepthError(f"depth is {d[1]}x{d[0]} but its left image is {g[1]}x{g[0]}", path=view.name,
                         hint="the depth must be registered to the left image's pixel grid (D435: left infrared)")


def measure_board_views(profile: StereoProfile, views: Iterable[DepthView], *, pattern: tuple[int, int],
                        square_m: float, fb_px_m: float, source: str, total: int | None = None,
                        bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M,
                        visible_m: tuple[float, float] | None = None,
                        progress: ProgressCallback | None = None) -> QualityResult:
    """Score every view on its chessboard (``pattern`` inner corners, ``square_m`` metres): see the module
    docstring. Views without a detectable board are listed with a note and no metrics, never dropped.
    ``visible_m`` (near, far metres) is the matcher's depth range: a board outside it gets a warning note."""
    frames: list[FrameQuality] = []
    poses: list[FloatArray | None] = []
    repeats = _Repeats()
    for i, view in enumerate(views):
        _check_shapes(view)
        board = None if view.grey is None else find_board(view.grey, view.K, view.D, pattern, square_m)
        if board is None:
            frames.append(FrameQuality(view.name, None, None, None, None, None, 0, 0,
                                       note=f"no {pattern[0]}x{pattern[1]} chessboard found"))
            poses.append(None)
        else:
            quality, mask, span = _score_board(view, board, pattern, fb_px_m)
            if quality.outlier_pct is not None and quality.outlier_pct > MISMATCH_NOTE_PCT:
                log.warning("%s: %s", quality.image, quality.note)  # the mismatch note, before any range note
            quality = _range_note(quality, span, visible_m)
            group = repeats.add(board.corners, mask, view.depth_m, quality.distance_m or board.plane.offset_m)
            frames.append(FrameQuality(**{**quality.as_dict(), "pose_group": group}))
            poses.append(board.T_cam_board)
        report(progress, i + 1, total or i + 1, "depth quality")
    if not any(f.distance_m is not None for f in frames):
        raise DepthError(f"no {pattern[0]}x{pattern[1]} chessboard found in any of {len(frames)} frames",
                         field="--pattern", hint="check --pattern (INNER corners, e.g. 9x6) and the images")
    temporal = repeats.noise()
    return QualityResult(profile.name, source, fb_px_m, frames,
                         summarise_bins(frames, fb_px_m=fb_px_m, bins=bins,
                                        temporal=[(t["distance_m"], t["temporal_noise_pct"]) for t in temporal]),
                         temporal, datasheet_figures(profile), poses)


def central_roi(shape: tuple[int, int], fraction: float) -> NDArray[np.bool_]:
    """(H, W) mask of the central rectangle spanning ``fraction`` of the width and of the height."""
    if not 0.0 < fraction <= 1.0:
        raise DepthError(f"ROI fraction must be in (0, 1], got {fraction}", field="--roi", hint="e.g. 0.8")
    h, w = shape
    mh, mw = round(h * (1 - fraction) / 2), round(w * (1 - fraction) / 2)
    mask = np.zeros(shape, bool)
    mask[mh:h - mh, mw:w - mw] = True
    return mask


def measure_wall_views(profile: StereoProfile, views: Iterable[DepthView], *, fb_px_m: float, source: str,
                       roi_fraction: float = 0.8, distance_m: float | None = None,
                       bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M,
                       progress: ProgressCallback | None = None,
                       total: int | None = None) -> QualityResult:
    """Flat-wall mode (no board): plane fit, sub-pixel RMS and fill rate on the central ROI of every frame;
    Z accuracy against ``distance_m`` (metres along the optical axis, a fronto-parallel wall) when given.
    All frames are one static pose, so two or more frames also give the temporal noise."""
    frames: list[FrameQuality] = []
    stack: list[FloatArray] = []
    mask: NDArray[np.bool_] | None = None
    rays: FloatArray | None = None
    for i, view in enumerate(views):
        _check_shapes(view)
        if mask is None or mask.shape != view.depth_m.shape:
            mask = central_roi(view.depth_m.shape, roi_fraction)
            ys, xs = np.nonzero(mask)
            rays = normalised_rays(np.column_stack([xs, ys]).astype(np.float64), view.K, view.D)
        assert rays is not None
        values = view.depth_m[mask].astype(np.float64)
        frames.append(frame_quality(view.name, values, rays, fb_px_m=fb_px_m, distance_m=distance_m))
        stack.append(values)
        report(progress, i + 1, total or i + 1, "depth quality")
    if not frames:
        raise DepthError("no frames to score", field="--depth", hint="pass depth images")
    dist = distance_m if distance_m is not None else float(np.median([f.distance_m for f in frames
                                                                       if f.distance_m is not None] or [np.nan]))
    noise = temporal_noise_pct(stack, dist) if len({s.shape for s in stack}) == 1 else None
    temporal = [] if noise is None else [{"pose_group": 0, "frames": len(stack), "distance_m": dist,
                                          "temporal_noise_pct": noise}]
    return QualityResult(profile.name, source, fb_px_m, frames,
                         summarise_bins(frames, fb_px_m=fb_px_m, bins=bins, temporal=[(dist, noise)] if noise else []),
                         temporal, datasheet_figures(profile))

