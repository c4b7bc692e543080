"""Rectification, matching presets and the stereo depth pipeline (the only depth code that imports cv2).

``StereoPipeline(profile, preset=...)`` rectifies with the profile, matches with a preset
(:data:`PRESETS`), post-processes (:data:`STAGES`) and returns a :class:`DepthResult` (disparity in
pixels and depth in metres, NaN where invalid).
"""

from __future__ import annotations

from s2r.depth.pipeline import DepthResult, StereoPipeline
from s2r.depth.postprocess import STAGES
from s2r.depth.presets import PRESETS, MatcherConfig

__all__ = ["PRESETS", "STAGES", "DepthResult", "MatcherConfig", "StereoPipeline"]
