"""``s2r check``: is this stereo profile still right? A target-less check from ordinary recordings.

Pipeline: features matched in each pair (:mod:`s2r.drift.matches`), the relative-rotation error ``dR`` fitted
to their vertical disparity (:mod:`s2r.drift.model`), its sigma made honest by resampling frames (or image
regions for a single frame), what it costs (rows of mismatch for SGBM, depth bias at a few distances), and a
verdict: ``good``, ``drifted`` or ``cannot tell``.

What a target-less check cannot see: the baseline's length and the focal lengths' scale (a known size is
needed); every report says so.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.drift.matches import FrameMatches, match_frame
from s2r.drift.model import MODELS, fit_rotation, predict_right, robust_scale
from s2r.drift.turned import Turn, side_by_side_turn
from s2r.errors import CheckError
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.rectification import stereo_rectification

__all__ = ["AXES", "BLIND_SPOTS", "CONVENTION", "CheckSettings", "DriftResult", "check_drift", "check_image_sizes"]

FloatArray = NDArray[np.float64]
AXES = ("pitch", "yaw", "roll")  # about the right camera's optical x, y, z
CONVENTION = ("dR is the error: R_true = dR @ R_profile, dR = exp(omega) with omega = (pitch, yaw, roll) about the "
              "RIGHT camera's optical axes x right, y down, z forward; the correction is the same dR "
              "(R_fixed = dR @ R_profile)")
BLIND_SPOTS = ("A target-less check cannot see the baseline's length or the focal lengths' scale (they need a known "
               "size: recalibrate with a board), nor a principal-point shift that moves both images alike.")
REGION_GRID = (3, 4)  # rows x columns of the vertical-disparity map
#: Typical uncertainty of a calibrated lens' decentering coefficients (p1, p2): a few 1e-4 (REFERENCE.md).
TANGENTIAL_SIGMA = 2.5e-4


@dataclass(frozen=True)
class CheckSettings:
    """Tolerances and limits. ``tolerance_deg`` per axis (pitch, yaw, roll); ``min_matches`` below which the
    verdict is "cannot tell"; ``distances_m`` where the depth cost is stated."""

    tolerance_deg: tuple[float, float, float] = (0.05, 0.05, 0.05)
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
    sigma_source: str  # which of formal / resampled is larger, plus the model spread and lens floor
    model_spread_deg: FloatArray
    frames: list[dict[str, Any]]
    matches: int
    residual_px: float
    vertical_px: dict[str, float]
    region_map_px: list[list[float | None]]
    depth_cost: list[dict[str, float]]
    tolerance_deg: tuple[float, float, float]
    image_size: tuple[int, int]
    points: dict[str, FloatArray] = field(default_factory=dict, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the rotation per axis with sigma, the convention, costs, verdict and blind spots."""
        return {
            "profile": self.profile, "verdict": self.verdict, "reasons": self.reasons,
            "convention": CONVENTION,
            "rotation_error_deg": {a: float(v) for a, v in zip(AXES, self.omega_deg, strict=True)},
            "sigma_deg": {a: float(v) for a, v in zip(AXES, self.sigma_deg, strict=True)},
            "sigma_formal_deg": {a: float(v) for a, v in zip(AXES, self.sigma_formal_deg, strict=True)},
            "sigma_resampled_deg": None if self.sigma_resampled_deg is None else
            {a: float(v) for a, v in zip(AXES, self.sigma_resampled_deg, strict=True)},
            "sigma_source": self.sigma_source,
            "model_spread_deg": {a: float(v) for a, v in zip(AXES, self.model_spread_deg, strict=True)},
            "tolerance_deg": dict(zip(AXES, self.tolerance_deg, strict=True)),
            "matches": self.matches, "frames": self.frames, "residual_px": self.residual_px,
            "vertical_disparity_px": self.vertical_px, "region_map_px": self.region_map_px,
            "depth_cost": self.depth_cost, "blind_spots": BLIND_SPOTS,
        }


