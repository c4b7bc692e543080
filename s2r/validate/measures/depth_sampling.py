"""Depth-accuracy figures that do not hinge on the draw: jittered distances, bootstrap intervals, sub-pixel RMS.

SGBM's sub-pixel interpolation locks towards integer disparities, so a fronto-parallel plane (one sub-pixel phase
for every pixel) shows a bias that depends on its exact distance. Three things keep the per-bin figures stable:

- plane distances are jittered per frame (log-uniform within ``JITTER`` of the nominal distance, seeded), and
  "span" planes (:mod:`s2r.render.layouts`) cover a 1.5x depth range across the image, so each bin pools many
  sub-pixel phases;
- each bin's median gets a bootstrap confidence interval over FRAMES (the unit the draw varies), from a seeded
  subsample of each frame's pixels;
- the pipeline's own sub-pixel RMS is measured per frame, Intel's way (residuals of the estimated depth to its
  best-fit plane, converted to disparity with f B / Z^2), so the theory line can use it beside Intel's 0.08 px.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from s2r.quality.metrics import frame_quality

__all__ = ["JITTER", "BinSamples", "frame_subpixel_rms", "jitter_distances"]

FloatArray = NDArray[np.float64]
#: Half-width of the per-frame distance jitter, as a fraction of the nominal distance (log-uniform).
JITTER = 0.08
#: Pixels kept per frame and bin for the bootstrap; bootstrap resamples.
_KEEP = 3000
_RESAMPLES = 300
_STRIDE = 3


def jitter_distances(distances_m: Sequence[float], *, seed: int, jitter: float = JITTER) -> tuple[float, ...]:
    """Each distance (metres) times ``exp(U(-log(1 + jitter), log(1 + jitter)))``, seeded: one draw per frame."""
    rng = np.random.default_rng([seed, 9001])
    span = np.log1p(jitter)
    return tuple(float(d * np.exp(rng.uniform(-span, span))) for d in distances_m)


def frame_subpixel_rms(depth_m: NDArray[np.floating], K: FloatArray, fb_px_m: float) -> float | None:
    """Sub-pixel RMS (px) of one planar frame: the valid pixels' depth residuals to their best-fit plane, in
    disparity (Intel's plane-fit definition, :func:`s2r.quality.metrics.frame_quality`). ``depth_m`` is (H, W)
    metres in the rectified left image (NaN invalid), ``K`` its 3x3 intrinsics (no distortion). Every
    ``_STRIDE``-th pixel in each direction is used (a plane fit needs no more, and it keeps validate fast)."""
    h, w = depth_m.shape
    ys, xs = np.mgrid[0:h:_STRIDE, 0:w:_STRIDE]
    rays = np.column_stack([((xs - K[0, 2]) / K[0, 0]).ravel(), ((ys - K[1, 2]) / K[1, 1]).ravel()])
    depth = np.asarray(depth_m, np.float64)[::_STRIDE, ::_STRIDE].ravel()
    return frame_quality("", depth, rays, fb_px_m=fb_px_m).subpixel_rms_px


class BinSamples:
    """Per bin, a seeded subsample of each frame's relative errors (NaN = missing), for bootstrap intervals."""

    def __init__(self, bins: Sequence[tuple[float, float]], seed: int) -> None:
        self.bins = list(bins)
        self.rng = np.random.default_rng([seed, 4242])
        self.per_bin: list[list[FloatArray]] = [[] for _ in self.bins]

    def add(self, truth: FloatArray, rel: FloatArray) -> None:
        """Add one frame's scored pixels: true depth (m) and relative error, both (N,)."""
        for i, (lo, hi) in enumerate(self.bins):
            last = i == len(self.bins) - 1
            values = rel[(truth >= lo) & ((truth <= hi) if last else (truth < hi))]
            if values.size > _KEEP:
                values = self.rng.choice(values, _KEEP, replace=False)
            if values.size:
                self.per_bin[i].append(values)

    def interval(self, i: int, level: float = 0.95) -> tuple[float, float] | None:
        """Bootstrap ``level`` interval (percent) of bin ``i``'s median |error|, resampling frames; None when fewer
        than two frames reach the bin."""
        frames = self.per_bin[i]
        if len(frames) < 2:
            return None
        medians = []
        for _ in range(_RESAMPLES):
            pick = self.rng.integers(0, len(frames), len(frames))
            pooled = np.concatenate([frames[k] for k in pick])
            pooled = pooled[np.isfinite(pooled)]
            if pooled.size:
                medians.append(float(np.median(np.abs(pooled))) * 100.0)
        if not medians:
            return None
        tail = (1.0 - level) / 2.0 * 100.0
        return float(np.percentile(medians, tail)), float(np.percentile(medians, 100.0 - tail))

    def frames_in(self, i: int) -> int:
        """Frames with pixels in bin ``i``."""
        return len(self.per_bin[i])
