"""Solve a stereo pair from matched chessboard views: checks, then one joint solve (default) or ROS's way.

Default: each camera alone with OpenCV (:func:`s2r.calib.solve.solvers.rig.initial_rig`), the checks of
:mod:`s2r.calib.solve.solvers.rig` (identical images, mismatched pairs, ``--square`` unit, swapped cameras), then
:func:`s2r.calib.solve.solvers.joint.solve_joint` refining both cameras, the extrinsics and every board pose together
with outliers rejected inside the loop; every standard deviation comes from that solve's covariance.

``fix_intrinsics`` (ROS camera_calibration's way): intrinsics from the mono solves, held fixed in
``cv2.stereoCalibrate``; the baseline std then adds the intrinsics' uncertainty propagated through the
extrinsics (:func:`s2r.calib.solve.solvers.cvsolve.extrinsics_covariance`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.cvsolve import extrinsics_covariance, outlier_threshold, solve_mono, solve_stereo
from s2r.calib.solve.solvers.joint import START_DAMPING, WARM_DAMPING, JointInit, JointSolution, solve_joint
from s2r.calib.solve.solvers.jointterms import Masks
from s2r.calib.solve.solvers.observations import StereoObservation, chessboard_observation
from s2r.calib.solve.solvers.rig import RigInit, check_rig, initial_rig, pair_consistency
from s2r.errors import CalibrationError
from s2r.lens.models import LensModel, lens_model

__all__ = ["PairSolution", "solve_pair", "solve_pair_warped"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
Corners = NDArray[np.float32]
_MIN_VIEWS = 5


@dataclass(frozen=True)
class PairSolution:
    """The solved pair. ``keep`` indexes the input views used; ``per_view`` (len(keep), 3) RMS px (left,
    right, both); ``std_left/right`` (fx fy cx cy d0..dn, inf where unobservable, 0 for fixed terms);
    ``outliers`` (input index, left px, right px, both px, reason); ``mismatched`` (input index, reason);
    ``residuals`` per used view (left (N, 2), right (N, 2)) px; board poses ``rvecs``/``tvecs`` (left camera);
    ``rms_all_px`` the RMS over every corner of the used views (rejected ones too) of ``corners_total``;
    ``rejected_corners`` (input index, left count, right count) of the views that lost corners as outliers;
    ``cov_left/right`` the covariance of (fx, fy, cx, cy, free coefficients) per camera (joint solve only);
    ``warp_m`` the board's bend (x, y; metres at the board centre) and its std when it was solved;
    ``inliers`` per used view (left, right) the kept-corner masks (joint solve only: the warm start of the
    resampling solves); ``converged`` False when the joint solve stopped at its step limit still improving."""

    K1: FloatArray
    D1: FloatArray
    K2: FloatArray
    D2: FloatArray
    R: FloatArray
    T: FloatArray
    std_left: FloatArray
    std_right: FloatArray
    baseline_std_m: float
    rotation_std_deg: float
    rms_left_px: float
    rms_right_px: float
    rms_px: float
    keep: tuple[int, ...]
    per_view: FloatArray
    threshold_px: float
    outliers: tuple[tuple[int, float, float, float, str], ...]
    mismatched: tuple[tuple[int, str], ...]
    unobservable: tuple[str, ...]
    residuals: tuple[tuple[FloatArray, FloatArray], ...]
    rvecs: tuple[FloatArray, ...]
    tvecs: tuple[FloatArray, ...]
    method: str
    rms_all_px: float = float("nan")
    corners_total: int = 0
    rejected_corners: tuple[tuple[int, int, int], ...] = ()
    cov_left: FloatArray | None = None
    cov_right: FloatArray | None = None
    warp_m: FloatArray | None = None
    warp_std_m: FloatArray | None = None
    inliers: tuple[tuple[NDArray[np.bool_] | None, NDArray[np.bool_] | None], ...] = ()
    converged: bool = True


def _observations(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners],
                  obj: Corners) -> list[StereoObservation]:
    return [StereoObservation(n, chessboard_observation(obj, pl), chessboard_observation(obj, pr))
            for n, pl, pr in zip(names, left, right, strict=True)]


def _checked_init(obs: list[StereoObservation], size: tuple[int, int], lens: LensModel, *, square_m: float,
                  board_m: float) -> tuple[RigInit, list[int], list[tuple[int, str]]]:
    """Initial rig on the views that agree; returns (init, kept indices, mismatched (index, reason))."""
    init = initial_rig(obs, size, lens)
    if all(s.identical for s in init.scores):
        check_rig(init, square_m=square_m, board_size_m=board_m)  # raises: identical images
    bad = pair_consistency(init.scores, float(np.linalg.norm(init.T)))
    reasons = [(i, "mismatched pair: left and right images are identical" if init.scores[i].identical else
                f"mismatched pair: its left-right geometry is off by {init.scores[i].dt_m * 1000:.0f} mm / "
                f"{init.scores[i].drot_deg:.1f} deg from the other pairs") for i in bad]
    if 3 * len(bad) > len(obs):
        named = ", ".join(obs[i].name for i in bad[:6]) + (" ..." if len(bad) > 6 else "")
        raise CalibrationError(f"{len(bad)} of {len(obs)} pairs disagree on the left-right geometry ({named})",
                               field="input", hint="the left and right images do not pair up: check that each "
                                                   "pair was captured at the same moment and the files sort alike")
    keep = [i for i in range(len(obs)) if i not in set(bad)]
    if bad:
        for i, why in reasons:
            log.warning("%s: %s; dropped", obs[i].name, why)
        init = initial_rig([obs[i] for i in keep], size, lens)
    check_rig(init, square_m=square_m, board_size_m=board_m)
    return init, keep, reasons


def _camera_std(sol: JointSolution, side: str, lens: LensModel) -> FloatArray:
    std = [sol.std(f"{side} {n}") for n in ("fx", "fy", "cx", "cy")]
    dist = np.zeros(lens.n_coef)
    for i in lens.free:
        dist[i] = sol.std(f"{side} {lens.coef_names[i]}")
    return np.concatenate([std, dist])


def _intrinsics_cov(sol: JointSolution, side: str, lens: LensModel) -> FloatArray:
    idx = [sol.names.index(f"{side} {n}") for n in ("fx", "fy", "cx", "cy", *(lens.coef_names[i] for i in lens.free))]
    return np.asarray(sol.cov[np.ix_(idx, idx)], np.float64)


def _joint(obs: list[StereoObservation], keep: list[int], init: RigInit | JointInit, lens: LensModel,
           max_error_px: float | None, *, warp: bool = False, masks: Masks | None = None,
           damping: float = START_DAMPING) -> PairSolution:
    start = init if isinstance(init, JointInit) else init.joint_init()
    sol = solve_joint([obs[i] for i in keep], lens, start, max_view_error_px=max_error_px, warp=warp, masks=masks,
                      damping=damping)
    u = sol.T / np.linalg.norm(sol.T)
    b_std = float(np.sqrt(max(0.0, float(u @ sol.translation_cov() @ u))))
    r_std = float(np.degrees(np.sqrt(max(0.0, float(np.trace(sol.rotation_cov()))))))
    used = [j for j, ok in enumerate(sol.used) if ok]
    both = [float(np.sqrt(np.nanmean(sol.per_view_px[j] ** 2))) for j in range(len(keep))]
    thr = sol.view_threshold_px
    outliers = tuple((keep[j], float(sol.per_view_px[j, 0]), float(sol.per_view_px[j, 1]), both[j],
                      f"outlier: RMS {both[j]:.3f} px > {thr:.3f} px (left {sol.per_view_px[j, 0]:.3f}, right "
                      f"{sol.per_view_px[j, 1]:.3f})") for j in range(len(keep)) if not sol.used[j])
    rl = [sol.residuals[j][0] for j in used]
    rr = [sol.residuals[j][1] for j in used]
    ml = [sol.inliers[j][0] for j in used]
    mr = [sol.inliers[j][1] for j in used]
    rms_l = float(np.sqrt(np.mean(np.concatenate([np.sum(r[m] ** 2, axis=1) for r, m in zip(rl, ml, strict=True)
                                                  if r is not None and m is not None]))))
    rms_r = float(np.sqrt(np.mean(np.concatenate([np.sum(r[m] ** 2, axis=1) for r, m in zip(rr, mr, strict=True)
                                                  if r is not None and m is not None]))))
    every = [np.sum(r ** 2, axis=1) for j in used for r in sol.residuals[j] if r is not None]
    groups = tuple((keep[j], *(0 if m is None else int(np.sum(~m)) for m in sol.inliers[j])) for j in used
                   if any(m is not None and not m.all() for m in sol.inliers[j]))
    return PairSolution(
        cov_left=_intrinsics_cov(sol, "left", lens), cov_right=_intrinsics_cov(sol, "right", lens),
        rms_all_px=float(np.sqrt(np.mean(np.concatenate(every)))) if every else float("nan"),
        corners_total=int(sum(len(e) for e in every)), rejected_corners=groups,  # type: ignore[arg-type]
        K1=sol.K1, D1=sol.D1, K2=sol.K2, D2=sol.D2, R=sol.R, T=sol.T, std_left=_camera_std(sol, "left", lens),
        std_right=_camera_std(sol, "right", lens), baseline_std_m=b_std, rotation_std_deg=r_std,
        rms_left_px=rms_l, rms_right_px=rms_r, rms_px=sol.rms_px, keep=tuple(keep[j] for j in used),
        per_view=np.array([[sol.per_view_px[j, 0], sol.per_view_px[j, 1], both[j]] for j in used]),
        threshold_px=thr, outliers=outliers, mismatched=(), unobservable=sol.unobservable,
        residuals=tuple((r, q) for r, q in zip(rl, rr, strict=True)),  # type: ignore[misc]
        rvecs=tuple(sol.rvecs[j] for j in used), tvecs=tuple(sol.tvecs[j] for j in used),
        warp_m=sol.warp.copy() if warp else None, inliers=tuple(sol.inliers[j] for j in used),
        warp_std_m=np.array([sol.std("warp x"), sol.std("warp y")]) if warp else None,
        converged=sol.converged,
        method="s2r calibrate: OpenCV calibrateCameraExtended per camera to initialise, then one joint "
               f"Levenberg-Marquardt solve of both cameras ({lens.name}), extrinsics, board poses"
               + (" and the board's bend" if warp else ""))


def _fixed(obs: list[StereoObservation], keep: list[int], obj: Corners, size: tuple[int, int], lens: LensModel,
           max_error_px: float | None) -> PairSolution:
    """ROS's way: mono solves, then stereoCalibrate with the intrinsics fixed; outlier views dropped."""
    outliers: list[tuple[int, float, float, float, str]] = []
    thr: float | None = None
    while True:
        objs = [obj] * len(keep)
        pl = [obs[i].left.img.astype(np.float32) for i in keep]  # type: ignore[union-attr]
        pr = [obs[i].right.img.astype(np.float32) for i in keep]  # type: ignore[union-attr]
        ml = solve_mono(objs, pl, size, distortion=lens.name)
        mr = solve_mono(objs, pr, size, distortion=lens.name)
        st = solve_stereo(objs, pl, pr, size, ml, mr, distortion=lens.name)
        both = np.sqrt(np.mean(st.per_view_px ** 2, axis=1))
        thr = thr if thr is not None else outlier_threshold(both, max_error_px=max_error_px)
        bad = [j for j in range(len(keep)) if both[j] > thr]
        if not bad or len(keep) - len(bad) < _MIN_VIEWS:
            break
        outliers += [(keep[j], float(st.per_view_px[j, 0]), float(st.per_view_px[j, 1]), float(both[j]),
                      f"outlier: stereo RMS {both[j]:.3f} px > {thr:.3f} px") for j in bad]
        keep = [k for j, k in enumerate(keep) if j not in set(bad)]
    cov_e, _ = extrinsics_covariance(objs, pl, pr, st, distortion=lens.name, fixed_intrinsics=True)
    cov_t = cov_e[3:, 3:]
    u = st.T / np.linalg.norm(st.T)
    res = []
    for p_l, p_r, rv, tv in zip(pl, pr, st.rvecs, st.tvecs, strict=True):
        r3, t3 = cv2.composeRT(rv.reshape(3, 1), tv.reshape(3, 1), cv2.Rodrigues(st.R)[0], st.T.reshape(3, 1))[:2]
        res.append((cv2.projectPoints(obj, rv, tv, st.K1, st.D1)[0].reshape(-1, 2) - p_l,
                    cv2.projectPoints(obj, r3, t3, st.K2, st.D2)[0].reshape(-1, 2) - p_r))
    return PairSolution(
        K1=st.K1, D1=st.D1, K2=st.K2, D2=st.D2, R=st.R, T=st.T, std_left=ml.std, std_right=mr.std,
        baseline_std_m=float(np.sqrt(max(0.0, float(u @ cov_t @ u)))),
        rotation_std_deg=float(np.degrees(np.sqrt(max(0.0, float(np.trace(cov_e[:3, :3])))))),
        rms_left_px=ml.rms_px, rms_right_px=mr.rms_px, rms_px=st.rms_px, keep=tuple(keep),
        per_view=np.column_stack([st.per_view_px, np.sqrt(np.mean(st.per_view_px ** 2, axis=1))]),
        threshold_px=thr, outliers=tuple(outliers), mismatched=(),
        unobservable=tuple(f"{side} parameter {i}" for side, m in (("left", ml), ("right", mr))
                           for i, s in enumerate(m.std) if not np.isfinite(s)),
        residuals=tuple((a.astype(np.float64), b.astype(np.float64)) for a, b in res),
        rvecs=st.rvecs, tvecs=st.tvecs, rms_all_px=st.rms_px, corners_total=2 * len(obj) * len(keep),
        method="s2r calibrate --fix-intrinsics: OpenCV calibrateCameraExtended per camera, stereoCalibrate "
               "with CALIB_FIX_INTRINSIC (as ROS camera_calibration)")


