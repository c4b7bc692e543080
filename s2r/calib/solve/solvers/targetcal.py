"""Calibration from corners with ids: file-described targets (``--target``) and fisheye lenses (``--lens``).

Each view is a set of (corner id, board point, image point), so views where the board is cut by the image
edge count corner by corner. Each camera is solved on every view it saw (pinhole:
``cv2.calibrateCameraExtended``; fisheye: :func:`s2r.calib.solve.solvers.fisheye.solve_mono_fisheye`), views above the
robust threshold dropped and the solve repeated; then the pair is solved on the corners both cameras saw,
matched by id (pinhole: ``cv2.stereoCalibrateExtended`` with the intrinsics fixed; fisheye:
:func:`s2r.calib.solve.solvers.fisheye.solve_stereo_fisheye`), with the same outlier rule, the baseline's first-order
standard deviation, coverage counted over the corners actually seen, and the epipolar error after
rectification.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import Detection
from s2r.calib.detect.coverage import PoseSpread, coverage_of, coverage_warnings, pose_spread
from s2r.calib.detect.markers import usable_corners
from s2r.calib.solve.solvers.cvsolve import (
    MonoSolution,
    StereoSolution,
    baseline_covariance,
    outlier_threshold,
    solve_mono,
    solve_stereo,
)
from s2r.calib.solve.solvers.fisheye import (
    FisheyeMono,
    fisheye_baseline_covariance,
    solve_mono_fisheye,
    solve_stereo_fisheye,
)
from s2r.calib.solve.views import MIN_VIEWS, check_sizes, match_corner_order, too_few_error
from s2r.errors import CalibrationError
from s2r.lens.models import LensModel
from s2r.profile import CalibrationQuality, Camera, CameraUncertainty, Distortion, DroppedView, SourceFile
from s2r.targets import AnyTarget, CharucoTarget, CheckerboardTarget

__all__ = [
    "LENSES",
    "CameraViews",
    "MonoFit",
    "Observation",
    "fit_camera",
    "observations",
    "target_pattern",
    "to_camera",
]

log = logging.getLogger(__name__)
Corners = NDArray[np.float32]
Ids = NDArray[np.int32]
#: ``--lens`` choices: the projection model behind the distortion terms.
LENSES = ("pinhole", "fisheye")
_MAX_ROUNDS = 5
#: A corner is an outlier beyond this multiple of the median corner error (at least the floor, px).
CORNER_OUTLIER_FACTOR = 4.0
CORNER_OUTLIER_FLOOR_PX = 0.3


@dataclass(frozen=True)
class Observation:
    """One camera's view: image name, corner ids (N,), board points (N, 3) float32 m, image points (N, 2) px."""

    name: str
    ids: Ids
    obj: NDArray[np.float32]
    img: Corners


def observations(dets: Sequence[Detection], target: AnyTarget) -> list[Observation | None]:
    """The usable observation of each detection (None when not found or too few / collinear corners)."""
    out: list[Observation | None] = []
    for d in dets:
        if d.status != "ok" or d.corners is None:
            out.append(None)
            continue
        ids = d.ids if d.ids is not None else np.arange(len(d.corners), dtype=np.int32)
        obj = target.points_of(ids)
        out.append(Observation(d.name, ids, obj.astype(np.float32), d.corners) if usable_corners(ids, obj) else None)
    return out


def target_pattern(target: AnyTarget) -> tuple[tuple[int, int], float]:
    """``(pattern, square_m)`` recorded in the calibration quality for a target (its corner grid)."""
    if isinstance(target, CheckerboardTarget):
        return target.pattern, target.colSpacingMeters
    if isinstance(target, CharucoTarget):
        return (target.squaresX - 1, target.squaresY - 1), target.squareLength
    return (2 * target.tagCols, 2 * target.tagRows), target.tagSize


@dataclass(frozen=True)
class MonoFit:
    """One camera's solve: kept view indices, solution, intrinsics covariance (fisheye), threshold, outliers
    and the views as solved (outlier corners removed)."""

    keep: list[int]
    solution: MonoSolution
    cov: NDArray[np.float64] | None
    threshold: float
    outliers: list[DroppedView]
    views: list[Observation]


