"""Depth accuracy: render ground-truth scenes through a profile, run the depth pipeline, score by distance.

Errors are relative: ``(estimate - truth) / truth`` per pixel of the RECTIFIED left image, against the
renderer's ground-truth depth in that same image (``SceneFrame.depth_rect_m``). Pixels count only where the
truth is finite and the point is visible in the right image too (``x - d_truth >= 0``); the fill rate is the
share of those the pipeline returns a depth for.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.profile import DEFAULT_SUBPIXEL_PX, StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.validate.measures.depth_sampling import BinSamples, frame_subpixel_rms, jitter_distances
from s2r.validate.measures.resolution import theory_rel_rms

__all__ = ["DEFAULT_BINS_M", "BinStats", "DepthAccuracy", "DepthSamples", "bin_stats", "measure_depth_accuracy",
           "pixel_errors", "within_stats"]

#: Distance bins (metres): [lo, hi), the last one closed.
DEFAULT_BINS_M: tuple[tuple[float, float], ...] = ((0.5, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 5.0))

FloatArray = NDArray[np.float64]
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BinStats:
    """Depth errors of the pixels whose true depth lies in [lo_m, hi_m).

    Percentages are of the true depth: ``median_pct``/``p90_pct`` of the absolute relative error, ``bias_pct``
    the median signed relative error; ``fill_rate`` valid estimates / scored pixels; ``theory_lo_pct`` and
    ``theory_hi_pct`` Intel's theoretical RMS at the bin's ends with Intel's 0.08 px sub-pixel error (``None``
    without a profile); ``measured_theory_lo_pct``/``measured_theory_hi_pct`` the same model with the pipeline's
    MEASURED sub-pixel RMS; ``ci_lo_pct``/``ci_hi_pct`` a 95 % bootstrap interval of ``median_pct`` over the
    ``frames`` that reach the bin.
    """

    lo_m: float
    hi_m: float
    pixels: int
    valid: int
    fill_rate: float | None
    median_pct: float | None
    p90_pct: float | None
    bias_pct: float | None
    theory_lo_pct: float | None = None
    theory_hi_pct: float | None = None
    frames: int | None = None
    ci_lo_pct: float | None = None
    ci_hi_pct: float | None = None
    measured_theory_lo_pct: float | None = None
    measured_theory_hi_pct: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


@dataclass(frozen=True)
class DepthSamples:
    """Images of one frame for the report: rendered left (BGR uint8), rectified left, estimated and true
    depth (float32 metres, rectified left image, NaN invalid)."""

    name: str
    left: NDArray[np.uint8]
    rect_left: NDArray[np.uint8]
    depth_m: NDArray[np.float32]
    truth_m: NDArray[np.float32]


@dataclass(frozen=True)
class DepthAccuracy:
    """Depth accuracy of one profile with one preset over the rendered scenes."""

    profile: str
    preset: str
    scenes: tuple[str, ...]
    distances_m: tuple[float, ...]
    bins: list[BinStats]
    within_3m: BinStats
    samples: DepthSamples | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    subpixel_rms_px: float | None = None
    subpixel_frames: int = 0

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON (without the sample images)."""
        return {"profile": self.profile, "preset": self.preset, "scenes": list(self.scenes),
                "distances_m": list(self.distances_m), "bins": [b.as_dict() for b in self.bins],
                "within_3m": self.within_3m.as_dict(), "seconds": self.seconds,
                "subpixel_rms_px": self.subpixel_rms_px, "subpixel_frames": self.subpixel_frames,
                "subpixel_intel_px": DEFAULT_SUBPIXEL_PX}


