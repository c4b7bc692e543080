"""The last guard before a depth-quality figure is printed: a value no depth camera can produce on a plane is
not a measurement, so the frame carrying it is marked not scored, with the figure named, instead of printed.

The limits sit far above any working camera (Intel's D435 targets 2 % plane-fit RMS and 0.08 px sub-pixel RMS; a
poor matcher reaches 1-2 px) and far below what mismatches produce (thousands of percent, hundreds of pixels).
"""

from __future__ import annotations

import math
from typing import Protocol

__all__ = ["MAX_PLANE_FIT_RMS_PCT", "MAX_SUBPIXEL_RMS_PX", "MAX_TEMPORAL_NOISE_PCT", "MAX_Z_ACCURACY_PCT", "Figures",
           "insane_reason", "measured", "sane_value"]

#: Plane-fit RMS above this share of the distance (%) is no measurement of noise.
MAX_PLANE_FIT_RMS_PCT = 25.0
#: Sub-pixel RMS above this many disparity pixels is no sub-pixel figure.
MAX_SUBPIXEL_RMS_PX = 10.0
#: Z accuracy beyond this (± %) means the plane was matched to the wrong place, not measured.
MAX_Z_ACCURACY_PCT = 50.0
#: Temporal noise above this (%) is flicker between mismatches, not noise.
MAX_TEMPORAL_NOISE_PCT = 25.0

_LIMITS = (("plane_fit_rms_pct", "plane-fit RMS", MAX_PLANE_FIT_RMS_PCT, "%"),
           ("subpixel_rms_px", "sub-pixel RMS", MAX_SUBPIXEL_RMS_PX, "px"),
           ("z_accuracy_pct", "Z accuracy", MAX_Z_ACCURACY_PCT, "%"))


class Figures(Protocol):
    """The figures of one frame these checks read: a :class:`~s2r.quality.metrics.FrameQuality` (which imports this
    module, so it is named by its shape here)."""

    @property
    def distance_m(self) -> float | None: ...
    @property
    def z_accuracy_pct(self) -> float | None: ...
    @property
    def plane_fit_rms_pct(self) -> float | None: ...
    @property
    def subpixel_rms_px(self) -> float | None: ...
    @property
    def fill_rate_pct(self) -> float | None: ...
    @property
    def outlier_pct(self) -> float | None: ...
    @property
    def scored(self) -> bool: ...


def sane_value(value: float | None, limit: float) -> bool:
    """True for None (not measured) or a finite value within ``±limit``."""
    return value is None or (math.isfinite(value) and abs(value) <= limit)


def insane_reason(quality: Figures) -> str:
    """Why ``quality``'s figures cannot be measurements ("" when they can): non-finite values, percentages
    outside 0-100, negative counts, or a figure beyond its limit above."""
    problems = []
    for name, label, limit, unit in _LIMITS:
        value = getattr(quality, name)
        if not sane_value(value, limit):
            problems.append(f"{label} would read {value:.4g} {unit} (beyond {limit:g} {unit}: no depth camera's "
                            "noise, the matcher found another surface)")
    for name in ("fill_rate_pct", "outlier_pct"):
        value = getattr(quality, name)
        if value is not None and not (math.isfinite(value) and 0.0 <= value <= 100.0):
            problems.append(f"{name} would read {value} (outside 0-100 %)")
    if quality.distance_m is not None and not (math.isfinite(quality.distance_m) and quality.distance_m > 0):
        problems.append(f"distance would read {quality.distance_m} m")
    return "; ".join(problems)


def measured(quality: Figures) -> bool:
    """True when ``quality`` is scored and every figure of it can be a measurement: what summaries may use."""
    return quality.scored and not insane_reason(quality)
