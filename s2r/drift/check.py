"""``s2r check``: is this stereo profile still right? A target-less check from ordinary recordings.

Pipeline: features matched in each pair (:mod:`s2r.drift.matches`, SIFT and ORB), a look for swapped or
upside-down pairs (:mod:`s2r.drift.swap`), the relative-rotation error ``dR`` fitted to their vertical disparity
by several estimators whose spread enters sigma (:mod:`s2r.drift.estimate`), what it costs (rows of mismatch for
SGBM, depth bias at a few distances), and a verdict in degrees and pixels (:mod:`s2r.drift.verdict`): ``good``,
``drifted`` or ``cannot tell``.

What a target-less check cannot see: the baseline's length and the focal lengths' scale (a known size is
needed); every report says so.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.drift.estimate import Estimate, MatchSet, estimate_rotation
from s2r.drift.matches import FrameMatches, RawMatches, detection_scale, gate_matches
from s2r.drift.matching import check_image_sizes, match_pairs, working_profile
from s2r.drift.model import predict_right, robust_scale
from s2r.drift.swap import SwapFinding, find_swap
from s2r.drift.turned import Turn
from s2r.drift.verdict import AXES, Verdict, judge
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback
from s2r.rectification import StereoRectification

__all__ = ["AXES", "BLIND_SPOTS", "CONVENTION", "CheckSettings", "Checked", "DriftResult", "check_drift",
           "check_image_sizes", "match_pairs", "summarise"]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
CONVENTION = ("dR is the error: R_true = dR @ R_profile, dR = exp(omega) with omega = (pitch, yaw, roll) about the "
              "RIGHT camera's optical axes x right, y down, z forward; the correction is the same dR "
              "(R_fixed = dR @ R_profile)")
BLIND_SPOTS = ("A target-less check cannot see the baseline's length or the focal lengths' scale (they need a known "
               "size: recalibrate with a board), nor a principal-point shift that moves both images alike.")
REGION_GRID = (3, 4)  # rows x columns of the vertical-disparity map


@dataclass(frozen=True)
class CheckSettings:
    """Tolerances and limits. ``tolerance_deg`` per axis (pitch, yaw, roll); ``tolerance_px`` on the p95 rows of
    mismatch over the image; ``min_matches`` below which the verdict is "cannot tell"; ``distances_m`` where the
    depth cost is stated."""

    tolerance_deg: tuple[float, float, float] = (0.05, 0.05, 0.05)
    tolerance_px: float = 0.5
    significance: float = 3.0
    min_matches: int = 60
    min_frames_for_resampling: int = 4
    distances_m: tuple[float, ...] = (1.0, 2.0, 4.0)


@dataclass
class DriftResult:
    """Everything ``s2r check`` reports; ``as_dict`` is the ``--json`` document."""

    profile: str
    verdict: str
    reasons: list[str]
    omega_deg: FloatArray
    sigma_deg: FloatArray
    sigma_formal_deg: FloatArray
    sigma_resampled_deg: FloatArray | None
    sigma_source: str
    model_spread_deg: FloatArray  # the largest distance of an estimator from the reported rotation
    frames: list[dict[str, Any]]
    matches: int
    residual_px: float
    vertical_px: dict[str, float]
    region_map_px: list[list[float | None]]
    depth_cost: list[dict[str, float]]
    tolerance_deg: tuple[float, float, float]
    image_size: tuple[int, int]
    points: dict[str, FloatArray] = field(default_factory=dict, repr=False)
    tolerance_px: float = 0.5
    decided_by: str = ""
    unresolved: list[str] = field(default_factory=list)
    estimators_deg: dict[str, FloatArray] = field(default_factory=dict)
    swap: SwapFinding | None = None
    downscaled: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the rotation per axis with sigma, the convention, costs, verdict and blind spots."""
        def axes(v: FloatArray | None) -> dict[str, float] | None:
            return None if v is None else {a: float(x) for a, x in zip(AXES, v, strict=True)}

        return {
            "profile": self.profile, "verdict": self.verdict, "reasons": self.reasons,
            "decided_by": self.decided_by, "unresolved": self.unresolved, "convention": CONVENTION,
            "rotation_error_deg": axes(self.omega_deg), "sigma_deg": axes(self.sigma_deg),
            "sigma_formal_deg": axes(self.sigma_formal_deg), "sigma_resampled_deg": axes(self.sigma_resampled_deg),
            "sigma_source": self.sigma_source, "model_spread_deg": axes(self.model_spread_deg),
            "estimators_deg": {k: axes(v) for k, v in self.estimators_deg.items()},
            "tolerance_deg": dict(zip(AXES, self.tolerance_deg, strict=True)), "tolerance_px": self.tolerance_px,
            "swap": None if self.swap is None else {"found": self.swap.hypothesis, "or": self.swap.alternative,
                                                    "evidence": self.swap.evidence, "fix": self.swap.fix},
            "matches": self.matches, "frames": self.frames, "residual_px": self.residual_px,
            "vertical_disparity_px": self.vertical_px, "region_map_px": self.region_map_px,
            "depth_cost": self.depth_cost, "blind_spots": BLIND_SPOTS, "downscaled": self.downscaled,
        }


