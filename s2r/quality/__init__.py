"""Depth quality on recordings, Intel's way: board-plane ground truth by PnP, device depth, flat walls."""

from __future__ import annotations

from s2r.quality.metrics import FrameQuality, Plane, fit_plane, frame_quality, temporal_noise_pct
from s2r.quality.run import DepthView, QualityResult, measure_board_views, measure_wall_views
from s2r.quality.summary import DEFAULT_BINS_M, BinQuality, datasheet_figures

__all__ = [
    "DEFAULT_BINS_M",
    "BinQuality",
    "DepthView",
    "FrameQuality",
    "Plane",
    "QualityResult",
    "datasheet_figures",
    "fit_plane",
    "frame_quality",
    "measure_board_views",
    "measure_wall_views",
    "temporal_noise_pct",
]