def _fit_both(profile: StereoProfile, rect: Any, left: FloatArray, right: FloatArray
              ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Mean omega of the two physical models, their formal covariance (the larger) and their half-difference."""
    fits = [fit_rotation(profile, rect, left, right, model=m) for m in MODELS]
    omegas = np.array([f.omega for f in fits])
    covariance = fits[0].covariance if np.trace(fits[0].covariance) >= np.trace(fits[1].covariance) \
        else fits[1].covariance
    return omegas.mean(axis=0), covariance, np.abs(omegas[0] - omegas[1]) / 2.0


def _resampled(profile: StereoProfile, rect: Any, groups: NDArray[np.int_], left: FloatArray,
               right: FloatArray) -> FloatArray | None:
    """Jackknife sigma (rad) of omega over ``groups`` (frames, or image regions); None with under 3 groups."""
    labels = np.unique(groups)
    if len(labels) < 3:
        return None
    estimates = []
    for label in labels:
        keep = groups != label
        if keep.sum() >= 10:
            estimates.append(fit_rotation(profile, rect, left[keep], right[keep], model="centre").omega)
    if len(estimates) < 3:
        return None
    values = np.array(estimates)
    n = len(values)
    return np.asarray(np.sqrt((n - 1) / n * np.sum((values - values.mean(axis=0)) ** 2, axis=0)), np.float64)


def _lens_floor(profile: StereoProfile) -> FloatArray:
    """(3,) rad of sigma that lens-model error adds: yaw only, and only for a lens with distortion.

    Yaw's vertical disparity (``x y``) is the decentering term p2's pattern to first order; a calibration
    leaves p2 uncertain by about :data:`TANGENTIAL_SIGMA`, which reads as ``2 p2`` rad of yaw.
    """
    distorted = not (profile.left.distortion.is_zero and profile.right.distortion.is_zero)
    return np.array([0.0, 2.0 * TANGENTIAL_SIGMA if distorted else 0.0, 0.0])


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


def _costs(profile: StereoProfile, rect: Any, omega: FloatArray, sigma: FloatArray, distances: tuple[float, ...]
           ) -> tuple[dict[str, float], list[dict[str, float]]]:
    """Rows of mismatch the rotation causes over the image (px) and its depth bias at the image centre (with
    the sigma that yaw's sigma gives it: an unresolved yaw leaves the depth scale open)."""
    if not np.all(np.isfinite(omega)):  # not estimated: no cost to state
        nan = float("nan")
        return ({"median": nan, "p95": nan, "max": nan},
                [{"distance_m": z, "depth_error_m": nan, "depth_error_pct": nan, "depth_error_sigma_pct": nan}
                 for z in distances])
    w, h = rect.image_size
    u, v = np.meshgrid(np.linspace(0, w - 1, 17), np.linspace(0, h - 1, 13))
    grid = np.column_stack([u.ravel(), v.ravel()])
    far = predict_right(profile, rect, grid, np.zeros(len(grid)), omega, model="centre")
    rows = np.abs(far[:, 1] - grid[:, 1])
    vertical = {"median": float(np.median(rows)), "p95": float(np.percentile(rows, 95)), "max": float(rows.max())}
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


def _looks_swapped(matches: int, frames: list[FrameMatches], settings: CheckSettings) -> bool:
    """Many matches lie clearly behind the rig (a quarter or more; a good pair has only stray mismatches there):
    the left and right images (or cameras) are swapped. Far points stay near zero disparity either way, so a
    swapped pair of a mostly distant scene still has matches "in front"."""
    behind = sum(f.behind for f in frames)
    return behind >= max(settings.min_matches // 2, 0.25 * (matches + behind))


def _cannot_tell(matches: int, frames: list[FrameMatches], settings: CheckSettings) -> str:
    """Why too few matches: identical images, a swapped pair, blur or no texture (one sentence)."""
    identical = [f.name for f in frames if f.identical]
    if identical:
        return (f"left and right are the same image in {len(identical)} of {len(frames)} frames "
                f"({', '.join(identical[:3])}): the recording holds one camera twice")
    behind = sum(f.behind for f in frames)
    if _looks_swapped(matches, frames, settings):
        return (f"left and right look swapped: {behind} matches lie behind the rig (negative disparity) against "
                f"{matches} in front; swap the recording's left and right (or the profile's cameras)")
    why = f"only {matches} usable matches (need {settings.min_matches})"
    blurred = [f.name for f in frames if f.sharpness < 20.0]
    if blurred:
        why += f"; blurred or textureless frames: {', '.join(blurred[:5])}"
    return why + ": record scenes with texture at several depths, camera still"


def _verdict(omega_deg: FloatArray, sigma_deg: FloatArray, matches: int, frames: list[FrameMatches],
             settings: CheckSettings, *, weak: int = 1) -> tuple[str, list[str]]:
    """Verdict and reasons; ``weak`` is the axis (index into :data:`AXES`) that may stay unresolved."""
    tol = np.asarray(settings.tolerance_deg)
    if matches < settings.min_matches or not np.all(np.isfinite(omega_deg)) or _looks_swapped(matches, frames,
                                                                                               settings):
        return "cannot tell", [_cannot_tell(matches, frames, settings)]
    drifted = [f"{a} {o:+.3f} deg (+/- {s:.3f}) beyond {t:g} deg" for a, o, s, t in
               zip(AXES, omega_deg, sigma_deg, tol, strict=True)
               if abs(o) > t and abs(o) > settings.significance * s]
    if drifted:
        return "drifted", drifted
    unresolved = [f"{a}: sigma {s:.3f} deg is over half the {t:g} deg tolerance" for a, s, t in
                  zip(AXES, sigma_deg, tol, strict=True) if s > t / 2.0 and a != AXES[weak]]
    if unresolved:
        return "cannot tell", [*unresolved, "more frames with texture across the whole image narrow it"]
    judged = [(a, t) for a, s, t in zip(AXES, sigma_deg, tol, strict=True) if s <= t / 2.0]
    reasons = [f"{', '.join(a for a, _ in judged)} within tolerance ({', '.join(f'{t:g}' for _, t in judged)} deg)"]
    if sigma_deg[weak] > tol[weak] / 2.0:  # yaw alone may stay unresolved: it is the p2 pattern of a real lens
        reasons.append(f"{AXES[weak]} not resolved (sigma {sigma_deg[weak]:.3f} deg): on a lens with distortion it "
                       "looks like a tangential-distortion error; it scales depth, which only a target can check")
    return "good", reasons


def check_image_sizes(profile: StereoProfile, name: str, left: NDArray[np.uint8], right: NDArray[np.uint8]) -> None:
    """CheckError naming frame ``name`` when an image is not the size its camera has in ``profile``."""
    for side, cam, image in (("left", profile.left, left), ("right", profile.right, right)):
        if image.shape[:2] != (cam.height_px, cam.width_px):
            raise CheckError(f"{side} image is {image.shape[1]}x{image.shape[0]} px but the profile "
                             f"{profile.name!r} has {cam.width_px}x{cam.height_px}", path=name, field="image size",
                             hint="check the recording with the profile of the camera that took it")


def check_drift(profile: StereoProfile, pairs: Iterable[tuple[str, NDArray[np.uint8], NDArray[np.uint8]]], *,
                settings: CheckSettings = CheckSettings(), progress: ProgressCallback | None = None,
                total: int | None = None) -> DriftResult:
    """Check ``profile`` against raw grey stereo pairs ``(name, left, right)`` of ordinary scenes."""
    rect = stereo_rectification(profile)
    turn = None
    if abs(rect.P2[1, 3]) > abs(rect.P2[0, 3]):  # OpenCV rectified it top-bottom: check it turned side by side
        turn = side_by_side_turn(profile)
        rect = stereo_rectification(turn.profile)
    working = profile if turn is None else turn.profile
    frames: list[FrameMatches] = []
    for k, (name, left, right) in enumerate(pairs, start=1):
        check_image_sizes(profile, name, left, right)
        if turn is not None:
            left, right = turn.image(left), turn.image(right)
        frames.append(match_frame(working, rect, left, right, name=name))
        report(progress, k, total or k, "matching features")
    left_px = np.vstack([f.left for f in frames]) if frames else np.zeros((0, 2))
    right_px = np.vstack([f.right for f in frames]) if frames else np.zeros((0, 2))
    frame_of = np.concatenate([np.full(f.count, k) for k, f in enumerate(frames)]) if frames else np.zeros(0, int)
    return _summarise(working, rect, frames, left_px, right_px, frame_of, settings, turn)


def _summarise(profile: StereoProfile, rect: Any, frames: list[FrameMatches], left: FloatArray, right: FloatArray,
               frame_of: NDArray[np.int_], settings: CheckSettings, turn: Turn | None = None) -> DriftResult:
    """The fit, sigma, costs and verdict of the matches; with ``turn`` (a vertical rig checked turned) the
    rotation and its sigmas are given in the profile's own camera axes."""
    n = len(left)
    if n < max(10, settings.min_matches // 2):  # not estimated: NaN, never a confident zero
        omega, cov, spread = np.full(3, np.nan), np.full((3, 3), np.nan), np.full(3, np.nan)
    else:
        omega, cov, spread = _fit_both(profile, rect, left, right)
    formal = np.sqrt(np.clip(np.diag(cov), 0, None)) if n else np.full(3, np.nan)
    use_frames = len(frames) >= settings.min_frames_for_resampling
    groups = frame_of if use_frames else _region_groups(left, rect.image_size)
    resampled = _resampled(profile, rect, groups, left, right) if n >= settings.min_matches else None
    sigma = np.sqrt(np.fmax(formal, resampled if resampled is not None else 0.0) ** 2 + spread**2
                    + _lens_floor(profile) ** 2) if np.all(np.isfinite(omega)) else np.full(3, np.nan)
    source = ("formal (residual-scaled)" if resampled is None or np.all(formal >= resampled)
              else f"jackknife over {'frames' if use_frames else 'image regions'}") + " + model spread" + (
        " + lens floor on yaw" if _lens_floor(profile)[1] > 0 else "")
    residual = right[:, 1] - predict_right(profile, rect, left, left[:, 0] - right[:, 0] + rect.doffs_px, omega,
                                           model="centre")[:, 1] if n else np.zeros(0)
    vertical, costs = _costs(profile, rect, omega, sigma, settings.distances_m)
    weak = 1  # the axis a lens's p2 term mimics: yaw, or the profile's own axis that turned into yaw
    if turn is not None:
        omega, spread = turn.back(omega), turn.back_sigma(spread)
        sigma, formal = turn.back_sigma(sigma), turn.back_sigma(formal)
        resampled = None if resampled is None else turn.back_sigma(resampled)
        weak = int(np.argmax(np.abs(turn.M[1])))
        source += "; vertical rig: fitted with images and profile turned 90 deg, given in the profile's axes"
    omega_deg, sigma_deg = np.degrees(omega), np.degrees(sigma)
    verdict, reasons = _verdict(omega_deg, sigma_deg, n, frames, settings, weak=weak)
    return DriftResult(
        profile=profile.name, verdict=verdict, reasons=reasons, omega_deg=omega_deg, sigma_deg=sigma_deg,
        sigma_formal_deg=np.degrees(formal), sigma_resampled_deg=None if resampled is None else np.degrees(resampled),
        sigma_source=source, model_spread_deg=np.degrees(spread),
        frames=[{"name": f.name, "matches": f.count, "keypoints": f.keypoints, "sharpness": f.sharpness}
                for f in frames],
        matches=n, residual_px=robust_scale(residual) if n else float("nan"), vertical_px=vertical,
        region_map_px=_region_map(left, right[:, 1] - left[:, 1], rect.image_size) if n else [],
        depth_cost=costs, tolerance_deg=settings.tolerance_deg, image_size=rect.image_size,
        points={"left": left, "dy": right[:, 1] - left[:, 1]})