def pixel_errors(depth_m: NDArray[Any], truth_m: NDArray[Any], disparity_truth_px: NDArray[Any] | None = None
                 ) -> tuple[FloatArray, FloatArray]:
    """``(truth, relative error)`` of the scored pixels (finite truth, visible in both images), shape (N,).

    The relative error is NaN where the estimate is missing (NaN or non-positive).
    """
    truth = np.asarray(truth_m, dtype=np.float64)
    est = np.asarray(depth_m, dtype=np.float64)
    if est.shape != truth.shape:
        raise ValueError(f"depth {est.shape} and truth {truth.shape} must have the same shape")
    scored = np.isfinite(truth) & (truth > 0)
    if disparity_truth_px is not None:
        cols = np.arange(truth.shape[1], dtype=np.float64)[None, :]
        scored &= (cols - np.nan_to_num(np.asarray(disparity_truth_px, np.float64), nan=np.inf)) >= 0
    t = truth[scored]
    e = est[scored]
    rel = np.where(np.isfinite(e) & (e > 0), (e - t) / t, np.nan)
    return t, rel


def _stats(lo: float, hi: float, rel: FloatArray, profile: StereoProfile | None) -> BinStats:
    valid = rel[np.isfinite(rel)]
    n, k = int(rel.size), int(valid.size)
    theory = (None, None) if profile is None else (100 * theory_rel_rms(profile, lo), 100 * theory_rel_rms(profile, hi))
    if k == 0:
        return BinStats(lo, hi, n, k, k / n if n else None, None, None, None, *theory)
    absolute = np.abs(valid) * 100
    return BinStats(lo, hi, n, k, k / n, float(np.median(absolute)), float(np.percentile(absolute, 90)),
                    float(np.median(valid) * 100), *theory)


def bin_stats(truth: FloatArray, rel: FloatArray, bins: Sequence[tuple[float, float]], *,
              profile: StereoProfile | None = None) -> list[BinStats]:
    """Per-bin statistics of relative errors ``rel`` (NaN = missing) of pixels at true depths ``truth``."""
    out = []
    for i, (lo, hi) in enumerate(bins):
        last = i == len(bins) - 1
        mask = (truth >= lo) & ((truth <= hi) if last else (truth < hi))
        out.append(_stats(lo, hi, rel[mask], profile))
    return out


def within_stats(truth: FloatArray, rel: FloatArray, max_m: float = 3.0, *,
                 profile: StereoProfile | None = None) -> BinStats:
    """Statistics over every scored pixel with true depth up to ``max_m`` (the seed's 'within 3 m')."""
    lo = float(np.min(truth)) if truth.size else 0.0
    return _stats(lo, max_m, rel[truth <= max_m], profile)


