"""Sim and real recordings side by side per distance bin: medians over scored frames, bootstrap confidence
intervals over frames, and a verdict per metric and per bin.

A bin's figure is the median over its SCORED frames (frames not scored never count). Its 95 % interval resamples
those frames with replacement (``RESAMPLES`` times, seeded); the gap's interval resamples both sides
independently. A metric passes when ``|sim - real|`` is within its limit; ``certain`` says whether the gap's
interval lies wholly on the same side of the limit as the gap (else more frames would be needed to be sure).
Limits: Z accuracy and plane-fit RMS ``depth_gap_pct`` points, sub-pixel RMS ``subpixel_gap_rel`` of the real
value, fill rate ``fill_gap`` x 100 points.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from s2r.quality.metrics import FrameQuality
from s2r.quality.run import QualityResult
from s2r.quality.sanity import measured
from s2r.quality.summary import DEFAULT_BINS_M
from s2r.validate.tolerances import Tolerances

__all__ = ["METRICS", "RESAMPLES", "bootstrap_median", "compare_bins"]

#: Metrics compared per bin (``outlier_pct`` is shown, not judged).
METRICS = ("z_accuracy_pct", "plane_fit_rms_pct", "subpixel_rms_px", "fill_rate_pct", "outlier_pct")
RESAMPLES = 1000
_LEVEL = 0.95


def _values(frames: Sequence[FrameQuality], metric: str) -> np.ndarray:
    got = [getattr(f, metric) for f in frames]
    return np.asarray([v for v in got if v is not None and np.isfinite(v)], np.float64)


def _medians(values: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    picks = rng.integers(0, values.size, (RESAMPLES, values.size))
    return np.asarray(np.median(values[picks], axis=1), np.float64)


def _interval(samples: np.ndarray) -> tuple[float, float]:
    tail = (1.0 - _LEVEL) / 2.0 * 100.0
    return float(np.percentile(samples, tail)), float(np.percentile(samples, 100.0 - tail))


def bootstrap_median(values: Sequence[float], *, seed: int = 0) -> tuple[float, float] | None:
    """95 % bootstrap interval of the median of ``values`` (resampled with replacement); None under two values."""
    array = np.asarray(values, np.float64)
    if array.size < 2:
        return None
    return _interval(_medians(array, np.random.default_rng([seed, 5150])))


def _limit(metric: str, real: float | None, tol: Tolerances) -> float | None:
    if metric in ("z_accuracy_pct", "plane_fit_rms_pct"):
        return tol.depth_gap_pct
    if metric == "subpixel_rms_px":
        return None if real is None else tol.subpixel_gap_rel * abs(real)
    if metric == "fill_rate_pct":
        return 100.0 * tol.fill_gap
    return None


def _metric(real: Sequence[FrameQuality], sim: Sequence[FrameQuality], metric: str, tol: Tolerances,
            rng: np.random.Generator) -> dict[str, Any]:
    r, s = _values(real, metric), _values(sim, metric)
    out: dict[str, Any] = {"metric": metric, "real": float(np.median(r)) if r.size else None,
                           "sim": float(np.median(s)) if s.size else None, "real_ci": None, "sim_ci": None,
                           "gap": None, "gap_ci": None}
    rs = _medians(r, rng) if r.size >= 2 else None
    ss = _medians(s, rng) if s.size >= 2 else None
    out["real_ci"] = None if rs is None else _interval(rs)
    out["sim_ci"] = None if ss is None else _interval(ss)
    if out["real"] is not None and out["sim"] is not None:
        out["gap"] = out["sim"] - out["real"]
        if rs is not None and ss is not None:
            out["gap_ci"] = _interval(ss - rs)
    limit = _limit(metric, out["real"], tol)
    out["limit"] = limit
    if limit is None:
        out["passed"] = None
        return out
    out["passed"] = out["gap"] is not None and abs(out["gap"]) <= limit
    ci = out["gap_ci"]
    out["certain"] = ci is not None and (max(abs(ci[0]), abs(ci[1])) <= limit if out["passed"]
                                         else (ci[0] > limit or ci[1] < -limit))
    return out


def _in_bin(result: QualityResult, lo: float, hi: float) -> tuple[list[FrameQuality], int]:
    inside = [f for f in result.frames if f.distance_m is not None and lo <= f.distance_m < hi]
    scored = [f for f in inside if measured(f)]
    return scored, len(inside) - len(scored)


def compare_bins(real: QualityResult, sim: QualityResult, tol: Tolerances, *, seed: int = 0,
                 bins: Sequence[tuple[float, float]] = DEFAULT_BINS_M) -> list[dict[str, Any]]:
    """One row per bin holding real or sim frames: each side's frame counts, per metric the medians, intervals,
    gap and verdict (module docstring), and the bin's verdict.

    Row keys: ``lo_m``, ``hi_m``, ``real_frames``, ``sim_frames`` (scored), ``real_not_scored``,
    ``sim_not_scored``, ``real_<metric>``, ``sim_<metric>``, ``metrics`` (one dict per metric), ``verdicts``
    (the judged metrics: ``metric``, ``gap``, ``limit``, ``passed``), ``passed`` (None when the real side has no
    scored frame in the bin: nothing to compare against) and ``verdict`` (text).
    """
    rng = np.random.default_rng([seed, 7321])
    rows = []
    for lo, hi in bins:
        r, r_skip = _in_bin(real, lo, hi)
        s, s_skip = _in_bin(sim, lo, hi)
        if not (r or s or r_skip or s_skip):
            continue
        metrics = [_metric(r, s, m, tol, rng) for m in METRICS]
        row: dict[str, Any] = {"lo_m": lo, "hi_m": hi, "real_frames": len(r), "sim_frames": len(s),
                               "real_not_scored": r_skip, "sim_not_scored": s_skip, "metrics": metrics}
        for m in metrics:
            row[f"real_{m['metric']}"], row[f"sim_{m['metric']}"] = m["real"], m["sim"]
        row["verdicts"] = [{k: m[k] for k in ("metric", "gap", "limit", "passed", "gap_ci", "certain")}
                           for m in metrics if m["limit"] is not None]
        row["passed"], row["verdict"] = _bin_verdict(row)
        rows.append(row)
    return rows


def _bin_verdict(row: dict[str, Any]) -> tuple[bool | None, str]:
    if not row["real_frames"]:
        return None, "not compared: no scored real frame in this bin"
    if not row["sim_frames"]:
        return False, "FAIL: no scored sim frame in this bin"
    failed = [v["metric"].removesuffix("_pct").replace("_", " ") for v in row["verdicts"] if not v["passed"]]
    unsure = any(not v.get("certain") for v in row["verdicts"])
    text = "ok" if not failed else "FAIL: " + ", ".join(failed)
    return not failed, text + (" (uncertain: more frames needed)" if unsure else "")
