"""``s2r sensor fit``: a :class:`~s2r.sensor.model.SensorModel` from a chessboard recording.

Image noise and blur come from the raw grey images (left and right of stereo pairs, or a device's left infrared
images): :mod:`s2r.sensor.fit.images`. Depth figures come from device depth (:mod:`s2r.sensor.fit.depth`) or, for
stereo pairs, from the pipeline's depth measured by :mod:`s2r.quality` (sub-pixel RMS and fill rate per frame).

Across frames: sigma_d against distance is a least-squares line (a constant when the boards span under
:data:`MIN_SPAN_M`), reported at 1 m with its slope; fill rate is averaged per distance bin
(:data:`s2r.quality.DEFAULT_BINS_M`) at the bin's mean distance, a bin of fewer than :data:`MIN_FILL_FRAMES`
frames merged with its nearer neighbour (one tilted frame is no fill cliff), and a point that still rests on
fewer (too few frames in all) is flagged with its frame count; the dropout band is the summed excess of
missing pixels over the summed edge length.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from s2r.calib.detect import detect_board
from s2r.errors import DepthError
from s2r.progress import ProgressCallback, report
from s2r.quality.board import find_board
from s2r.quality.metrics import FrameQuality
from s2r.quality.run import DepthView
from s2r.quality.summary import DEFAULT_BINS_M
from s2r.sensor.fit.depth import DepthFrame, depth_frame, hole_scale_px
from s2r.sensor.fit.images import BoardImage, image_blur_px, image_noise_dn
from s2r.sensor.model import FillPoint, SensorModel

__all__ = ["MIN_SPAN_M", "SensorFit", "board_image", "fit_device_depth", "fit_images", "fit_model",
           "stereo_depth_frames"]

#: Smallest spread of board distances (m) over which sigma_d's growth with distance is fitted.
MIN_SPAN_M = 0.3
#: Frames a fill point must rest on; a thinner distance bin is merged with its neighbour.
MIN_FILL_FRAMES = 3
#: Largest disparity noise (px) reported as noise; beyond it the residuals are mismatches (a pattern period off).
_MAX_SIGMA_PX = 5.0


@dataclass
class SensorFit:
    """The fitted model, how each figure was measured, and the per-frame figures behind it."""

    model: SensorModel
    notes: dict[str, str] = field(default_factory=dict)
    frames: list[dict[str, Any]] = field(default_factory=list)
    sigma_by_distance: list[dict[str, float]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON: the model's fields at the top level, the measured sigma_d per distance bin
        (``subpixel_sigma_by_distance``), ``notes`` and ``frames_used``."""
        return {**self.model.model_dump(mode="json"), "subpixel_sigma_by_distance": self.sigma_by_distance,
                "notes": self.notes, "frames_used": self.frames}


def board_image(name: str, image: np.ndarray, pattern: tuple[int, int]) -> BoardImage | None:
    """A raw 8-bit image (grey (H, W) or BGR (H, W, 3)) as grey with its detected chessboard, or None when no
    board is found."""
    grey = np.asarray(image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), np.uint8)
    corners, _ = detect_board(grey, pattern)
    return None if corners is None else BoardImage(name, grey, np.asarray(corners, np.float32), pattern)


def fit_images(images: Sequence[BoardImage]) -> tuple[float | None, float | None, dict[str, str]]:
    """(noise DN, blur px, notes) of raw board images."""
    if not images:
        return None, None, {"images": "no chessboard found in any image"}
    blur, edges = image_blur_px(images)
    noise, how = image_noise_dn(images, blur_px=blur or 1.0)
    return noise, blur, {"image_noise_dn": how, "blur_sigma_px": f"{edges} board edges in {len(images)} images"}


def fit_device_depth(views: Iterable[DepthView], *, pattern: tuple[int, int], square_m: float, fb_px_m: float,
                     progress: ProgressCallback | None = None, total: int | None = None
                     ) -> tuple[list[DepthFrame], list[BoardImage]]:
    """Per-frame depth measurements of device depth views, and their grey images as board images."""
    frames: list[DepthFrame] = []
    images: list[BoardImage] = []
    for i, view in enumerate(views):
        report(progress, i + 1, total or i + 1, "sensor fit")
        if view.grey is None:
            continue
        board = find_board(view.grey, view.K, view.D, pattern, square_m)
        if board is None:
            continue
        images.append(BoardImage(view.name, view.grey, board.corners, pattern))
        frame = depth_frame(view.name, view.depth_m, board, pattern=pattern, K=view.K, D=view.D, fb_px_m=fb_px_m)
        if frame is not None:
            frames.append(frame)
    return frames, images


def stereo_depth_frames(frames: Sequence[FrameQuality]) -> list[DepthFrame]:
    """The pipeline depth's per-frame sub-pixel RMS and fill rate (from :mod:`s2r.quality`) as depth frames.

    Frames :mod:`s2r.quality` does not score (its ``not_scored`` reason: too few valid pixels, mismatches
    dominating, a board outside the matcher's range; where the quality module has no such field, any note)
    measure the matcher's failure, not the sensor, and are left out."""
    return [DepthFrame(f.image, f.distance_m, f.subpixel_rms_px, f.fill_rate_pct, None, None, None)
            for f in frames if f.distance_m is not None and f.fill_rate_pct is not None
            and not getattr(f, "not_scored", f.note)]