@dataclass(frozen=True)
class CameraViews:
    """The observations one camera made, the image size and what to fit."""

    views: list[Observation]
    size: tuple[int, int]
    lens: str
    distortion: str
    #: drop single outlier corners (boards identified corner by corner; a chessboard keeps its full grid)
    prune_corners: bool = True


def _solve(cv: CameraViews, keep: Sequence[int]) -> tuple[MonoSolution, NDArray[np.float64] | None]:
    objs, imgs = [cv.views[i].obj for i in keep], [cv.views[i].img for i in keep]
    if cv.lens == "fisheye":
        fm: FisheyeMono = solve_mono_fisheye(objs, imgs, cv.size)
        return fm.solution, fm.cov
    return solve_mono(objs, imgs, cv.size, distortion=cv.distortion), None


def fit_camera(cv: CameraViews, *, max_error_px: float | None, camera: str) -> MonoFit:
    """Solve one camera on all its views; drop views above the robust threshold (of the first solve) and
    repeat until none is (or fewer than MIN_VIEWS would remain)."""
    keep = list(range(len(cv.views)))
    outliers: list[DroppedView] = []
    thr: float | None = None
    for _ in range(_MAX_ROUNDS):
        sol, cov = _solve(cv, keep)
        if thr is None:
            thr = outlier_threshold(sol.per_view_px, max_error_px=max_error_px)
        bad = [j for j, e in enumerate(sol.per_view_px) if e > thr]
        if not bad or len(keep) - len(bad) < MIN_VIEWS:
            break
        outliers += [DroppedView(name=cv.views[keep[j]].name, rms_px=float(sol.per_view_px[j]),
                                 reason=f"outlier: {camera} RMS {sol.per_view_px[j]:.3f} px > {thr:.3f} px")
                     for j in bad]
        keep = [k for j, k in enumerate(keep) if j not in set(bad)]
    assert thr is not None
    pruned = _prune_corners(cv, keep, sol) if cv.prune_corners else None
    if pruned is not None:
        cv.views[:] = pruned
        sol, cov = _solve(cv, keep)
    return MonoFit(keep, sol, cov, thr, outliers, list(cv.views))


def corner_residuals(sol: MonoSolution, obs: Observation, lens: str, j: int) -> NDArray[np.float64]:
    """Reprojection error (N,) px of each corner of ``obs``, view ``j`` of the solution."""
    obj = obs.obj.astype(np.float64).reshape(-1, 1, 3)
    if lens == "fisheye":
        proj, _ = cv2.fisheye.projectPoints(obj, sol.rvecs[j].reshape(3, 1), sol.tvecs[j].reshape(3, 1), sol.K,
                                            sol.D.reshape(4, 1))
    else:
        proj, _ = cv2.projectPoints(obj, sol.rvecs[j], sol.tvecs[j], sol.K, sol.D)
    return np.asarray(np.linalg.norm(np.asarray(proj).reshape(-1, 2) - obs.img.reshape(-1, 2), axis=1), np.float64)


def _prune_corners(cv: CameraViews, keep: Sequence[int], sol: MonoSolution) -> list[Observation] | None:
    """The views without corners whose error exceeds ``CORNER_OUTLIER_FACTOR`` x the median corner error
    (at least ``CORNER_OUTLIER_FLOOR_PX``): a corner pulled by a marker edge or a neighbour spoils a good
    view; None when no corner is that far off."""
    res = {k: corner_residuals(sol, cv.views[k], cv.lens, j) for j, k in enumerate(keep)}
    limit = max(CORNER_OUTLIER_FACTOR * float(np.median(np.concatenate(list(res.values())))),
                CORNER_OUTLIER_FLOOR_PX)
    if not any(bool(np.any(r > limit)) for r in res.values()):
        return None
    views = list(cv.views)
    for k, r in res.items():
        ok = r <= limit
        o = views[k]
        if not ok.all() and usable_corners(o.ids[ok], o.obj[ok].astype(np.float64)):
            views[k] = Observation(o.name, o.ids[ok], o.obj[ok], o.img[ok])
    log.info("dropped corners farther than %.2f px from the first solve's projection", limit)
    return views