def solve_pair_warped(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners], obj: Corners,
                      base: PairSolution, *, distortion: str, max_error_px: float | None = None) -> PairSolution:
    """The joint solve of ``base``'s views (``left[i]``/``right[i]``, the views ``base`` kept, in its order)
    with the board's bend also solved, started from ``base``."""
    obs = _observations(names, left, right, obj)
    init = JointInit(base.K1, base.D1, base.K2, base.D2, base.R, base.T, base.rvecs, base.tvecs)
    masks = [list(m) for m in base.inliers] or None
    return _joint(obs, list(range(len(obs))), init, lens_model(distortion), max_error_px, warp=True, masks=masks,
                  damping=WARM_DAMPING)


def solve_pair(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners], obj: Corners,
               size: tuple[int, int], *, distortion: str, max_error_px: float | None = None,
               fix_intrinsics: bool = False, square_m: float = 0.025) -> PairSolution:
    """Check and solve matched views (``left[i]``/``right[i]`` corners of board points ``obj``).

    Raises:
        CalibrationError: identical images, more than a third of the pairs mismatched, implausible
            geometry for ``square_m``, swapped cameras, too few views, a diverged solve.
    """
    lens = lens_model(distortion)
    obs = _observations(names, left, right, obj)
    board_m = float(np.ptp(obj[:, 0]) if len(obj) else 0.0)
    init, keep, mism = _checked_init(obs, size, lens, square_m=square_m, board_m=board_m)
    if len(keep) < _MIN_VIEWS:
        raise CalibrationError(f"only {len(keep)} consistent pairs, at least {_MIN_VIEWS} needed",
                               hint="record more views with the board visible in both cameras")
    sol = _fixed(obs, keep, obj, size, lens, max_error_px) if fix_intrinsics else \
        _joint(obs, keep, init, lens, max_error_px)
    return replace(sol, mismatched=tuple(mism))
