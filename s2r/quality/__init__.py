"""Depth quality on recordings, Intel's way: board-plane ground truth by PnP, device depth, flat walls."""

from __future__ import annotations

from s2r.quality.metrics import FrameQuality, Plane, fit_plane, frame_quality, not_scored, temporal_noise_pct
from s2r.quality.mismatch import PlaneFit, robust_plane, truth_mismatches
from s2r.quality.run import DepthView, FrameImage, QualityResult, measure_board_views, measure_wall_views
from s2r.quality.sanity import insane_reason
from s2r.quality.source import OpenedSource, RecordingSource, open_source, parse_source
from s2r.quality.summary import DEFAULT_BINS_M, BinQuality, QualityVerdict, datasheet_figures, quality_verdict

__all__ = [
    "DEFAULT_BINS_M",
    "BinQuality",
    "DepthView",
    "FrameImage",
    "FrameQuality",
    "OpenedSource",
    "Plane",
    "PlaneFit",
    "QualityResult",
    "QualityVerdict",
    "RecordingSource",
    "datasheet_figures",
    "fit_plane",
    "frame_quality",
    "insane_reason",
    "measure_board_views",
    "measure_wall_views",
    "not_scored",
    "open_source",
    "parse_source",
    "quality_verdict",
    "robust_plane",
    "temporal_noise_pct",
    "truth_mismatches",
]
