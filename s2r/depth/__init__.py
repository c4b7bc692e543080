"""Rectification, matching presets and the stereo depth pipeline.

``StereoPipeline(profile, preset=...)`` rectifies with the profile, matches with a preset
(:data:`PRESETS`), post-processes (:data:`STAGES`) and returns a :class:`DepthResult` (disparity in
pixels and depth in metres, NaN where invalid). The pipeline classes load OpenCV on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from s2r.depth.names import PRESETS, STAGES

if TYPE_CHECKING:
    from s2r.depth.pipeline import DepthResult, StereoPipeline

__all__ = ["PRESETS", "STAGES", "DepthResult", "StereoPipeline"]


def __getattr__(name: str) -> Any:
    if name in ("DepthResult", "StereoPipeline"):
        from s2r.depth import pipeline

        return getattr(pipeline, name)
    raise AttributeError(f"module 's2r.depth' has no attribute {name!r}")
