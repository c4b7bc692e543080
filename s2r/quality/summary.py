"""Per-distance-bin summaries of frame metrics, Intel's theory line and the RealSense datasheet figures."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from s2r.profile import DEFAULT_SUBPIXEL_PX, StereoProfile
from s2r.quality.metrics import FrameQuality
from s2r.quality.sanity import measured

__all__ = ["DEFAULT_BINS_M", "BinQuality", "QualityVerdict", "datasheet_figures", "quality_verdict", "summarise_bins"]

#: Distance bins (metres, [lo, hi)) of the per-bin summary, finer near the camera where boards are usually
#: recorded (and where a few centimetres change the error most); empty bins are left out.
_EDGES_M = (0.0, 0.3, 0.4, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 7.0, 10.0, 20.0)
DEFAULT_BINS_M: tuple[tuple[float, float], ...] = tuple(pairwise(_EDGES_M))


@dataclass(frozen=True)
class BinQuality:
    """Medians over the SCORED frames whose distance lies in [lo_m, hi_m); percentages of the distance.
    ``frames`` counts those scored frames, ``not_scored`` the bin's frames that were not scored (with a reason).

    ``temporal_noise_pct`` is the median over repeated poses in the bin (None without repeats);
    ``theory_rms_pct`` Intel's model ``Z s / (f B)`` at the bin's median distance with s = 0.08 px.
    """

    lo_m: float
    hi_m: float
    frames: int
    distance_m: float | None
    z_accuracy_pct: float | None
    plane_fit_rms_pct: float | None
    subpixel_rms_px: float | None
    fill_rate_pct: float | None
    temporal_noise_pct: float | None
    theory_rms_pct: float | None
    not_scored: int = 0
    outlier_pct: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


def _median(values: Sequence[float | None]) -> float | None:
    kept = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.median(kept)) if kept else None


def summarise_bins(frames: Sequence[FrameQuality], *, fb_px_m: float,
                   temporal: Sequence[tuple[float, float]] = (),
                   bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M) -> list[BinQuality]:
    """Per-bin medians of the scored ``frames`` (frames without a distance are skipped; a bin of frames none of
    which is scored is listed with its count and no figures); ``temporal`` holds
    ``(distance_m, temporal_noise_pct)`` of each repeated pose; ``fb_px_m`` is f (px) times B (m)."""
    out = []
    for lo, hi in bins:
        near = [f for f in frames if f.distance_m is not None and lo <= f.distance_m < hi]
        inside = [f for f in near if measured(f)]
        if not inside:
            if near:
                out.append(BinQuality(lo, hi, 0, _median([f.distance_m for f in near]), None, None, None, None, None,
                                      None, len(near)))
            continue
        dist = _median([f.distance_m for f in inside])
        out.append(BinQuality(
            lo, hi, len(inside), dist, _median([f.z_accuracy_pct for f in inside]),
            _median([f.plane_fit_rms_pct for f in inside]), _median([f.subpixel_rms_px for f in inside]),
            _median([f.fill_rate_pct for f in inside]), _median([t for d, t in temporal if lo <= d < hi]),
            None if dist is None else 100.0 * dist * DEFAULT_SUBPIXEL_PX / fb_px_m, len(near) - len(inside),
            _median([f.outlier_pct for f in inside])))
    return out


def datasheet_figures(profile: StereoProfile) -> dict[str, Any] | None:
    """The RealSense D400 datasheet's depth-quality targets for a RealSense profile (None otherwise)."""
    text = f"{profile.name} {profile.provenance.model_dump_json()}".lower()
    if "realsense" not in text and "d435" not in text and "d415" not in text and "d455" not in text:
        return None
    return {"source": "Intel RealSense D400 Series datasheet (document 337029), depth quality specification",
            "distance_m": 2.0, "roi": "80 % of the field of view",
            "z_accuracy_pct": 2.0, "plane_fit_rms_pct": 2.0,
            "note": "targets for the device's own depth (active projector, at 2 m); sub-pixel model 0.08 px"}


@dataclass(frozen=True)
class QualityVerdict:
    """A recording's verdict: ``level`` "good" / "check" / "poor", a one-line ``headline`` and the ``reasons``."""

    level: str
    headline: str
    reasons: tuple[str, ...]

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return {"level": self.level, "headline": self.headline, "reasons": list(self.reasons)}


def _not_scored_reasons(frames: Sequence[FrameQuality]) -> list[str]:
    counts: dict[str, int] = {}
    for f in frames:
        if not measured(f):
            key = (f.not_scored or "figure not a measurement").split(":")[0].split(" (")[0]
            counts[key] = counts.get(key, 0) + 1
    return [f"{n} frame(s): {why}" for why, n in sorted(counts.items(), key=lambda kv: -kv[1])]


def quality_verdict(frames: Sequence[FrameQuality], datasheet: dict[str, Any] | None = None) -> QualityVerdict:
    """"poor" when no frame is scored or the median Z accuracy exceeds the datasheet's limit (2 % without one);
    "check" when some frames are not scored or mismatches exceed 5 % of a scored frame; else "good"."""
    scored = [f for f in frames if measured(f)]
    if not scored:
        return QualityVerdict("poor", f"no frame of {len(frames)} could be scored", tuple(_not_scored_reasons(frames)))
    limit = float(datasheet["z_accuracy_pct"]) if datasheet else 2.0
    accuracy = _median([f.z_accuracy_pct for f in scored])
    rms = _median([f.plane_fit_rms_pct for f in scored])
    subpx = _median([f.subpixel_rms_px for f in scored])
    figures = (f"{len(scored)}/{len(frames)} frames scored; median Z accuracy "
               f"{'-' if accuracy is None else f'{accuracy:+.2f} %'}, plane-fit RMS "
               f"{'-' if rms is None else f'{rms:.2f} %'}, sub-pixel RMS {'-' if subpx is None else f'{subpx:.3f} px'}"
               " (Intel's typical 0.08 px)")
    reasons = _not_scored_reasons(frames)
    mismatched = [f.image for f in scored if (f.outlier_pct or 0.0) > 5.0]
    if mismatched:
        reasons.append(f"{len(mismatched)} scored frame(s) with more than 5 % mismatches (excluded from the RMS): "
                       + ", ".join(mismatched))
    if accuracy is not None and abs(accuracy) > limit:
        return QualityVerdict("poor", f"Z accuracy {accuracy:+.2f} % beyond {limit:g} %: {figures}", tuple(reasons))
    return QualityVerdict("check" if reasons else "good", figures, tuple(reasons))
