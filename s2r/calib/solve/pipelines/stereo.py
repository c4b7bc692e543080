"""Stereo calibration from image pairs: detect, check, solve with outlier rejection, build the profile."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.ma  # np.median's first call loads it (10 ms): here, while the workers still detect
from numpy.typing import NDArray

from s2r.calib.detect import Detection
from s2r.calib.detect.chessboard import board_object_points
from s2r.calib.detect.coverage import Coverage, PoseSpread, coverage_of, coverage_warnings, pose_spread
from s2r.calib.detect.pairs import PairDetection, display_name
from s2r.calib.solve.honesty.heldout import StereoHeldout, stereo_heldout
from s2r.calib.solve.honesty.models import ModelComparison
from s2r.calib.solve.honesty.projection import ProjectionMap
from s2r.calib.solve.honesty.verdict import Verdict, stereo_verdict
from s2r.calib.solve.pipelines.stereo_figures import (
    board_text,
    choose_warp,
    dropped_warning,
    fit_warnings,
    merge_repeated_views,
    projection_maps,
    repeat_warning,
    with_reported_std,
)
from s2r.calib.solve.solvers.pair import PairSolution, solve_pair, solve_pair_warped
from s2r.calib.solve.views import (
    MIN_VIEWS,
    check_sizes,
    no_board_error,
    select_diverse,
    stereo_views,
    too_few_error,
)
from s2r.errors import CalibrationError
from s2r.executor import usable_cores
from s2r.lens.fold import fold_warnings
from s2r.lens.models import DEFAULT_LENS, LENS_MODELS, lens_model
from s2r.profile import (
    CalibrationQuality,
    Camera,
    CameraUncertainty,
    Distortion,
    DroppedView,
    Extrinsics,
    Provenance,
    SourceFile,
    StereoProfile,
)
from s2r.progress import ProgressCallback, report
from s2r.rectification import stereo_rectification

__all__ = ["StereoCalibration", "ViewError", "board_text", "calibrate_detected_pairs", "calibrate_stereo",
           "calibrate_stereo_detections", "make_camera"]

log = logging.getLogger(__name__)
Corners = NDArray[np.float32]


@dataclass(frozen=True)
class ViewError:
    """Per-view RMS reprojection errors (px) of one pair; ``used`` False for outliers (``reason`` says why)."""

    name: str
    left_px: float
    right_px: float
    stereo_px: float
    used: bool
    reason: str = ""


@dataclass(frozen=True)
class StereoCalibration:
    """A stereo calibration: the real profile and every figure behind it.

    ``views`` per-view errors of the used views (and the outliers, ``used`` False); ``dropped`` every
    skipped image or view with its reason; ``threshold_px`` the outlier threshold of the last round;
    coverage per camera; ``spread`` of the board poses (left camera); ``epipolar_rms_px`` the RMS of
    y differences of matching corners after rectification; ``corners_left/right`` the used views' corners;
    ``sample_paths`` (files) or ``sample_images`` (bags, grey) one used pair, for the report; ``frames`` (stream
    inputs: videos) the frames read, used as views and not kept by reason
    (:func:`s2r.calib.solve.pipelines.stereo_stream.frame_counts`).
    """

    profile: StereoProfile
    views: tuple[ViewError, ...]
    dropped: tuple[DroppedView, ...]
    threshold_px: float
    coverage_left: Coverage
    coverage_right: Coverage
    spread: PoseSpread
    epipolar_rms_px: float
    warnings: tuple[str, ...]
    used_names: tuple[str, ...]
    corners_left: tuple[Corners, ...] = field(repr=False)
    corners_right: tuple[Corners, ...] = field(repr=False)
    reordered: tuple[str, ...] = ()
    sample_paths: tuple[Path, Path] | None = None
    sample_images: tuple[NDArray[np.uint8], NDArray[np.uint8]] | None = field(default=None, repr=False)
    detection_cached: int = 0
    solution: PairSolution | None = field(default=None, repr=False)
    models: ModelComparison | None = None
    verdict: Verdict | None = None
    view_paths: dict[str, tuple[Path, Path]] = field(default_factory=dict, repr=False)
    heldout: StereoHeldout | None = None
    board: str = ""
    projection: dict[str, dict[str, ProjectionMap | None]] = field(default_factory=dict, repr=False)
    board_warp: dict[str, Any] | None = None
    frames: dict[str, Any] | None = None

    def figures(self) -> dict[str, Any]:
        """The calibration figures as plain JSON-ready values (what ``--json`` prints)."""
        p = self.profile
        quality = p.provenance.calibration
        return {
            "verdict": None if self.verdict is None else self.verdict.as_dict(),
            "profile": p.name,
            "left": _camera_figures(p.left), "right": _camera_figures(p.right),
            "translation_m": list(p.extrinsics.translation_m), "baseline_m": p.baseline_m,
            "baseline_std_m": p.extrinsics.baseline_std_m,
            "rotation_deg": float(np.degrees(p.rotation_angle_rad)),
            "quality": None if quality is None else quality.model_dump(mode="json"),
            "threshold_px": self.threshold_px,
            "views": [vars(v) for v in self.views],
            "dropped": [d.model_dump(mode="json") for d in self.dropped],
            "coverage_grid_left": self.coverage_left.counts.tolist(),
            "coverage_grid_right": self.coverage_right.counts.tolist(),
            "reordered_right_corners": list(self.reordered),
            "warnings": list(self.warnings),
            "detections_from_cache": self.detection_cached,
            "rotation_std_deg": None if self.solution is None or not np.isfinite(self.solution.rotation_std_deg)
            else self.solution.rotation_std_deg,
            "unobservable": [] if self.solution is None else list(self.solution.unobservable),
            "model_comparison": None if self.models is None else self.models.as_dict(),
            "board": self.board,
            "board_warp": self.board_warp,
            "rms_all_px": None if self.solution is None else _nan_none(self.solution.rms_all_px),
            "corners_total": None if self.solution is None else self.solution.corners_total,
            "corners_rejected": None if self.solution is None else
            sum(a + b for _, a, b in self.solution.rejected_corners),
            "rejected_corner_groups": self.corner_groups(),
            "stereo_heldout": None if self.heldout is None else self.heldout.as_dict(),
            "projection_uncertainty": {side: {src: None if m is None else m.as_dict() for src, m in maps.items()}
                                       for side, maps in self.projection.items()},
            "frames": self.frames,
        }


    def corner_groups(self) -> list[dict[str, Any]]:
        """Every used view that lost corners as outliers: its name, the count per camera and why."""
        if self.solution is None:
            return []
        thr = "5 robust sigmas of the residuals (at least 0.3 px)"
        return [{"name": self.used_names[self.solution.keep.index(i)] if i in self.solution.keep else str(i),
                 "left": a, "right": b, "reason": f"corner residual beyond {thr}"}
                for i, a, b in self.solution.rejected_corners]


def _nan_none(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _camera_figures(cam: Camera) -> dict[str, Any]:
    std = cam.std
    return {"fx_px": cam.fx_px, "fy_px": cam.fy_px, "cx_px": cam.cx_px, "cy_px": cam.cy_px,
            "distortion": list(cam.distortion.coefficients),
            "std": None if std is None else std.model_dump(mode="json")}


def make_camera(K: NDArray[np.float64], D: NDArray[np.float64], size: tuple[int, int], std: NDArray[np.float64],
                *, distortion: str) -> Camera:
    """A profile Camera from OpenCV K, D and the std vector ``(fx, fy, cx, cy, d...)``."""
    lens = lens_model(distortion)
    coefs = tuple(float(v) for v in np.asarray(D, np.float64).reshape(-1)[:lens.n_coef])
    dstd = [float(v) for v in np.asarray(std, np.float64)[4:4 + lens.n_coef]]

    def sd(v: float) -> float | None:  # unobservable (inf / NaN) is None, never a NaN the profile rejects
        return float(v) if np.isfinite(v) else None

    if max(abs(c) for c in coefs) > 1000:
        raise CalibrationError(f"the {distortion} lens model is degenerate on these views (a coefficient of "
                               f"{max(coefs, key=abs):.4g})", field="--distortion",
                               hint="use a model with fewer terms, e.g. --distortion k1k2p1p2")
    return Camera(
        width_px=size[0], height_px=size[1], fx_px=float(K[0, 0]), fy_px=float(K[1, 1]),
        cx_px=float(K[0, 2]), cy_px=float(K[1, 2]),
        distortion=Distortion(model=lens.profile_model, coefficients=coefs),  # type: ignore[arg-type]
        std=CameraUncertainty(fx_px=sd(std[0]), fy_px=sd(std[1]), cx_px=sd(std[2]), cy_px=sd(std[3]),
                              distortion=tuple(dstd) if all(np.isfinite(dstd)) else None))


def epipolar_rms(profile: StereoProfile, left: Sequence[Corners], right: Sequence[Corners]) -> float:
    """RMS (px) of the y differences of matching corners after undistortion and rectification."""
    rect = stereo_rectification(profile)
    dys = []
    for pl, pr in zip(left, right, strict=True):
        ul = cv2.undistortPoints(pl.reshape(-1, 1, 2).astype(np.float64), profile.left.K, profile.left.D,
                                 R=rect.R1, P=rect.P1).reshape(-1, 2)
        ur = cv2.undistortPoints(pr.reshape(-1, 1, 2).astype(np.float64), profile.right.K, profile.right.D,
                                 R=rect.R2, P=rect.P2).reshape(-1, 2)
        dys.append(ul[:, 1] - ur[:, 1])
    return float(np.sqrt(np.mean(np.concatenate(dys) ** 2))) if dys else float("nan")


def _uncertainty_warnings(profile: StereoProfile) -> list[str]:
    out = []
    for side, cam in (("left", profile.left), ("right", profile.right)):
        s = cam.std
        if s is None:
            continue
        for name, val, sd, limit in (("fx", cam.fx_px, s.fx_px, 0.005), ("fy", cam.fy_px, s.fy_px, 0.005),
                                     ("cx", cam.width_px, s.cx_px, 0.01), ("cy", cam.height_px, s.cy_px, 0.01)):
            if sd is not None and sd > limit * val:
                out.append(f"{side} {name} is uncertain: std {sd:.2f} px is large; add views covering the "
                           "image corners at varied tilt")
    b_std = profile.extrinsics.baseline_std_m
    if b_std is not None and b_std > 0.01 * profile.baseline_m:
        out.append(f"baseline is uncertain: std {b_std * 1000:.2f} mm of {profile.baseline_m * 1000:.1f} mm; "
                   "add views at several distances")
    return out


def calibrate_stereo_detections(
    pairs: Sequence[tuple[str, Detection, Detection]], *, pattern: tuple[int, int], square_m: float, name: str,
    distortion: str = DEFAULT_LENS, max_error_px: float | None = None, fix_intrinsics: bool = False,
    swap: bool = False, sources: Sequence[SourceFile] = (), extra_dropped: Sequence[DroppedView] = (),
    sample_paths: tuple[Path, Path] | None = None, compare: bool = True, jobs: int | None = None,
) -> StereoCalibration:
    """Solve a stereo calibration from per-image detections (any input kind); see :func:`calibrate_stereo`
    (``jobs``: processes of the resampling solves, default all cores)."""
    if swap:
        pairs = [(n, dr, dl) for n, dl, dr in pairs]
    size = check_sizes([d for _, dl, dr in pairs for d in (dl, dr)])
    views = stereo_views(pairs, pattern)
    readable = sum(d.status != "unreadable" for _, dl, dr in pairs for d in (dl, dr))
    if not any(d.status == "ok" for _, dl, dr in pairs for d in (dl, dr)):
        raise no_board_error(readable, pattern)
    dropped = [*extra_dropped, *views.dropped]
    views, repeats = merge_repeated_views(views)
    dropped += repeats
    if len(views.names) < MIN_VIEWS:
        raise too_few_error(len(views.names), dropped, pattern=pattern)
    obj = board_object_points(pattern, square_m)
    selected = select_diverse(views.left, pattern, size)
    if len(selected) < len(views.names):
        log.warning("%d usable pairs; solving with the %d most diverse (MAX_SOLVE_VIEWS)", len(views.names),
                    len(selected))
    sol = solve_pair([views.names[i] for i in selected], [views.left[i] for i in selected],
                     [views.right[i] for i in selected], obj, size, distortion=distortion, max_error_px=max_error_px,
                     fix_intrinsics=fix_intrinsics, square_m=square_m)
    keep = [selected[i] for i in sol.keep]
    pl, pr = [views.left[i] for i in keep], [views.right[i] for i in keep]
    names = [views.names[k] for k in keep]
    warp_solve = None if fix_intrinsics else partial(solve_pair_warped, names, pl, pr, obj, sol,
                                                      distortion=distortion, max_error_px=max_error_px)
    held, models, held_w, warped = stereo_heldout(
        names, pl, pr, obj, sol, lens=lens_model(distortion), compare=tuple(LENS_MODELS) if compare else (),
        max_error_px=max_error_px, jobs=jobs or usable_cores(), warp_solve=warp_solve)
    sol, held, warp_figures = choose_warp(sol, held, warped, held_w)
    keep = [selected[i] for i in sol.keep]
    pl, pr = [views.left[i] for i in keep], [views.right[i] for i in keep]
    sol = with_reported_std(sol, held)
    dropped += [DroppedView(name=views.names[selected[i]], reason=why) for i, why in sol.mismatched]
    outliers = [ViewError(views.names[selected[i]], a, b, c, used=False, reason=why)
                for i, a, b, c, why in sol.outliers]
    dropped += [DroppedView(name=o.name, rms_px=o.stereo_px, reason=o.reason) for o in outliers]
    cov_l, cov_r = coverage_of(pl, size), coverage_of(pr, size)
    spread = pose_spread(sol.rvecs, sol.tvecs, pl, pattern=pattern, square_m=square_m, size=size)
    quality = CalibrationQuality(
        pattern=pattern, square_m=square_m, views_used=len(keep), views_dropped=tuple(dropped),
        views_detected=len(views.names), rms_left_px=sol.rms_left_px, rms_right_px=sol.rms_right_px,
        rms_stereo_px=sol.rms_px, coverage_left=cov_l.fraction, coverage_right=cov_r.fraction,
        tilt_range_deg=spread.tilt_deg, distance_range_m=spread.distance_m, distortion_terms=distortion)
    profile = _stereo_profile(name, sol, pl, pr, size, distortion=distortion, sources=sources, quality=quality)
    epi = profile.provenance.calibration.epipolar_rms_px if profile.provenance.calibration else None
    folds = fold_warnings([("left", profile.left), ("right", profile.right)])
    warnings = [*repeat_warning(repeats), *dropped_warning(dropped), *fit_warnings(held, sol),
                *([models.warning] if models is not None and models.warning else []),
                *_unobservable_warnings(sol.unobservable), *_uncertainty_warnings(profile), *folds,
                *coverage_warnings("left", cov_l, spread), *coverage_warnings("right", cov_r)]
    for w in warnings:
        log.warning("%s", w)
    heldout = None if held is None else held.verdict_px
    verdict = stereo_verdict(
        rms_px=sol.rms_px, heldout_px=heldout, epipolar_px=float("nan") if epi is None else epi,
        baseline_m=profile.baseline_m, baseline_std_m=profile.extrinsics.baseline_std_m,
        coverage=(cov_l.fraction, cov_r.fraction), model_warning=None if models is None else models.warning,
        unobservable=sol.unobservable, mismatched=len(sol.mismatched),
        heldout_over_all=held is not None and held.judged_over_all, converged=sol.converged, lens_folds=folds)
    view_errors = [ViewError(views.names[k], float(e[0]), float(e[1]), float(e[2]), used=True)
                   for k, e in zip(keep, sol.per_view, strict=True)]
    return StereoCalibration(
        profile=profile, views=tuple(view_errors + outliers), dropped=tuple(dropped),
        threshold_px=sol.threshold_px, coverage_left=cov_l, coverage_right=cov_r, spread=spread,
        epipolar_rms_px=float("nan") if epi is None else epi, warnings=tuple(warnings),
        used_names=tuple(views.names[k] for k in keep),
        corners_left=tuple(pl), corners_right=tuple(pr), reordered=views.reordered, sample_paths=sample_paths,
        detection_cached=sum(d.cached for _, dl, dr in pairs for d in (dl, dr)), solution=sol, models=models,
        verdict=verdict, heldout=held, board=board_text(pattern, square_m),
        projection=projection_maps(sol, held, size, lens_model(distortion).free), board_warp=warp_figures)


def _unobservable_warnings(names: Sequence[str]) -> list[str]:
    if not names:
        return []
    return [f"not observable from these views: {', '.join(names)} (std reported as unknown); use a lens model "
            "with fewer terms (--distortion k1k2p1p2) or add views covering the image corners at varied tilt"]


def _stereo_profile(name: str, sol: PairSolution, pl: Sequence[Corners], pr: Sequence[Corners],
                    size: tuple[int, int], *, distortion: str, sources: Sequence[SourceFile],
                    quality: CalibrationQuality) -> StereoProfile:
    """The real profile: cameras with std devs, extrinsics with the baseline std, provenance with the
    quality figures completed by the epipolar error after rectification."""
    b_std = sol.baseline_std_m if np.isfinite(sol.baseline_std_m) else None
    profile = StereoProfile(
        name=name,
        left=make_camera(sol.K1, sol.D1, size, sol.std_left, distortion=distortion),
        right=make_camera(sol.K2, sol.D2, size, sol.std_right, distortion=distortion),
        extrinsics=Extrinsics(rotation=tuple(tuple(float(v) for v in row) for row in sol.R),  # type: ignore[arg-type]
                              translation_m=tuple(float(v) for v in sol.T),  # type: ignore[arg-type]
                              baseline_std_m=b_std),
        provenance=Provenance(origin="real", method=sol.method, sources=tuple(sources), calibration=quality))
    epi = epipolar_rms(profile, pl, pr)
    return profile.model_copy(update={"provenance": profile.provenance.model_copy(
        update={"calibration": quality.model_copy(update={"epipolar_rms_px": epi})})})


def calibrate_stereo(
    left_paths: Sequence[Path], right_paths: Sequence[Path], *, pattern: tuple[int, int] = (9, 6),
    square_m: float = 0.025, name: str = "calibrated", distortion: str = DEFAULT_LENS,
    max_error_px: float | None = None, fix_intrinsics: bool = False, swap: bool = False, jobs: int | None = None,
    cache_dir: Path | None = None, progress: ProgressCallback | None = None, names: Sequence[str] | None = None,
    unpaired: Sequence[Path] = (), compare: bool = True,
) -> StereoCalibration:
    """Calibrate a stereo pair from chessboard image files (``left_paths[i]`` pairs with ``right_paths[i]``).

    Args:
        pattern: inner corners ``(cols, rows)``; square_m: square size in metres.
        distortion: a :data:`s2r.lens.models.LENS_MODELS` choice; default ``k1k2p1p2`` (k3 fixed, as ROS).
        max_error_px: fixed per-view RMS outlier threshold; default a robust (median/MAD) one.
        fix_intrinsics: ROS's way (intrinsics from each camera alone, held fixed) instead of the joint solve.
        swap: exchange the left and right images (when the check finds the right camera to the left).
        compare: score every lens model on held-out views (:func:`s2r.calib.solve.honesty.models.compare_models`).
        jobs: detection processes (default all cores); cache_dir: per-image corner cache folder.
        names: pair labels (default the left file stems); unpaired: files without a partner (listed as dropped).

    Raises:
        CalibrationError: mixed sizes, no board at all (wrong pattern), fewer than MIN_VIEWS usable pairs,
            identical or mismatched pairs, swapped cameras, an implausible ``square_m``.
    """
    detection = PairDetection(left_paths, right_paths, pattern=pattern, jobs=jobs, cache_dir=cache_dir,
                              progress=progress, names=names, unpaired=unpaired, swap=swap)
    return calibrate_detected_pairs(detection, square_m=square_m, name=name, distortion=distortion,
                                    max_error_px=max_error_px, fix_intrinsics=fix_intrinsics, jobs=jobs,
                                    progress=progress, compare=compare)


def calibrate_detected_pairs(
    detection: PairDetection, *, square_m: float, name: str = "calibrated", distortion: str = DEFAULT_LENS,
    max_error_px: float | None = None, fix_intrinsics: bool = False, jobs: int | None = None,
    progress: ProgressCallback | None = None, compare: bool = True,
) -> StereoCalibration:
    """:func:`calibrate_stereo` of a detection already started (the CLI starts it before loading the solver,
    so both run at once); waits for it, then solves (options as :func:`calibrate_stereo`)."""
    found = detection.result()
    for p in found.unpaired:
        log.warning("%s has no partner image; skipped", p)
    extra = [DroppedView(name=display_name(p), reason="unpaired: no partner image") for p in found.unpaired]
    sources = [SourceFile(path=str(p), sha256=found.sha256[p]) for p in (*found.left, *found.right)]
    report(progress, 0, 1, "solving")
    result = calibrate_stereo_detections(
        found.pairs, pattern=detection.pattern, square_m=square_m, name=name, distortion=distortion,
        max_error_px=max_error_px, fix_intrinsics=fix_intrinsics, sources=sources, extra_dropped=extra,
        compare=compare, jobs=jobs or usable_cores())
    report(progress, 1, 1, "solving")
    idx = [n for n, _, _ in found.pairs].index(result.used_names[0])
    view_paths = {n: (a, b) for (n, _, _), a, b in zip(found.pairs, found.left, found.right, strict=True)}
    return replace(result, sample_paths=(found.left[idx], found.right[idx]), view_paths=view_paths)
