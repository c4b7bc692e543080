"""Static poses of a board recording, found by their corners, and Intel's temporal noise of each pose."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.quality.metrics import temporal_noise_pct
from s2r.quality.sanity import MAX_TEMPORAL_NOISE_PCT, sane_value

__all__ = ["REPEAT_PX", "StaticPoses"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
#: Board corners within this RMS distance (pixels) of an earlier frame's count as the same static pose.
REPEAT_PX = 0.5


class StaticPoses:
    """Groups frames by static pose (corners within ``REPEAT_PX`` RMS of the group's first frame) and keeps each
    scored frame's depth on the group's ROI (the first frame's), for temporal noise."""

    def __init__(self) -> None:
        self.groups: list[tuple[NDArray[np.float32], NDArray[np.bool_], list[FloatArray], float]] = []

    def add(self, corners: NDArray[np.float32], mask: NDArray[np.bool_], depth: NDArray[np.float32],
            distance_m: float, *, scored: bool = True) -> int:
        """The frame's pose group; its ROI depth (``mask`` (H, W) over ``depth`` (H, W) metres) joins the group's
        samples when ``scored``."""
        for k, (ref, ref_mask, depths, _) in enumerate(self.groups):
            if ref.shape == corners.shape and np.sqrt(np.mean(np.sum((ref - corners) ** 2, axis=1))) < REPEAT_PX:
                if scored and ref_mask.shape == depth.shape:
                    depths.append(depth[ref_mask].astype(np.float64))
                return k
        self.groups.append((corners, mask, [depth[mask].astype(np.float64)] if scored else [], distance_m))
        return len(self.groups) - 1

    def noise(self) -> list[dict[str, Any]]:
        """Per group of two or more scored frames: ``pose_group``, ``frames``, ``distance_m`` and Intel's
        ``temporal_noise_pct`` (:func:`s2r.quality.metrics.temporal_noise_pct`); a value beyond
        ``MAX_TEMPORAL_NOISE_PCT`` is logged and left out (flicker between mismatches, not noise)."""
        out = []
        for k, (_, _, depths, distance) in enumerate(self.groups):
            value = temporal_noise_pct(depths)
            if value is not None and not sane_value(value, MAX_TEMPORAL_NOISE_PCT):
                log.warning("pose %d: temporal noise would read %.4g %%: not a measurement, left out", k, value)
                continue
            if value is not None:
                out.append({"pose_group": k, "frames": len(depths), "distance_m": distance,
                            "temporal_noise_pct": value})
        return out