def _sample_index(frames: Sequence[Any]) -> int:
    """The frame shown in the report: a slanted (or room) frame if any, else the plane nearest 1.5 m."""
    for preferred in ("slanted", "room"):
        found = [i for i, f in enumerate(frames) if f.description.get("scene") == preferred]
        if found:
            return found[len(found) // 2]
    return min(range(len(frames)), key=lambda i: abs(float(np.nanmedian(frames[i].depth_rect_m)) - 1.5))


def _render_all(profile: StereoProfile, scenes: Sequence[tuple[str, Sequence[float]]], *, supersample: int,
                seed: int, jobs: int | None, progress: ProgressCallback | None, renderer: str = "pybullet",
                scene_path: str | None = None, scene_camera: str | None = None
                ) -> tuple[list[Any], list[tuple[str, Sequence[float]]]]:
    """Frames of every scene; scenes after the first are optional (skipped with a warning if unrenderable)."""
    from s2r.render.backend import RendererChoice
    from s2r.render.scenes import render_scene

    frames: list[Any] = []
    rendered: list[tuple[str, Sequence[float]]] = []
    for k, (scene, nominal) in enumerate(scenes):
        distances = nominal if scene == "room" else jitter_distances(nominal, seed=seed + 7919 * k)
        try:
            frames += render_scene(profile, scene=scene, distances_m=tuple(distances), supersample=supersample,
                                   seed=seed, jobs=jobs, progress=progress,
                                   renderer=RendererChoice(renderer, scene_path, scene_camera))
        except RenderError as exc:
            if k == 0:
                raise
            log.warning("%s: %s scene skipped: %s", profile.name, scene, exc)
            continue
        rendered.append((scene, distances))
    return frames, rendered


def measure_depth_accuracy(profile: StereoProfile, *, preset: str = "profile",
                           scenes: Sequence[tuple[str, Sequence[float]]] = (("planes", (0.5, 1.0, 2.0, 3.0, 5.0)),),
                           bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M, supersample: int = 2,
                           seed: int = 0, jobs: int | None = 1,
                           progress: ProgressCallback | None = None, renderer: str = "pybullet",
                           scene_path: str | None = None, scene_camera: str | None = None) -> DepthAccuracy:
    """Render each ``(scene, distances_m)`` through ``profile``, run the depth pipeline with ``preset``, score.

    Plane distances are jittered per frame (:func:`s2r.validate.measures.depth_sampling.jitter_distances`); every
    frame's pixels are pooled and binned by true depth (metres, rectified left frame); each bin gets a bootstrap
    interval over frames, and planar frames give the pipeline's measured sub-pixel RMS.
    """
    from s2r.depth.pipeline import StereoPipeline

    start = time.perf_counter()
    frames, rendered_scenes = _render_all(profile, scenes, supersample=supersample, seed=seed, jobs=jobs,
                                          progress=progress, renderer=renderer, scene_path=scene_path,
                                          scene_camera=scene_camera)
    rendered = time.perf_counter()
    pipeline = StereoPipeline(profile, preset=preset)
    truths, rels, samples = [], [], None
    sampler, subpixel = BinSamples(bins, seed), []
    keep = _sample_index(frames)
    K_rect, fb = pipeline.rectification.P1[:3, :3], pipeline.rectification.fx_px * pipeline.rectification.baseline_m
    for i, frame in enumerate(frames):
        result = pipeline.compute(frame.left, frame.right)
        t, r = pixel_errors(result.depth, frame.depth_rect_m, frame.disparity_rect_px)
        truths.append(t)
        rels.append(r)
        sampler.add(t, r)
        if frame.description.get("scene") in ("planes", "slanted", "span"):
            on_plane = np.where(np.isfinite(frame.depth_rect_m), result.depth, np.nan)
            subpixel.append(frame_subpixel_rms(on_plane, K_rect, fb))
        report(progress, i + 1, len(frames), "depth pipeline")
        if i == keep:
            samples = DepthSamples(f"{frame.description.get('scene', '')} {frame.name}", frame.left,
                                   np.asarray(result.rect_left), result.depth, frame.depth_rect_m)
    matched = time.perf_counter()
    truth, rel = np.concatenate(truths), np.concatenate(rels)
    measured = [v for v in subpixel if v is not None]
    s_px = float(np.median(measured)) if measured else None
    return DepthAccuracy(
        profile=profile.name, preset=preset, scenes=tuple(name for name, _ in rendered_scenes),
        distances_m=tuple(sorted({float(d) for _, ds in rendered_scenes for d in ds})),
        bins=_with_intervals(bin_stats(truth, rel, bins, profile=profile), sampler, profile, s_px),
        within_3m=within_stats(truth, rel, 3.0, profile=profile),
        samples=samples, seconds={"render_scenes": rendered - start, "depth_pipeline": matched - rendered},
        subpixel_rms_px=s_px, subpixel_frames=len(measured),
    )


def _with_intervals(stats: list[BinStats], sampler: BinSamples, profile: StereoProfile, s_px: float | None
                    ) -> list[BinStats]:
    """``stats`` with frame counts, bootstrap intervals and the measured-sub-pixel theory line."""
    out = []
    for i, b in enumerate(stats):
        ci = sampler.interval(i)
        theory = (None, None) if s_px is None else (100 * theory_rel_rms(profile, b.lo_m, subpixel_px=s_px),
                                                     100 * theory_rel_rms(profile, b.hi_m, subpixel_px=s_px))
        out.append(replace(b, frames=sampler.frames_in(i), ci_lo_pct=None if ci is None else ci[0],
                           ci_hi_pct=None if ci is None else ci[1], measured_theory_lo_pct=theory[0],
                           measured_theory_hi_pct=theory[1]))
    return out
