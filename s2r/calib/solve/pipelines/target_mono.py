"""One camera with corner ids: ``s2r calibrate --mono --target TARGET.yaml`` and ``--mono --lens fisheye``.

The same inputs, cache and rules as the stereo corner-id path (:mod:`.target_stereo`), and the same honest
figures as the chessboard ``--mono`` path (:mod:`.mono`): repeated views merged with a warning, a held-out error
over 4 interleaved folds of views, the jackknife std of fx, fy, cx, cy beside the covariance's (the larger
reported and written to the profile), the dropped views with their reasons, the board stated, a verdict.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from s2r.calib.detect import Detection
from s2r.calib.detect.coverage import coverage_of, coverage_warnings
from s2r.calib.solve.honesty.target import merge_repeat_observations, mono_fit_heldout
from s2r.calib.solve.honesty.verdict import mono_verdict
from s2r.calib.solve.pipelines.mono import MonoCalibration
from s2r.calib.solve.pipelines.mono_figures import mono_projection
from s2r.calib.solve.pipelines.stereo_figures import dropped_warning, repeat_warning
from s2r.calib.solve.pipelines.target_stereo import _detect, _method, _skipped
from s2r.calib.solve.solvers.targetcal import (
    CameraViews,
    centred_spread,
    fit_camera,
    no_target_error,
    observations,
    quality_of,
    to_camera,
)
from s2r.calib.solve.views import MIN_VIEWS, check_sizes, too_few_error
from s2r.executor import usable_cores
from s2r.lens.fold import fold_warnings
from s2r.lens.models import DEFAULT_LENS
from s2r.profile import MonoProfile, Provenance, SourceFile
from s2r.progress import ProgressCallback
from s2r.targets import AnyTarget, CheckerboardTarget

__all__ = ["calibrate_mono_target", "calibrate_mono_target_detections"]

log = logging.getLogger(__name__)


def calibrate_mono_target(
    paths: Sequence[Path], *, target: AnyTarget, lens: str = "pinhole", distortion: str = DEFAULT_LENS,
    name: str = "calibrated", max_error_px: float | None = None, jobs: int | None = None,
    cache_dir: Path | None = None, progress: ProgressCallback | None = None,
) -> MonoCalibration:
    """Calibrate one camera from image files of ``target`` (partial views used) through ``lens``; see
    :func:`calibrate_mono_target_detections`."""
    hashes: dict[Path, str] = {}
    jobs = jobs or usable_cores()
    dets = _detect(paths, target, jobs=jobs, cache_dir=cache_dir, progress=progress, hashes=hashes)
    result = calibrate_mono_target_detections(
        dets, target=target, lens=lens, distortion=distortion, name=name, max_error_px=max_error_px, jobs=jobs,
        sources=[SourceFile(path=str(p), sha256=h) for p, h in hashes.items()])
    first = next(p for p, d in zip(paths, dets, strict=True) if d.name == result.view_names[0])
    return replace(result, sample_path=Path(first))


def calibrate_mono_target_detections(
    dets: Sequence[Detection], *, target: AnyTarget, lens: str = "pinhole", distortion: str = DEFAULT_LENS,
    name: str = "calibrated", max_error_px: float | None = None, jobs: int = 1, sources: Sequence[SourceFile] = (),
) -> MonoCalibration:
    """Calibrate one camera from per-image detections with corner ids (``jobs``: processes of the fold solves)."""
    size = check_sizes(dets)
    obs = observations(dets, target)
    if not any(o is not None for o in obs):
        raise no_target_error(sum(d.status != "unreadable" for d in dets), target)
    skipped = _skipped(dets, obs)
    views, repeats = merge_repeat_observations([o for o in obs if o is not None])
    if len(views) < MIN_VIEWS:
        raise too_few_error(len(views), [*skipped, *repeats], what="images")
    prune = not isinstance(target, CheckerboardTarget)
    fit = fit_camera(CameraViews(views, size, lens, distortion, prune), max_error_px=max_error_px, camera="the")
    fit, held = mono_fit_heldout(fit, size, lens=lens, distortion=distortion, max_error_px=max_error_px, jobs=jobs,
                                 prune_corners=prune)
    used = [views[i] for i in fit.keep]
    cov = coverage_of([v.img for v in views], size)
    spread = centred_spread(fit.solution, used, target, size)
    dropped = (*skipped, *repeats, *fit.outliers)
    quality = quality_of(target, lens=lens, distortion=distortion, views_used=len(used), views_dropped=dropped,
                         views_detected=len(views) + len(repeats), rms_left_px=fit.solution.rms_px,
                         coverage_left=cov.fraction, tilt_range_deg=spread.tilt_deg,
                         distance_range_m=spread.distance_m)
    profile = MonoProfile(name=name, camera=to_camera(fit.solution, size, lens=lens, distortion=distortion),
                          provenance=Provenance(origin="real", method=_method(lens, False), calibration=quality,
                                                sources=tuple(sources)))
    folds = fold_warnings([("the", profile.camera)])
    warnings = [*repeat_warning(repeats), *dropped_warning(fit.outliers), *coverage_warnings("the", cov, spread),
                *folds]
    for w in warnings:
        log.warning("%s", w)
    cam = profile.camera
    verdict = mono_verdict(rms_px=fit.solution.rms_px, heldout_px=None if held is None else held.heldout_px,
                           fx_px=cam.fx_px, fx_std_px=None if cam.std is None else cam.std.fx_px,
                           coverage=cov.fraction, lens_folds=folds)
    return MonoCalibration(profile=profile, view_names=tuple(v.name for v in used),
                           view_errors_px=tuple(float(e) for e in fit.solution.per_view_px), dropped=dropped,
                           threshold_px=fit.threshold, coverage=cov, spread=spread, warnings=tuple(warnings),
                           corners=tuple(v.img for v in used), verdict=verdict, heldout=held,
                           board=target.describe(), projection={} if lens == "fisheye" else {"camera": mono_projection(
                               [v.obj for v in used], [v.img for v in used], fit.solution, held, size,
                               distortion=distortion)})