def _sigma_line(frames: Sequence[DepthFrame], *, linear: bool) -> tuple[float | None, float]:
    """(sigma_d at 1 m, growth per metre) of the frames' sigma_d against distance (``linear`` False: the median,
    no growth)."""
    pts = np.array([(f.distance_m, f.sigma_d_px) for f in frames if f.sigma_d_px is not None], np.float64)
    if len(pts) == 0:
        return None, 0.0
    if not linear or len(pts) < 3 or np.ptp(pts[:, 0]) < MIN_SPAN_M:
        return float(np.median(pts[:, 1])), 0.0
    slope, intercept = np.polyfit(pts[:, 0], pts[:, 1], 1)
    return max(float(intercept + slope), 0.0), float(slope)


def _fill_groups(frames: Sequence[DepthFrame]) -> tuple[list[list[DepthFrame]], int]:
    """The frames by distance bin, each bin of fewer than :data:`MIN_FILL_FRAMES` frames merged into its nearer
    neighbour (by mean distance), and how many bins were merged."""
    groups = [g for lo, hi in DEFAULT_BINS_M if (g := [f for f in frames if lo <= f.distance_m < hi])]
    merged = 0
    while len(groups) > 1 and min(len(g) for g in groups) < MIN_FILL_FRAMES:
        i = min(range(len(groups)), key=lambda k: len(groups[k]))
        mean = [float(np.mean([f.distance_m for f in g])) for g in groups]
        sides = [j for j in (i - 1, i + 1) if 0 <= j < len(groups)]
        j = min(sides, key=lambda k: abs(mean[k] - mean[i]))
        groups[j] = sorted(groups[j] + groups[i], key=lambda f: f.distance_m)
        del groups[i]
        merged += 1
    return groups, merged


def _fill_curve(frames: Sequence[DepthFrame]) -> tuple[tuple[FillPoint, ...], str]:
    """Fill points per distance bin (module docstring) and the note that says how they rest on frames."""
    groups, merged = _fill_groups(frames)
    points = tuple(FillPoint(distance_m=float(np.mean([f.distance_m for f in g])),
                             fill_rate_pct=float(np.mean([f.fill_pct for f in g])), frames=len(g)) for g in groups)
    thin = [p for p in points if p.frames is not None and p.frames < MIN_FILL_FRAMES]
    note = f"{len(points)} point(s) from {len(frames)} frames"
    if merged:
        note += f"; {merged} bin(s) of fewer than {MIN_FILL_FRAMES} frames merged with their neighbours"
    if thin:
        note += "; FEW FRAMES: " + ", ".join(f"{p.distance_m:.2f} m rests on {p.frames}" for p in thin)
    return points, note


def _sigma_by_bin(frames: Sequence[DepthFrame]) -> list[dict[str, float]]:
    """Measured sigma_d per distance bin: mean distance and median sigma_d of the bin's frames."""
    out = []
    for lo, hi in DEFAULT_BINS_M:
        inside = [f for f in frames if lo <= f.distance_m < hi and f.sigma_d_px is not None]
        if inside:
            out.append({"distance_m": float(np.mean([f.distance_m for f in inside])),
                        "subpixel_sigma_px": float(np.median([f.sigma_d_px for f in inside]))})
    return out


def _band_px(frames: Sequence[DepthFrame]) -> float | None:
    pairs = [(f.band_missing_px, f.edge_length_px) for f in frames
             if f.band_missing_px is not None and f.edge_length_px is not None]
    length = sum(b for _, b in pairs)
    return sum(a for a, _ in pairs) / length if length > 0 else None


def fit_model(images: Sequence[BoardImage], depth: Sequence[DepthFrame], *, source: str, stereo_frames: int = 0
              ) -> SensorFit:
    """The sensor model of the measured images and depth frames (module docstring); ``stereo_frames``: how many
    stereo frames were measured before :func:`stereo_depth_frames` left the flagged ones out (for the notes)."""
    if not images and not depth:
        raise DepthError("no chessboard found in any frame", field="--pattern",
                         hint="check --pattern (INNER corners, e.g. 9x6) and the images")
    noise, blur, notes = fit_images(images)
    device = any(f.transitions is not None for f in depth)  # stereo frames: the pipeline's RMS, no line
    sigma, growth = _sigma_line(depth, linear=device)
    band = _band_px(depth)
    holes = hole_scale_px(list(depth))
    if not depth and stereo_frames:
        notes["subpixel_sigma_px"] = f"none of {stereo_frames} stereo frames scored without a note (see depth-quality)"
    if depth:
        near, far = min(f.distance_m for f in depth), max(f.distance_m for f in depth)
        notes["subpixel_sigma_px"] = f"{sum(f.sigma_d_px is not None for f in depth)} frames, {near:.2f}-{far:.2f} m"
    if device:
        notes["edge_dropout_px"] = "measured" if band is not None else "no depth edges away from the image border"
    if sigma is not None and sigma > _MAX_SIGMA_PX:  # mismatches, not noise: no figure rather than a false one
        notes["subpixel_sigma_px"] = f"{sigma:.3g} px measured: mismatches, not noise; left out"
        sigma, growth = None, 0.0
    fill, notes["fill_rate_by_distance"] = _fill_curve(depth) if depth else ((), "no depth frames")
    model = SensorModel(image_noise_dn=noise, blur_sigma_px=blur, subpixel_sigma_px=sigma,
                        subpixel_growth_px_per_m=growth, fill_rate_by_distance=fill,
                        hole_scale_px=holes or 0.0, edge_dropout_px=band, source=source,
                        frames=max(len(images), len(depth)))
    rows = [{"image": f.name, "distance_m": f.distance_m, "sigma_d_px": f.sigma_d_px, "fill_rate_pct": f.fill_pct}
            for f in depth]
    return SensorFit(model, notes, rows, _sigma_by_bin(depth))
