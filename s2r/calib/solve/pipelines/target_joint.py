"""The joint solve of a target calibration: both cameras, extrinsics and board poses on corners matched by id.

Started from the per-camera fits of :mod:`s2r.calib.solve.pipelines.target_stereo`; the solve itself is issue 11's
joint solver (:mod:`s2r.calib.solve.solvers.joint` through ``solvers.pair._joint``, which has no public name yet), run
with the pinhole lens models or the equidistant :data:`s2r.lens.models.FISHEYE`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.observations import BoardObservation, StereoObservation
from s2r.calib.solve.solvers.pair import PairSolution
from s2r.calib.solve.solvers.pair import _joint as joint_pair_solution
from s2r.calib.solve.solvers.rig import RigInit
from s2r.calib.solve.solvers.targetcal import MonoFit, Observation, PairView
from s2r.lens.models import FISHEYE, LensModel, lens_model

__all__ = ["joint_solve", "lens_model_of"]


def _board(o: Observation) -> BoardObservation:
    return BoardObservation(o.ids.astype(np.int64), o.obj.astype(np.float64), o.img.astype(np.float64))


def lens_model_of(lens: str, distortion: str) -> LensModel:
    """The joint solver's lens model of ``--lens`` / ``--distortion``."""
    return FISHEYE if lens == "fisheye" else lens_model(distortion)


def joint_solve(names: Sequence[str], obs_l: list[Observation | None], obs_r: list[Observation | None],
                 keeps: list[dict[int, int]], fit_l: MonoFit, fit_r: MonoFit, views: Sequence[PairView], *,
                 lens: str, distortion: str, max_error_px: float | None
                 ) -> tuple[list[StereoObservation], PairSolution]:
    """The joint solve (:mod:`s2r.calib.solve.solvers.joint`) of every view either camera kept, started from the mono
    fits: R, T the consensus of the views both saw, each view's board pose from the left fit (or from the right fit
    moved into the left camera)."""
    R, T = _consensus([(fit_l.solution.rvecs[v.idx_l], fit_l.solution.tvecs[v.idx_l], fit_r.solution.rvecs[v.idx_r],
                        fit_r.solution.tvecs[v.idx_r]) for v in views])
    joint_obs, rv, tv = [], [], []
    for k, n in enumerate(names):
        left = _board(obs_l[k]) if k in keeps[0] and obs_l[k] is not None else None  # type: ignore[arg-type]
        right = _board(obs_r[k]) if k in keeps[1] and obs_r[k] is not None else None  # type: ignore[arg-type]
        if left is None and right is None:
            continue
        if left is not None:
            r, t = fit_l.solution.rvecs[keeps[0][k]], fit_l.solution.tvecs[keeps[0][k]]
        else:
            Rr = cv2.Rodrigues(fit_r.solution.rvecs[keeps[1][k]])[0]
            r = np.asarray(cv2.Rodrigues(R.T @ Rr)[0], np.float64).reshape(3)
            t = R.T @ (fit_r.solution.tvecs[keeps[1][k]] - T)
        joint_obs.append(StereoObservation(n, left, right))
        rv.append(r)
        tv.append(t)
    init = RigInit(left=replace(fit_l.solution, rvecs=tuple(rv), tvecs=tuple(tv)), right=fit_r.solution, R=R, T=T,
                   scores=())
    sol = joint_pair_solution(joint_obs, list(range(len(joint_obs))), init, lens_model_of(lens, distortion),
                              max_error_px)
    method = ("s2r calibrate --target: " if lens != "fisheye" else "s2r calibrate --lens fisheye: ") + \
        ("OpenCV fisheye.calibrate" if lens == "fisheye" else "OpenCV calibrateCameraExtended") + \
        " per camera on every view it saw, then one joint solve of both cameras, extrinsics and board poses " \
        "on corners matched by id"
    return joint_obs, replace(sol, method=method)


def _consensus(poses: Sequence[tuple[NDArray[np.float64], ...]]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Right-from-left motion: chordal mean rotation and median translation of the views' relative poses."""
    Rs, Ts = [], []
    for rl, tl, rr, tr in poses:
        Rl, Rr = cv2.Rodrigues(rl)[0], cv2.Rodrigues(rr)[0]
        Rs.append(Rr @ Rl.T)
        Ts.append(tr - Rr @ Rl.T @ tl)
    U, _, Vt = np.linalg.svd(np.mean(Rs, axis=0))
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = U @ np.diag([1.0, 1.0, -1.0]) @ Vt
    return np.asarray(R, np.float64), np.asarray(np.median(Ts, axis=0), np.float64)
