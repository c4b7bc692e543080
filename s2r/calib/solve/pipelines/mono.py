"""Single-camera calibration (``s2r calibrate --mono``) into a :class:`~s2r.profile.MonoProfile`."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import CornerCache, Detection, DetectItem, detect_stream
from s2r.calib.detect.chessboard import board_object_points
from s2r.calib.detect.coverage import Coverage, PoseSpread, coverage_of, coverage_warnings, pose_spread
from s2r.calib.solve.honesty.models import ModelComparison, compare_models
from s2r.calib.solve.honesty.mono_resample import MonoHeldout, mono_heldout, reported_std
from s2r.calib.solve.honesty.projection import ProjectionMap
from s2r.calib.solve.honesty.verdict import Verdict, mono_verdict
from s2r.calib.solve.pipelines.mono_figures import mono_projection
from s2r.calib.solve.pipelines.stereo import make_camera
from s2r.calib.solve.pipelines.stereo_figures import board_text, dropped_warning, repeat_warning
from s2r.calib.solve.solvers.cvsolve import MonoSolution, outlier_threshold, solve_mono
from s2r.calib.solve.views import MIN_VIEWS, check_sizes, merge_repeats, no_board_error, select_diverse, too_few_error
from s2r.executor import usable_cores
from s2r.fileio import sha256_file
from s2r.lens.fold import fold_warnings
from s2r.lens.models import DEFAULT_LENS, LENS_MODELS
from s2r.profile import CalibrationQuality, DroppedView, MonoProfile, Provenance, SourceFile
from s2r.progress import ProgressCallback

__all__ = ["MonoCalibration", "calibrate_mono", "calibrate_mono_detections"]

log = logging.getLogger(__name__)
Corners = NDArray[np.float32]
_METHOD = "s2r calibrate --mono: OpenCV calibrateCameraExtended"


@dataclass(frozen=True)
class MonoCalibration:
    """A single-camera calibration: the profile, per-view RMS (px) of used views, dropped views, coverage."""

    profile: MonoProfile
    view_names: tuple[str, ...]
    view_errors_px: tuple[float, ...]
    dropped: tuple[DroppedView, ...]
    threshold_px: float
    coverage: Coverage
    spread: PoseSpread
    warnings: tuple[str, ...]
    corners: tuple[Corners, ...] = field(repr=False)
    sample_path: Path | None = None
    models: ModelComparison | None = None
    verdict: Verdict | None = None
    heldout: MonoHeldout | None = None
    board: str = ""
    projection: dict[str, dict[str, ProjectionMap | None]] = field(default_factory=dict, repr=False)

    def figures(self) -> dict[str, Any]:
        """The figures as JSON-ready values (what ``--json`` prints)."""
        cam = self.profile.camera
        quality = self.profile.provenance.calibration
        return {
            "verdict": None if self.verdict is None else self.verdict.as_dict(),
            "profile": self.profile.name,
            "camera": {"fx_px": cam.fx_px, "fy_px": cam.fy_px, "cx_px": cam.cx_px, "cy_px": cam.cy_px,
                       "distortion": list(cam.distortion.coefficients),
                       "std": None if cam.std is None else cam.std.model_dump(mode="json")},
            "quality": None if quality is None else quality.model_dump(mode="json"),
            "threshold_px": self.threshold_px,
            "views": [{"name": n, "rms_px": e} for n, e in zip(self.view_names, self.view_errors_px, strict=True)],
            "dropped": [d.model_dump(mode="json") for d in self.dropped],
            "coverage_grid": self.coverage.counts.tolist(),
            "warnings": list(self.warnings),
            "model_comparison": None if self.models is None else self.models.as_dict(),
            "board": self.board,
            "heldout": None if self.heldout is None else self.heldout.as_dict(),
            "projection_uncertainty": {side: {src: None if m is None else m.as_dict() for src, m in maps.items()}
                                       for side, maps in self.projection.items()},
        }


def _solve_with_outliers(names: list[str], corners: list[Corners], obj: Corners, size: tuple[int, int], *,
                         pattern: tuple[int, int], distortion: str,
                         max_error_px: float | None) -> tuple[list[int], MonoSolution, float, list[DroppedView]]:
    keep = select_diverse(corners, pattern, size)
    if len(keep) < len(names):
        log.warning("%d usable images; solving with the %d most diverse (MAX_SOLVE_VIEWS)", len(names), len(keep))
    dropped: list[DroppedView] = []
    thr: float | None = None
    while True:
        sol = solve_mono([obj] * len(keep), [corners[i] for i in keep], size, distortion=distortion)
        if thr is None:
            thr = outlier_threshold(sol.per_view_px, max_error_px=max_error_px)
        bad = [j for j, e in enumerate(sol.per_view_px) if e > thr]
        if not bad or len(keep) - len(bad) < MIN_VIEWS:
            return keep, sol, thr, dropped
        dropped += [DroppedView(name=names[keep[j]], rms_px=float(sol.per_view_px[j]),
                                reason=f"outlier: RMS {sol.per_view_px[j]:.3f} px > {thr:.3f} px") for j in bad]
        keep = [k for j, k in enumerate(keep) if j not in set(bad)]


def calibrate_mono(paths: Sequence[Path], *, pattern: tuple[int, int], square_m: float,
                   name: str = "calibrated", distortion: str = DEFAULT_LENS, max_error_px: float | None = None,
                   jobs: int | None = None, cache_dir: Path | None = None,
                   progress: ProgressCallback | None = None, compare: bool = True) -> MonoCalibration:
    """Calibrate one camera from chessboard image files; see :func:`calibrate_mono_detections` (``jobs``:
    detection and resampling processes, default all cores; ``cache_dir``: the corner cache folder)."""
    hashes = {Path(p): sha256_file(p) for p in paths}
    items = (DetectItem(name=f"{Path(p).parent.name}/{Path(p).name}", sha256=hashes[Path(p)], source=Path(p))
             for p in paths)
    cache = CornerCache(cache_dir) if cache_dir is not None else None
    jobs = jobs or usable_cores()
    dets = list(detect_stream(items, pattern=pattern, jobs=jobs, cache=cache, total=len(paths), progress=progress))
    result = calibrate_mono_detections(dets, pattern=pattern, square_m=square_m, name=name, distortion=distortion,
                                       max_error_px=max_error_px, jobs=jobs, compare=compare,
                                       sources=[SourceFile(path=str(p), sha256=h) for p, h in hashes.items()])
    by_name = {d.name: Path(p) for p, d in zip(paths, dets, strict=True)}
    return replace(result, sample_path=by_name.get(result.view_names[0]))


def _views(dets: Sequence[Detection], pattern: tuple[int, int]
           ) -> tuple[list[str], list[Corners], list[DroppedView], list[DroppedView]]:
    """Names and corners of the images whose board was found (repeats merged), the skipped images and the
    repeats, each with its reason."""
    ok = [d for d in dets if d.status == "ok" and d.corners is not None]
    skipped = [DroppedView(name=d.name, reason=f"{d.status.replace('_', ' ')}: {d.detail}")
               for d in dets if d.status != "ok"]
    if not ok:
        raise no_board_error(sum(d.status != "unreadable" for d in dets), pattern)
    names = [d.name for d in ok]
    corners = [d.corners for d in ok if d.corners is not None]
    keep, repeats = merge_repeats(names, corners, corners)
    if len(keep) < MIN_VIEWS:
        raise too_few_error(len(keep), [*skipped, *repeats], what="images", pattern=pattern)
    return [names[i] for i in keep], [corners[i] for i in keep], skipped, repeats


def calibrate_mono_detections(dets: Sequence[Detection], *, pattern: tuple[int, int], square_m: float,
                              name: str = "calibrated", distortion: str = DEFAULT_LENS,
                              max_error_px: float | None = None, jobs: int = 1, compare: bool = True,
                              sources: Sequence[SourceFile] = ()) -> MonoCalibration:
    """Calibrate one camera from per-image chessboard detections: repeated views merged, the same outlier and
    coverage rules as :func:`s2r.calib.calibrate_stereo`, a held-out error over 4 interleaved folds with the
    jackknife std beside the covariance's (the larger reported and written to the profile), the lens models
    compared on held-out views (``compare``) and the verdict; ``jobs``: processes of the fold solves."""
    size = check_sizes(dets)
    names, corners, skipped, repeats = _views(dets, pattern)
    obj = board_object_points(pattern, square_m)
    keep, sol, thr, outliers = _solve_with_outliers(names, corners, obj, size, pattern=pattern,
                                                    distortion=distortion, max_error_px=max_error_px)
    used = [corners[i] for i in keep]
    held, models = mono_heldout([obj] * len(used), used, sol, size, distortion=distortion,
                                max_error_px=max_error_px, jobs=jobs, compare=tuple(LENS_MODELS) if compare else ())
    if held is None and compare:  # too few views for the folds: the leave-views-out comparison alone
        models = compare_models(used, None, obj, size, chosen=distortion, guess=((sol.K, sol.D), (sol.K, sol.D)))
    std = reported_std(sol.std, held)
    cov = coverage_of(used, size)
    spread = pose_spread(sol.rvecs, sol.tvecs, used, pattern=pattern, square_m=square_m, size=size)
    dropped = (*skipped, *repeats, *outliers)
    quality = CalibrationQuality(
        pattern=pattern, square_m=square_m, views_used=len(keep), views_dropped=dropped, rms_left_px=sol.rms_px,
        views_detected=len(names) + len(repeats),
        coverage_left=cov.fraction, tilt_range_deg=spread.tilt_deg, distance_range_m=spread.distance_m,
        distortion_terms=distortion)
    profile = MonoProfile(name=name, camera=make_camera(sol.K, sol.D, size, std, distortion=distortion),
                          provenance=Provenance(origin="real", method=_METHOD, calibration=quality,
                                                sources=tuple(sources)))
    unobservable = [n for n, sd in zip(("fx", "fy", "cx", "cy"), sol.std[:4], strict=True) if not np.isfinite(sd)]
    folds = fold_warnings([("the", profile.camera)])
    warnings = [*repeat_warning(repeats), *dropped_warning(outliers),
                *([models.warning] if models is not None and models.warning else []),
                *coverage_warnings("the", cov, spread), *folds]
    for w in warnings:
        log.warning("%s", w)
    cam = profile.camera
    heldout = held.heldout_px if held is not None else None if models is None else \
        next(m.heldout_px for m in models.scores if m.chosen)
    verdict = mono_verdict(
        rms_px=sol.rms_px, heldout_px=heldout,
        fx_px=cam.fx_px, fx_std_px=None if cam.std is None else cam.std.fx_px, coverage=cov.fraction,
        model_warning=None if models is None else models.warning, unobservable=unobservable, lens_folds=folds)
    return MonoCalibration(profile=profile, view_names=tuple(names[i] for i in keep),
                           view_errors_px=tuple(float(e) for e in sol.per_view_px), dropped=dropped,
                           threshold_px=thr, coverage=cov, spread=spread, warnings=tuple(warnings),
                           corners=tuple(used), models=models, verdict=verdict, heldout=held,
                           board=board_text(pattern, square_m),
                           projection={"camera": mono_projection([obj] * len(used), used, sol, held, size,
                                                                 distortion=distortion)})