def _region_groups(left: FloatArray, size: tuple[int, int]) -> NDArray[np.int_]:
    rows, cols = REGION_GRID
    r = np.clip((left[:, 1] / size[1] * rows).astype(int), 0, rows - 1)
    c = np.clip((left[:, 0] / size[0] * cols).astype(int), 0, cols - 1)
    return np.asarray(r * cols + c, np.int_)


def _region_map(left: FloatArray, dy: FloatArray, size: tuple[int, int]) -> list[list[float | None]]:
    """Median vertical disparity (px) per cell of :data:`REGION_GRID` over the rectified left image."""
    groups = _region_groups(left, size)
    rows, cols = REGION_GRID
    return [[float(np.median(dy[groups == r * cols + c])) if np.any(groups == r * cols + c) else None
             for c in range(cols)] for r in range(rows)]


def rows_of_mismatch(profile: StereoProfile, rect: StereoRectification, omega: FloatArray) -> dict[str, float]:
    """Rows of mismatch (px: median, p95, max over a 17 x 13 grid of the rectified image) that a rotation
    ``omega`` (rad) leaves for far points."""
    w, h = rect.image_size
    u, v = np.meshgrid(np.linspace(0, w - 1, 17), np.linspace(0, h - 1, 13))
    grid = np.column_stack([u.ravel(), v.ravel()])
    far = predict_right(profile, rect, grid, np.zeros(len(grid)), omega, model="centre")
    rows = np.abs(far[:, 1] - grid[:, 1])
    return {"median": float(np.median(rows)), "p95": float(np.percentile(rows, 95)), "max": float(rows.max())}


def _costs(profile: StereoProfile, rect: Any, omega: FloatArray, sigma: FloatArray, distances: tuple[float, ...]
           ) -> tuple[dict[str, float], list[dict[str, float]]]:
    """Rows of mismatch the rotation causes over the image (px) and its depth bias at the image centre (with
    the sigma that yaw's sigma gives it: an unresolved yaw leaves the depth scale open)."""
    if not np.all(np.isfinite(omega)):  # not estimated: no cost to state
        nan = float("nan")
        return ({"median": nan, "p95": nan, "max": nan},
                [{"distance_m": z, "depth_error_m": nan, "depth_error_pct": nan, "depth_error_sigma_pct": nan}
                 for z in distances])
    vertical = rows_of_mismatch(profile, rect, omega)
    centre = np.array([[rect.P1[0, 2], rect.P1[1, 2]]])
    costs = []
    for z in distances:
        z_seen = _seen_depth(profile, rect, centre, z, omega)
        z_sigma = abs(_seen_depth(profile, rect, centre, z, omega + np.array([0.0, sigma[1], 0.0])) - z_seen)
        costs.append({"distance_m": z, "depth_error_m": z_seen - z, "depth_error_pct": 100.0 * (z_seen - z) / z,
                      "depth_error_sigma_pct": 100.0 * z_sigma / z})
    return vertical, costs


def _seen_depth(profile: StereoProfile, rect: Any, centre: FloatArray, z: float, omega: FloatArray) -> float:
    """Depth (m) the profile's rectification reads at the image centre for a point at ``z`` on a rig turned
    by ``omega``."""
    d = rect.fx_px * rect.baseline_m / z
    moved = predict_right(profile, rect, centre, np.array([d]), omega, model="centre")
    seen = float(centre[0, 0] - moved[0, 0] + rect.doffs_px)
    return rect.fx_px * rect.baseline_m / seen if seen > 0 else float("inf")


