"""Stereo and mono calibration with corner ids: ``--target TARGET.yaml`` and ``--lens fisheye``.

The same inputs, cache, outlier rule, standard deviations, coverage warnings and result types as the
chessboard path (:mod:`.stereo`, :mod:`.mono`), on views that may be partial: each camera is
solved on every view it saw, the pair on the corners both cameras saw (matched by id). A ``--pattern``
chessboard through a fisheye lens comes here as a Kalibr checkerboard target.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from s2r.calib.detect import CornerCache, Detection, DetectItem, detect_stream
from s2r.calib.detect.coverage import coverage_of, coverage_warnings
from s2r.calib.solve.honesty.heldout import StereoHeldout
from s2r.calib.solve.honesty.target import merge_repeat_pairs, pair_heldout
from s2r.calib.solve.honesty.verdict import stereo_verdict
from s2r.calib.solve.pipelines.stereo import StereoCalibration, ViewError, _uncertainty_warnings
from s2r.calib.solve.pipelines.stereo_figures import fit_warnings, repeat_warning, with_reported_std
from s2r.calib.solve.pipelines.target_joint import joint_solve, lens_model_of
from s2r.calib.solve.solvers.cvsolve import StereoSolution, outlier_threshold
from s2r.calib.solve.solvers.observations import StereoObservation
from s2r.calib.solve.solvers.pair import PairSolution
from s2r.calib.solve.solvers.targetcal import (
    CameraViews,
    MonoFit,
    Observation,
    PairView,
    baseline_cov,
    camera_of,
    centred_spread,
    fit_camera,
    no_target_error,
    observations,
    pair_views,
    quality_of,
    solve_pair,
    to_camera,
)
from s2r.calib.solve.views import MIN_VIEWS, check_sizes, too_few_error
from s2r.executor import usable_cores
from s2r.fileio import sha256_file
from s2r.lens.fold import fold_warnings
from s2r.lens.models import DEFAULT_LENS
from s2r.profile import DroppedView, Extrinsics, Provenance, SourceFile, StereoProfile
from s2r.progress import ProgressCallback, report
from s2r.rectification import stereo_rectification
from s2r.targets import AnyTarget, CheckerboardTarget

__all__ = ["calibrate_stereo_target", "calibrate_stereo_target_detections"]

log = logging.getLogger(__name__)
_STEREO_ROUNDS = 4


def _method(lens: str, stereo: bool) -> str:
    if lens == "fisheye":
        base = "s2r calibrate --lens fisheye: OpenCV fisheye.calibrate per camera"
        return base + (", pair on corners matched by id (scipy least_squares, intrinsics fixed)" if stereo else "")
    base = "s2r calibrate --target: OpenCV calibrateCameraExtended per camera on partial views"
    return base + (", stereoCalibrate on corners matched by id with CALIB_FIX_INTRINSIC" if stereo else "")


def _skipped(dets: Sequence[Detection], obs: Sequence[Observation | None]) -> list[DroppedView]:
    out = []
    for d, o in zip(dets, obs, strict=True):
        if o is None:
            why = f"{d.status.replace('_', ' ')}: {d.detail}" if d.status != "ok" else \
                "too few corners: fewer than 6, or all on one line"
            out.append(DroppedView(name=d.name, reason=why))
    return out


def epipolar_rms(profile: StereoProfile, views: Sequence[PairView]) -> float:
    """RMS (px) of the y differences of matching corners after undistortion and rectification (both lens
    models)."""
    rect = stereo_rectification(profile)
    fish = profile.left.distortion.model == "equidistant"
    und = cv2.fisheye.undistortPoints if fish else cv2.undistortPoints
    dys = []
    for v in views:
        ul = und(v.left.reshape(-1, 1, 2).astype(np.float64), profile.left.K, profile.left.D, R=rect.R1, P=rect.P1)
        ur = und(v.right.reshape(-1, 1, 2).astype(np.float64), profile.right.K, profile.right.D, R=rect.R2,
                 P=rect.P2)
        dys.append(np.asarray(ul).reshape(-1, 2)[:, 1] - np.asarray(ur).reshape(-1, 2)[:, 1])
    return float(np.sqrt(np.mean(np.concatenate(dys) ** 2))) if dys else float("nan")


@dataclass
class _Pair:
    views: list[PairView]
    stereo: StereoSolution
    threshold: float
    outliers: list[ViewError]


def _stereo_rounds(views: list[PairView], fit_l: MonoFit, fit_r: MonoFit, size: tuple[int, int], *, lens: str,
                   distortion: str, max_error_px: float | None) -> _Pair:
    outliers: list[ViewError] = []
    thr: float | None = None
    for _ in range(_STEREO_ROUNDS):
        if len(views) < MIN_VIEWS:
            raise too_few_error(len(views), [DroppedView(name=o.name, reason=o.reason) for o in outliers])
        st = solve_pair(views, fit_l, fit_r, size, lens=lens, distortion=distortion)
        err = st.per_view_px.max(axis=1)
        if thr is None:
            thr = outlier_threshold(err, max_error_px=max_error_px)
        bad = [j for j, e in enumerate(err) if e > thr]
        if not bad or len(views) - len(bad) < MIN_VIEWS:
            return _Pair(views, st, thr, outliers)
        outliers += [ViewError(views[j].name, float(st.per_view_px[j, 0]), float(st.per_view_px[j, 1]),
                               float(err[j]), used=False, reason=f"outlier: stereo RMS {err[j]:.3f} px > {thr:.3f} px")
                     for j in bad]
        views = [v for j, v in enumerate(views) if j not in set(bad)]
    assert thr is not None
    return _Pair(views, st, thr, outliers)


def _mono_fits(obs_l: list[Observation | None], obs_r: list[Observation | None], size: tuple[int, int], *,
               lens: str, distortion: str, max_error_px: float | None, dropped: list[DroppedView],
               prune: bool = True) -> tuple[list[MonoFit], list[dict[int, int]]]:
    """Each camera on every view it saw (outlier views and corners removed, written back into ``obs_*``);
    returns the fits and, per camera, view index -> position in the fit's kept views."""
    fits, keeps = [], []
    for side, obs in (("left", obs_l), ("right", obs_r)):
        index = [k for k, o in enumerate(obs) if o is not None]
        if len(index) < MIN_VIEWS:
            raise too_few_error(len(index), dropped, what=f"{side} images")
        fit = fit_camera(CameraViews([obs[k] for k in index], size, lens, distortion, prune),  # type: ignore[misc]
                         max_error_px=max_error_px, camera=side)
        for j, k in enumerate(index):
            obs[k] = fit.views[j]
        fits.append(fit)
        keeps.append({index[j]: pos for pos, j in enumerate(fit.keep)})
        dropped += fit.outliers
    return fits, keeps