def to_camera(sol: MonoSolution, size: tuple[int, int], *, lens: str, distortion: str) -> Camera:
    """A profile camera from a solution: equidistant for fisheye lenses, else OpenCV's pinhole model."""
    if lens == "fisheye":
        model, ncoef = "equidistant", 4
    else:
        model, ncoef = ("rational_polynomial", 8) if distortion == "rational" else ("plumb_bob", 5)
    K, std = sol.K, sol.std
    return Camera(
        width_px=size[0], height_px=size[1], fx_px=float(K[0, 0]), fy_px=float(K[1, 1]), cx_px=float(K[0, 2]),
        cy_px=float(K[1, 2]),
        distortion=Distortion(model=model,  # type: ignore[arg-type]
                              coefficients=tuple(float(v) for v in np.asarray(sol.D).reshape(-1)[:ncoef])),
        std=CameraUncertainty(fx_px=float(std[0]), fy_px=float(std[1]), cx_px=float(std[2]), cy_px=float(std[3]),
                              distortion=tuple(float(v) for v in std[4:4 + ncoef])))


def camera_of(K: NDArray[np.float64], D: NDArray[np.float64], std: NDArray[np.float64], size: tuple[int, int],
              model: LensModel) -> Camera:
    """A profile camera from the joint solve: K, D (the model's stored coefficients), std ``(fx fy cx cy d..)``
    with inf for unobservable parameters (stored as unknown)."""
    def sd(v: float) -> float | None:
        return float(v) if np.isfinite(v) else None

    dstd = [float(v) for v in std[4:4 + model.n_coef]]
    return Camera(
        width_px=size[0], height_px=size[1], fx_px=float(K[0, 0]), fy_px=float(K[1, 1]), cx_px=float(K[0, 2]),
        cy_px=float(K[1, 2]),
        distortion=Distortion(model=model.profile_model,  # type: ignore[arg-type]
                              coefficients=tuple(float(v) for v in np.asarray(D).reshape(-1)[:model.n_coef])),
        std=CameraUncertainty(fx_px=sd(std[0]), fy_px=sd(std[1]), cx_px=sd(std[2]), cy_px=sd(std[3]),
                              distortion=tuple(dstd) if all(np.isfinite(dstd)) else None))


def centred_spread(sol: MonoSolution, views: Sequence[Observation], target: AnyTarget,
                   size: tuple[int, int]) -> PoseSpread:
    """Tilt, distance (to the target's centre) and image share of the solved views."""
    centre = target.object_points().mean(axis=0)
    tv = [t + cv2.Rodrigues(r)[0] @ centre for r, t in zip(sol.rvecs, sol.tvecs, strict=True)]
    return pose_spread(sol.rvecs, tv, [v.img for v in views], pattern=(1, 1), square_m=1.0, size=size)


def quality_of(target: AnyTarget, *, lens: str, distortion: str, **figures: object) -> CalibrationQuality:
    """The calibration quality record of a target calibration (``target`` names the board)."""
    pattern, square = target_pattern(target)
    terms = "equidistant" if lens == "fisheye" else distortion
    return CalibrationQuality(pattern=pattern, square_m=square, target=target.describe(), distortion_terms=terms,
                              **figures)  # type: ignore[arg-type]


@dataclass(frozen=True)
class PairView:
    """Corners both cameras saw in one pair, matched by id; indices into each camera's kept views."""

    name: str
    obj: NDArray[np.float32]
    left: Corners
    right: Corners
    idx_l: int
    idx_r: int