def _cannot_tell(matches: int, frames: Sequence[FrameMatches], settings: CheckSettings) -> str:
    """Why too few matches: identical images, blur or no texture (one sentence)."""
    identical = [f.name for f in frames if f.identical]
    if identical:
        return (f"left and right are the same image in {len(identical)} of {len(frames)} frames "
                f"({', '.join(identical[:3])}): the recording holds one camera twice")
    why = f"only {matches} usable matches (need {settings.min_matches})"
    blurred = [f.name for f in frames if f.sharpness < 20.0]
    if blurred:
        why += f"; blurred or textureless frames: {', '.join(blurred[:5])}"
    return why + ": record scenes with texture at several depths, camera still"


@dataclass
class Checked:
    """A finished check with what it was made of: the profile as given, the matched frames (raw matches kept, so
    a corrected profile can be checked on them again without detecting again) and the result."""

    profile: StereoProfile
    frames: list[FrameMatches]
    result: DriftResult


def _downscale_note(size: tuple[int, int]) -> str:
    scale = detection_scale(size)
    if scale >= 1.0:
        return ""
    note = (f"{size[0]}x{size[1]} px images downscaled to {round(size[0] * scale)}x{round(size[1] * scale)} for "
            "feature detection (memory and time bounded); matches are measured in full-size pixels")
    log.warning("%s", note)
    return note


def regated(profile: StereoProfile, frames: Sequence[FrameMatches]) -> list[FrameMatches]:
    """``frames`` (matched for some profile of the same images) gated again for ``profile``."""
    working, rect, _ = working_profile(profile)
    out = []
    for f in frames:
        if f.raw is None:
            out.append(f)
            continue
        left, right, behind = gate_matches(working, rect, f.raw)
        out.append(replace(f, left=left, right=right, behind=behind))
    return out


def check_drift(profile: StereoProfile, pairs: Iterable[tuple[str, NDArray[np.uint8], NDArray[np.uint8]]], *,
                settings: CheckSettings = CheckSettings(), progress: ProgressCallback | None = None,
                total: int | None = None, jobs: int = 1) -> DriftResult:
    """Check ``profile`` against raw grey stereo pairs ``(name, left, right)`` of ordinary scenes (matched in
    ``jobs`` processes, see :func:`match_pairs`)."""
    return run_check(profile, pairs, settings=settings, progress=progress, total=total, jobs=jobs).result


def run_check(profile: StereoProfile, pairs: Iterable[tuple[str, NDArray[np.uint8], NDArray[np.uint8]]], *,
              settings: CheckSettings = CheckSettings(), progress: ProgressCallback | None = None,
              total: int | None = None, jobs: int = 1) -> Checked:
    """:func:`check_drift`, keeping the matched frames (for ``--fix`` and its re-check on held-out frames)."""
    frames = match_pairs(profile, pairs, progress=progress, total=total, jobs=jobs)
    result = summarise(profile, frames, settings=settings)
    return Checked(profile, frames, result)


def _match_set(frames: Sequence[FrameMatches], use: str, rect: StereoRectification, profile: StereoProfile,
               by_frame: bool) -> MatchSet:
    """One detector's gated matches over ``frames`` with their jackknife groups (frames, or image regions)."""
    pieces: list[tuple[FloatArray, FloatArray]] = []
    for f in frames:
        if use == "sift":
            pieces.append((f.left, f.right))
        else:
            second: RawMatches | None = f.second
            pieces.append(gate_matches(profile, rect, second)[:2] if second is not None and len(second.left)
                          else (np.zeros((0, 2)), np.zeros((0, 2))))
    left = np.vstack([p[0] for p in pieces]) if pieces else np.zeros((0, 2))
    right = np.vstack([p[1] for p in pieces]) if pieces else np.zeros((0, 2))
    groups = np.concatenate([np.full(len(p[0]), k) for k, p in enumerate(pieces)]) if pieces else np.zeros(0, int)
    return MatchSet(left, right, np.asarray(groups if by_frame else _region_groups(left, rect.image_size), np.int_))