def calibrate_stereo_target_detections(
    pairs: Sequence[tuple[str, Detection, Detection]], *, target: AnyTarget, lens: str = "pinhole",
    distortion: str = DEFAULT_LENS, name: str = "calibrated", max_error_px: float | None = None,
    fix_intrinsics: bool = False, swap: bool = False, sources: Sequence[SourceFile] = (),
    extra_dropped: Sequence[DroppedView] = (), jobs: int = 1,
) -> StereoCalibration:
    """Solve a stereo calibration from per-image detections with corner ids (see the module docstring);
    ``jobs``: processes of the held-out folds."""
    if swap:
        pairs = [(n, dr, dl) for n, dl, dr in pairs]
    size = check_sizes([d for _, dl, dr in pairs for d in (dl, dr)])
    names = [n for n, _, _ in pairs]
    obs_l = observations([dl for _, dl, _ in pairs], target)
    obs_r = observations([dr for _, _, dr in pairs], target)
    if not any(o is not None for o in (*obs_l, *obs_r)):
        raise no_target_error(sum(d.status != "unreadable" for _, dl, dr in pairs for d in (dl, dr)), target)
    dropped = [*extra_dropped, *_skipped([dl for _, dl, _ in pairs], obs_l),
               *_skipped([dr for _, _, dr in pairs], obs_r)]
    unique, repeats = merge_repeat_pairs(names, obs_l, obs_r)
    names, obs_l, obs_r = [names[i] for i in unique], [obs_l[i] for i in unique], [obs_r[i] for i in unique]
    dropped += repeats
    (fit_l, fit_r), keeps = _mono_fits(obs_l, obs_r, size, lens=lens, distortion=distortion,
                                       max_error_px=max_error_px, dropped=dropped,
                                       prune=not isinstance(target, CheckerboardTarget))
    views, reordered = pair_views(names, obs_l, obs_r, keeps[0], keeps[1], target)
    if len(views) < MIN_VIEWS:
        raise too_few_error(len(views), dropped)
    if fix_intrinsics:
        solved = _stereo_rounds(views, fit_l, fit_r, size, lens=lens, distortion=distortion,
                                max_error_px=max_error_px)
        dropped += [DroppedView(name=o.name, rms_px=o.stereo_px, reason=o.reason) for o in solved.outliers]
        fixed = _fixed_result(solved, fit_l, fit_r, size, target=target, lens=lens, distortion=distortion,
                              name=name, sources=sources, dropped=dropped, reordered=reordered, obs=(obs_l, obs_r),
                              detected=len(names) + len(repeats))
        return replace(fixed, warnings=(*_logged(repeat_warning(repeats)), *fixed.warnings))
    joint_obs, sol = joint_solve(names, obs_l, obs_r, keeps, fit_l, fit_r, views, lens=lens,
                                  distortion=distortion, max_error_px=max_error_px)
    held = pair_heldout(joint_obs, sol, lens_model_of(lens, distortion), max_error_px=max_error_px, jobs=jobs)
    result = _joint_result(joint_obs, with_reported_std(sol, held), views, size, target=target, lens=lens,
                           distortion=distortion, name=name, sources=sources, dropped=dropped, reordered=reordered,
                           obs=(obs_l, obs_r), detected=len(names) + len(repeats), fit_l=fit_l, heldout=held)
    return replace(result, warnings=(*_logged(repeat_warning(repeats)), *result.warnings))