def pair_views(names: Sequence[str], left: Sequence[Observation | None], right: Sequence[Observation | None],
               keep_l: dict[int, int], keep_r: dict[int, int], target: AnyTarget) -> tuple[list[PairView], list[str]]:
    """Pairs whose both views were kept, their common corner ids (right full chessboards put in the left's
    order first); returns the pair views and the names of pairs whose right corners were reordered."""
    out, reordered = [], []
    for k, (name, ol, orr) in enumerate(zip(names, left, right, strict=True)):
        if ol is None or orr is None or k not in keep_l or k not in keep_r:
            continue
        r_img, r_ids = orr.img, orr.ids
        if isinstance(target, CheckerboardTarget):
            r_img, flipped = match_corner_order(ol.img, orr.img, target.pattern)
            if flipped:
                reordered.append(name)
        common, il, ir = np.intersect1d(ol.ids, r_ids, return_indices=True)
        obj = target.points_of(common)
        if not usable_corners(common.astype(np.int32), obj):
            continue
        out.append(PairView(name, obj.astype(np.float32), ol.img[il], r_img[ir], keep_l[k], keep_r[k]))
    return out, reordered


def solve_pair(views: Sequence[PairView], fit_l: MonoFit, fit_r: MonoFit, size: tuple[int, int], *, lens: str,
               distortion: str) -> StereoSolution:
    """The pair's motion from the corners both cameras saw, intrinsics from the mono fits."""
    objs, pl, pr = [v.obj for v in views], [v.left for v in views], [v.right for v in views]
    if lens == "fisheye":
        return solve_stereo_fisheye(objs, pl, pr, fit_l.solution, fit_r.solution, idx_l=[v.idx_l for v in views],
                                    idx_r=[v.idx_r for v in views])
    return solve_stereo(objs, pl, pr, size, fit_l.solution, fit_r.solution, distortion=distortion)


def baseline_cov(views: Sequence[PairView], st: StereoSolution, fit_l: MonoFit, fit_r: MonoFit, *, lens: str,
                 distortion: str) -> NDArray[np.float64]:
    """Covariance (3x3, m^2) of the translation, both lens kinds."""
    objs, pl, pr = [v.obj for v in views], [v.left for v in views], [v.right for v in views]
    if lens == "fisheye":
        assert fit_l.cov is not None and fit_r.cov is not None
        return fisheye_baseline_covariance(objs, pl, pr, st, fit_l.cov, fit_r.cov)[0]
    return baseline_covariance(objs, pl, pr, st, distortion=distortion, fixed_intrinsics=True)[0]


def check_enough(found: int, dropped: Sequence[DroppedView], *, what: str) -> None:
    """CalibrationError when fewer than MIN_VIEWS usable views remain."""
    if found < MIN_VIEWS:
        raise too_few_error(found, dropped, what=what)


def sizes_of(dets: Sequence[Detection]) -> tuple[int, int]:
    """The one image size of the detections (CalibrationError otherwise)."""
    return check_sizes(dets)


def camera_warnings(camera: str, views: Sequence[Corners], size: tuple[int, int], spread: PoseSpread | None
                    ) -> tuple[float, list[str], object]:
    """Coverage fraction, warnings and the coverage of corners actually seen."""
    cov = coverage_of(list(views), size)
    return cov.fraction, coverage_warnings(camera, cov, spread), cov


def sample_of(paths: Sequence[Path], names: Sequence[str], first: str) -> Path | None:
    """The file of view ``first``."""
    return next((Path(p) for p, n in zip(paths, names, strict=True) if n == first), None)


def source_list(hashes: dict[Path, str]) -> tuple[SourceFile, ...]:
    """Provenance entries of the input files."""
    return tuple(SourceFile(path=str(p), sha256=h) for p, h in hashes.items())


def no_target_error(n_images: int, target: AnyTarget) -> CalibrationError:
    """The error for 'the target was found nowhere', nearly always a wrong TARGET.yaml."""
    return CalibrationError(f"no {target.describe()} found in any of the {n_images} readable images",
                            field="--target", hint="check the target file: sizes, tag/square counts, dictionary "
                                                   "(and legacyPattern for boards drawn by OpenCV <= 4.5)")
