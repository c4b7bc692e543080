"""Figures of a depth-quality run (matplotlib, Agg): each metric against distance with its theory lines, and each
frame's image with its region of interest beside its depth image. Returned as PNG data URIs."""

from __future__ import annotations

from typing import Any

import numpy as np

from s2r.htmlreport import figure_to_data_uri
from s2r.profile import DEFAULT_SUBPIXEL_PX
from s2r.quality.metrics import FrameQuality
from s2r.quality.run import FrameImage, QualityResult
from s2r.quality.sanity import measured

__all__ = ["frame_figure", "metric_figures"]

_METRICS = (("z_accuracy_pct", "Z accuracy %"), ("plane_fit_rms_pct", "plane-fit RMS % of distance"),
            ("subpixel_rms_px", "sub-pixel RMS px"), ("fill_rate_pct", "fill rate %"), ("outlier_pct", "outliers %"))


def _measured_subpixel(frames: list[FrameQuality]) -> float | None:
    values = [f.subpixel_rms_px for f in frames if measured(f) and f.subpixel_rms_px is not None]
    return float(np.median(values)) if values else None


def _theory(ax: Any, name: str, result: QualityResult, distances: np.ndarray) -> None:
    """Intel's model (0.08 px), the same model with the measured sub-pixel value, the datasheet's figure."""
    subpx = _measured_subpixel(result.frames)
    if name == "plane_fit_rms_pct":
        for s, style, label in ((DEFAULT_SUBPIXEL_PX, "--", f"theory, Intel's {DEFAULT_SUBPIXEL_PX:g} px"),
                                (subpx, ":", f"theory, measured {subpx or 0:.3g} px")):
            if s is not None:
                ax.plot(distances, 100.0 * distances * s / result.fb_px_m, style, label=label)
    if name == "subpixel_rms_px":
        ax.axhline(DEFAULT_SUBPIXEL_PX, ls="--", color="C1", label=f"Intel's typical {DEFAULT_SUBPIXEL_PX:g} px")
        if subpx is not None:
            ax.axhline(subpx, ls=":", color="C2", label=f"measured median {subpx:.3g} px")
    ds = result.datasheet
    if ds is not None and name == "plane_fit_rms_pct":
        ax.plot([ds["distance_m"]], [ds[name]], "kv", label=f"datasheet: < {ds[name]:g} % at {ds['distance_m']:g} m")
    if ds is not None and name == "z_accuracy_pct":
        ax.errorbar([ds["distance_m"]], [0.0], yerr=[ds[name]], fmt="none", ecolor="k", capsize=6,
                    label=f"datasheet: within ±{ds[name]:g} % at {ds['distance_m']:g} m")


def _caption(name: str, label: str, result: QualityResult) -> str:
    """The figure's caption, naming its lines (they are drawn in the image only)."""
    subpx = _measured_subpixel(result.frames)
    lines = []
    if name == "plane_fit_rms_pct":
        lines.append(f"theory, Intel's model Z s / (f B) with s = {DEFAULT_SUBPIXEL_PX:g} px"
                     + ("" if subpx is None else f" and with the measured s = {subpx:.3g} px"))
    if name == "subpixel_rms_px":
        lines.append(f"Intel's typical {DEFAULT_SUBPIXEL_PX:g} px"
                     + ("" if subpx is None else f" and the measured median {subpx:.3g} px"))
    ds = result.datasheet
    if ds is not None and name in ("z_accuracy_pct", "plane_fit_rms_pct"):
        lines.append(f"datasheet: < {ds[name]:g} % at {ds['distance_m']:g} m")
    return f"{label} against distance" + (f"; lines: {'; '.join(lines)}" if lines else "")


def metric_figures(result: QualityResult) -> list[tuple[str, str]]:
    """(caption, data URI) of each metric against distance: scored frames as points, not-scored frames marked
    on the axis, with the theory lines (Intel's 0.08 px, the measured sub-pixel value, a RealSense datasheet)."""
    import matplotlib.pyplot as plt

    scored = [f for f in result.frames if measured(f) and f.distance_m is not None]
    dropped = [float(f.distance_m) for f in result.frames if not measured(f) and f.distance_m is not None]
    known = [f.distance_m for f in result.frames if f.distance_m is not None]
    if result.datasheet is not None:
        known.append(float(result.datasheet["distance_m"]))
    lo, hi = (min(known), max(known)) if known else (0.1, 1.0)
    distances = np.linspace(max(0.0, lo * 0.9), hi * 1.1, 50)
    out = []
    for name, label in _METRICS:
        fig, ax = plt.subplots(figsize=(6.0, 3.4))
        xs = [float(f.distance_m or 0.0) for f in scored if getattr(f, name) is not None]
        ys = [getattr(f, name) for f in scored if getattr(f, name) is not None]
        ax.plot(xs, ys, "o", color="C0", label=f"scored frames ({len(xs)})")
        if dropped:
            ax.plot(dropped, [0.0] * len(dropped), "x", color="C3", label=f"not scored ({len(dropped)})")
        _theory(ax, name, result, distances)
        ax.set_xlabel("distance m")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        out.append((_caption(name, label, result), figure_to_data_uri(fig)))
    return out


def frame_figure(image: FrameImage, quality: FrameQuality | None) -> str:
    """One frame: its image with the ROI drawn, and its depth image (metres, colour bar), as a data URI."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8.0, 3.0))
    if image.grey is not None:
        axes[0].imshow(image.grey, cmap="gray", vmin=0, vmax=255)
    else:
        axes[0].text(0.5, 0.5, "no image", ha="center", va="center")
    depth = np.asarray(image.depth_m, np.float64)
    finite = depth[np.isfinite(depth) & (depth > 0)]
    lo, hi = (np.percentile(finite, 2), np.percentile(finite, 98)) if finite.size else (0.0, 1.0)
    shown = axes[1].imshow(np.where(np.isfinite(depth), depth, np.nan), cmap="viridis", vmin=lo,
                           vmax=max(hi, lo + 1e-3))
    fig.colorbar(shown, ax=axes[1], label="depth m", fraction=0.046)
    if image.roi is not None:
        quad = np.vstack([image.roi, image.roi[:1]])
        for ax in axes:
            ax.plot(quad[:, 0], quad[:, 1], "-", color="red", lw=1.2)
    for ax in axes:
        ax.set_axis_off()
    status = "not scored" if quality is None or not quality.scored else "scored"
    fig.suptitle(f"{image.name}: {status}", fontsize=9)
    return figure_to_data_uri(fig)