def _logged(warnings: list[str]) -> list[str]:
    for w in warnings:
        log.warning("%s", w)
    return warnings


def _joint_result(joint_obs: list[StereoObservation], sol: PairSolution, views: Sequence[PairView],
                  size: tuple[int, int], *, target: AnyTarget, lens: str, distortion: str, name: str,
                  sources: Sequence[SourceFile], dropped: list[DroppedView], reordered: list[str],
                  obs: tuple[list[Observation | None], list[Observation | None]], detected: int,
                  fit_l: MonoFit, heldout: StereoHeldout | None = None) -> StereoCalibration:
    model = lens_model_of(lens, distortion)
    used = {joint_obs[i].name for i in sol.keep}
    outliers = [ViewError(joint_obs[i].name, a, b, c, used=False, reason=why) for i, a, b, c, why in sol.outliers]
    dropped = [*dropped, *(DroppedView(name=o.name, rms_px=o.stereo_px, reason=o.reason) for o in outliers)]
    pv = [v for v in views if v.name in used]
    seen_l = [o.img for o in obs[0] if o is not None]
    seen_r = [o.img for o in obs[1] if o is not None]
    cov_l, cov_r = coverage_of(seen_l, size), coverage_of(seen_r, size)
    left_views = [o for o in obs[0] if o is not None]
    spread = centred_spread(fit_l.solution, [left_views[i] for i in fit_l.keep], target, size)
    quality = quality_of(target, lens=lens, distortion=distortion, views_used=len(sol.keep),
                         views_dropped=tuple(dropped), views_detected=detected, rms_left_px=sol.rms_left_px,
                         rms_right_px=sol.rms_right_px, rms_stereo_px=sol.rms_px, coverage_left=cov_l.fraction,
                         coverage_right=cov_r.fraction, tilt_range_deg=spread.tilt_deg,
                         distance_range_m=spread.distance_m)
    b_std = sol.baseline_std_m if np.isfinite(sol.baseline_std_m) else None
    profile = StereoProfile(
        name=name, left=camera_of(sol.K1, sol.D1, sol.std_left, size, model),
        right=camera_of(sol.K2, sol.D2, sol.std_right, size, model),
        extrinsics=Extrinsics(rotation=tuple(tuple(float(v) for v in row) for row in sol.R),  # type: ignore[arg-type]
                              translation_m=tuple(float(v) for v in sol.T),  # type: ignore[arg-type]
                              baseline_std_m=b_std),
        provenance=Provenance(origin="real", method=sol.method, sources=tuple(sources), calibration=quality))
    epi = epipolar_rms(profile, pv)
    profile = profile.model_copy(update={"provenance": profile.provenance.model_copy(
        update={"calibration": quality.model_copy(update={"epipolar_rms_px": epi})})})
    folds = fold_warnings([("left", profile.left), ("right", profile.right)])
    warnings = [*_unobservable(sol.unobservable), *_uncertainty_warnings(profile),
                *fit_warnings(heldout, sol), *folds,
                *coverage_warnings("left", cov_l, spread), *coverage_warnings("right", cov_r)]
    for w in warnings:
        log.warning("%s", w)
    view_errors = [ViewError(joint_obs[i].name, float(e[0]), float(e[1]), float(e[2]), used=True)
                   for i, e in zip(sol.keep, sol.per_view, strict=True)]
    verdict = stereo_verdict(rms_px=sol.rms_px, heldout_px=None if heldout is None else heldout.verdict_px,
                             epipolar_px=epi, baseline_m=profile.baseline_m,
                             baseline_std_m=profile.extrinsics.baseline_std_m,
                             coverage=(cov_l.fraction, cov_r.fraction), unobservable=sol.unobservable,
                             heldout_over_all=heldout is not None and heldout.judged_over_all,
                             converged=sol.converged, lens_folds=folds)
    # per used view, each camera's corners (empty when that camera did not see the board) aligned with the
    # solve's residuals, as the report draws them
    empty = np.zeros((0, 2))
    seen = [(joint_obs[i].left, joint_obs[i].right) for i in sol.keep]
    aligned = replace(sol, residuals=tuple((empty if r[0] is None else r[0], empty if r[1] is None else r[1])
                                           for r in sol.residuals))
    return StereoCalibration(
        profile=profile, views=tuple(view_errors + outliers), dropped=tuple(dropped), threshold_px=sol.threshold_px,
        coverage_left=cov_l, coverage_right=cov_r, spread=spread, epipolar_rms_px=epi, warnings=tuple(warnings),
        used_names=tuple(joint_obs[i].name for i in sol.keep),
        corners_left=tuple(empty.astype(np.float32) if o is None else o.img.astype(np.float32) for o, _ in seen),
        corners_right=tuple(empty.astype(np.float32) if o is None else o.img.astype(np.float32) for _, o in seen),
        reordered=tuple(reordered), solution=aligned, verdict=verdict, board=target.describe(), heldout=heldout)