def _estimate(profile: StereoProfile, rect: StereoRectification, frames: Sequence[FrameMatches],
              settings: CheckSettings, swap: SwapFinding | None) -> tuple[Estimate, MatchSet]:
    by_frame = len(frames) >= settings.min_frames_for_resampling
    sift = _match_set(frames, "sift", rect, profile, by_frame)
    if swap is not None or sift.count < max(10, settings.min_matches // 2):  # never a confident number
        nan = np.full(3, np.nan)
        return Estimate(nan, nan, nan, None, nan, {}, "not estimated"), sift
    orb = _match_set(frames, "orb", rect, profile, by_frame)
    estimate = estimate_rotation(profile, rect, sift, orb, min_matches=settings.min_matches)
    where = "frames" if by_frame else "image regions"
    return replace(estimate, source=estimate.source.replace("jackknife", f"jackknife over {where}")), sift


def _back(estimate: Estimate, turn: Turn) -> Estimate:
    """The estimate in the profile's own camera axes (the rig was checked turned on its side)."""
    return replace(estimate, omega=turn.back(estimate.omega), sigma=turn.back_sigma(estimate.sigma),
                   formal=turn.back_sigma(estimate.formal), spread=turn.back_sigma(estimate.spread),
                   resampled=None if estimate.resampled is None else turn.back_sigma(estimate.resampled),
                   estimators={k: turn.back(v) for k, v in estimate.estimators.items()},
                   source=estimate.source + "; vertical rig: fitted with images and profile turned 90 deg, given in "
                   "the profile's axes")


def _judge(profile: StereoProfile, rect: StereoRectification, estimate: Estimate, n: int,
           frames: Sequence[FrameMatches], settings: CheckSettings, turn: Turn | None,
           swap: SwapFinding | None) -> Verdict:
    if swap is not None:
        return Verdict("cannot tell", [swap.sentence()], "", [])
    if n < settings.min_matches or not np.all(np.isfinite(estimate.omega)):
        return Verdict("cannot tell", [_cannot_tell(n, frames, settings)], "", [])
    M = np.eye(3) if turn is None else turn.M
    weak = 1 if turn is None else int(np.argmax(np.abs(turn.M[1])))  # the axis the p2 lens term mimics
    return judge(np.degrees(estimate.omega), np.degrees(estimate.sigma), tolerance_deg=settings.tolerance_deg,
                 tolerance_px=settings.tolerance_px, significance=settings.significance, weak=weak,
                 rows_px=lambda deg: rows_of_mismatch(profile, rect, M @ np.radians(deg)))


def summarise(given: StereoProfile, frames: Sequence[FrameMatches], *, settings: CheckSettings = CheckSettings(),
              look_for_swap: bool = True) -> DriftResult:
    """The fit, sigma, costs and verdict of matched ``frames`` for the profile ``given``; the rotation and its
    sigmas are given in the profile's own camera axes (also for a vertical rig, checked turned)."""
    profile, rect, turn = working_profile(given)
    swap = find_swap(profile, rect, frames) if look_for_swap else None
    estimate, sift = _estimate(profile, rect, frames, settings, swap)
    left, right, n = sift.left, sift.right, sift.count
    omega_turned = estimate.omega
    estimated = bool(n) and bool(np.all(np.isfinite(omega_turned)))
    residual = right[:, 1] - predict_right(profile, rect, left, left[:, 0] - right[:, 0] + rect.doffs_px,
                                           omega_turned, model="centre")[:, 1] if estimated else np.zeros(0)
    vertical, costs = _costs(profile, rect, omega_turned, estimate.sigma, settings.distances_m)
    reported = estimate if turn is None else _back(estimate, turn)
    verdict = _judge(profile, rect, reported, n, frames, settings, turn, swap)
    size = frames[0].raw.size if frames and frames[0].raw is not None else rect.image_size
    return DriftResult(
        profile=given.name, verdict=verdict.verdict, reasons=verdict.reasons,
        omega_deg=np.degrees(reported.omega), sigma_deg=np.degrees(reported.sigma),
        sigma_formal_deg=np.degrees(reported.formal),
        sigma_resampled_deg=None if reported.resampled is None else np.degrees(reported.resampled),
        sigma_source=reported.source, model_spread_deg=np.degrees(reported.spread),
        frames=[{"name": f.name, "matches": f.count, "keypoints": f.keypoints, "sharpness": f.sharpness}
                for f in frames],
        matches=n, residual_px=robust_scale(residual) if estimated else float("nan"), vertical_px=vertical,
        region_map_px=_region_map(left, right[:, 1] - left[:, 1], rect.image_size) if n else [],
        depth_cost=costs, tolerance_deg=settings.tolerance_deg, image_size=rect.image_size,
        points={"left": left, "dy": right[:, 1] - left[:, 1]}, tolerance_px=settings.tolerance_px,
        decided_by=verdict.decided_by, unresolved=verdict.unresolved,
        estimators_deg={k: np.degrees(v) for k, v in reported.estimators.items()}, swap=swap,
        downscaled=_downscale_note(size) if frames else "")