def _fixed_result(solved: _Pair, fit_l: MonoFit, fit_r: MonoFit, size: tuple[int, int], *, target: AnyTarget,
                  lens: str, distortion: str, name: str, sources: Sequence[SourceFile], dropped: list[DroppedView],
                  reordered: list[str], obs: tuple[list[Observation | None], list[Observation | None]],
                  detected: int) -> StereoCalibration:
    """The result of ROS's way (--fix-intrinsics): mono intrinsics held fixed in the pair's solve."""
    st, views = solved.stereo, solved.views
    seen_l = [o.img for k, o in enumerate(obs[0]) if o is not None]
    seen_r = [o.img for k, o in enumerate(obs[1]) if o is not None]
    cov_l, cov_r = coverage_of(seen_l, size), coverage_of(seen_r, size)
    left_views = [o for o in obs[0] if o is not None]
    spread = centred_spread(fit_l.solution, [left_views[i] for i in fit_l.keep], target, size)
    cov_t = baseline_cov(views, st, fit_l, fit_r, lens=lens, distortion=distortion)
    u = st.T / np.linalg.norm(st.T)
    left = to_camera(fit_l.solution, size, lens=lens, distortion=distortion)
    right = to_camera(fit_r.solution, size, lens=lens, distortion=distortion)
    quality = quality_of(target, lens=lens, distortion=distortion, views_used=len(views),
                         views_dropped=tuple(dropped), views_detected=detected,
                         rms_left_px=fit_l.solution.rms_px, rms_right_px=fit_r.solution.rms_px,
                         rms_stereo_px=st.rms_px, coverage_left=cov_l.fraction, coverage_right=cov_r.fraction,
                         tilt_range_deg=spread.tilt_deg, distance_range_m=spread.distance_m)
    profile = StereoProfile(
        name=name, left=left, right=right,
        extrinsics=Extrinsics(rotation=tuple(tuple(float(v) for v in row) for row in st.R),  # type: ignore[arg-type]
                              translation_m=tuple(float(v) for v in st.T),  # type: ignore[arg-type]
                              baseline_std_m=float(np.sqrt(max(0.0, float(u @ cov_t @ u))))),
        provenance=Provenance(origin="real", method=_method(lens, True), sources=tuple(sources), calibration=quality))
    epi = epipolar_rms(profile, views)
    profile = profile.model_copy(update={"provenance": profile.provenance.model_copy(
        update={"calibration": quality.model_copy(update={"epipolar_rms_px": epi})})})
    folds = fold_warnings([("left", profile.left), ("right", profile.right)])
    warnings = [*_uncertainty_warnings(profile), *coverage_warnings("left", cov_l, spread),
                *coverage_warnings("right", cov_r), *folds]
    for w in warnings:
        log.warning("%s", w)
    view_errors = [ViewError(v.name, float(e[0]), float(e[1]), float(max(e)), used=True)
                   for v, e in zip(views, st.per_view_px, strict=True)]
    # no held-out error on this path: the mono fits it holds fixed are not resampled
    verdict = stereo_verdict(rms_px=st.rms_px, heldout_px=None, epipolar_px=epi, baseline_m=profile.baseline_m,
                             baseline_std_m=profile.extrinsics.baseline_std_m,
                             coverage=(cov_l.fraction, cov_r.fraction), lens_folds=folds)
    return StereoCalibration(
        profile=profile, views=tuple(view_errors + solved.outliers), dropped=tuple(dropped),
        threshold_px=solved.threshold, coverage_left=cov_l, coverage_right=cov_r, spread=spread,
        epipolar_rms_px=epi, warnings=tuple(warnings), used_names=tuple(v.name for v in views),
        corners_left=tuple(v.left for v in views), corners_right=tuple(v.right for v in views),
        reordered=tuple(reordered), board=target.describe(), verdict=verdict)


def _unobservable(names: Sequence[str]) -> list[str]:
    if not names:
        return []
    return [f"not observable from these views: {', '.join(names)} (std reported as unknown); add views covering "
            "the image corners at varied tilt"]


def _detect(paths: Sequence[Path], target: AnyTarget, *, jobs: int | None, cache_dir: Path | None,
            progress: ProgressCallback | None, hashes: dict[Path, str]) -> list[Detection]:
    def items() -> list[DetectItem]:
        out = []
        for p in paths:
            hashes[Path(p)] = sha256_file(p)
            out.append(DetectItem(name=f"{Path(p).parent.name}/{Path(p).name}", sha256=hashes[Path(p)],
                                  source=Path(p)))
        return out

    cache = CornerCache(cache_dir, target) if cache_dir is not None else None
    return list(detect_stream(items(), pattern=(0, 0), jobs=jobs or usable_cores(), cache=cache,
                              total=len(paths), progress=progress, target=target))


def calibrate_stereo_target(
    left_paths: Sequence[Path], right_paths: Sequence[Path], *, target: AnyTarget, lens: str = "pinhole",
    distortion: str = DEFAULT_LENS, name: str = "calibrated", max_error_px: float | None = None,
    fix_intrinsics: bool = False, swap: bool = False, jobs: int | None = None, cache_dir: Path | None = None,
    progress: ProgressCallback | None = None, names: Sequence[str] | None = None, unpaired: Sequence[Path] = (),
) -> StereoCalibration:
    """Calibrate a stereo pair from image files of ``target`` (partial views used) through ``lens``
    (``pinhole`` or ``fisheye``); ``left_paths[i]`` pairs with ``right_paths[i]``."""
    hashes: dict[Path, str] = {}
    interleaved = [p for pair in zip(left_paths, right_paths, strict=True) for p in pair]
    dets = _detect(interleaved, target, jobs=jobs, cache_dir=cache_dir, progress=progress, hashes=hashes)
    labels = list(names) if names is not None else [Path(p).stem for p in left_paths]
    pairs = [(n, dets[2 * k], dets[2 * k + 1]) for k, n in enumerate(labels)]
    extra = [DroppedView(name=f"{Path(p).parent.name}/{Path(p).name}", reason="unpaired: no partner image")
             for p in unpaired]
    report(progress, 0, 1, "solving")
    result = calibrate_stereo_target_detections(
        pairs, target=target, lens=lens, distortion=distortion, name=name, max_error_px=max_error_px,
        fix_intrinsics=fix_intrinsics, swap=swap,
        sources=[SourceFile(path=str(p), sha256=h) for p, h in hashes.items()],
        extra_dropped=extra, jobs=jobs or usable_cores())
    report(progress, 1, 1, "solving")
    idx = labels.index(result.used_names[0])
    sample = (Path(right_paths[idx]), Path(left_paths[idx])) if swap else (Path(left_paths[idx]),
                                                                          Path(right_paths[idx]))
    return StereoCalibration(**{**result.__dict__, "sample_paths": sample,
                                "detection_cached": sum(d.cached for d in dets)})
