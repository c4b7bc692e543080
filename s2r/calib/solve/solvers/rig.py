"""Initial rig from each camera alone, and the checks that catch the classic stereo mistakes.

- :func:`initial_rig`: OpenCV ``calibrateCameraExtended`` per camera (the lens model's flags), then the
  pair's rotation and translation as the robust consensus of every view's relative pose (left board
  pose to right board pose), which mismatched pairs cannot drag.
- :func:`pair_consistency`: each view's deviation from that consensus (translation in metres, rotation
  in degrees); views far off are pairs whose images do not belong together.
- :func:`check_rig`: left and right swapped (right camera found to the left), ``--square`` in the wrong
  unit (implausible board distances or baseline), identical left and right images.

Frames: board poses are the board frame in each camera's optical frame; ``X_right = R X_left + T`` (m).
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.solve.solvers.cvsolve import INIT_CRITERIA, MonoSolution, solve_mono_observations
from s2r.calib.solve.solvers.joint import JointInit
from s2r.calib.solve.solvers.observations import BoardObservation, StereoObservation
from s2r.errors import CalibrationError
from s2r.lens.models import LensModel

__all__ = ["PairScore", "RigInit", "SwappedCamerasError", "check_rig", "initial_rig", "pair_consistency"]

FloatArray = NDArray[np.float64]


class SwappedCamerasError(CalibrationError):
    """The right camera came out to the left of the left one: the inputs look swapped (the CLI words the fix,
    which depends on whether ``--swap`` was already given)."""


#: Board distances (m) and baselines (m) beyond which ``--square`` is surely in the wrong unit.
MAX_BOARD_DISTANCE_M = 30.0
MAX_BASELINE_M = 3.0
MIN_BOARD_DISTANCE_M = 0.02
#: Most views each camera's initialisation solves with (evenly spaced); the other views' board poses are then
#: fitted alone (solvePnP) with those intrinsics. The joint solve refines everything on all views: from 12 or
#: 20 views it reached the same answer (fx and baseline within 1e-7 relative) on four real sets of 22-40 pairs,
#: and 12 halves this step (~25 ms per camera at 20 views).
MAX_INIT_VIEWS = 12


@dataclass(frozen=True)
class PairScore:
    """One view's relative pose against the consensus: translation (m) and rotation (deg) deviations."""

    name: str
    dt_m: float
    drot_deg: float
    identical: bool


@dataclass(frozen=True)
class RigInit:
    """Mono solutions (all views), the consensus R, T, and the joint solve's starting point."""

    left: MonoSolution
    right: MonoSolution
    R: FloatArray
    T: FloatArray
    scores: tuple[PairScore, ...]

    def joint_init(self) -> JointInit:
        return JointInit(self.left.K, self.left.D, self.right.K, self.right.D, self.R, self.T,
                         self.left.rvecs, self.left.tvecs)


def _relative(rl: FloatArray, tl: FloatArray, rr: FloatArray, tr: FloatArray) -> tuple[FloatArray, FloatArray]:
    Rl, Rr = cv2.Rodrigues(rl)[0], cv2.Rodrigues(rr)[0]
    R = Rr @ Rl.T
    return np.asarray(R, np.float64), np.asarray(tr - R @ tl, np.float64)


def _mean_rotation(rotations: Sequence[FloatArray]) -> FloatArray:
    """Chordal L2 mean of rotations (projection of the mean matrix onto SO(3))."""
    U, _, Vt = np.linalg.svd(np.mean(rotations, axis=0))
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = U @ np.diag([1.0, 1.0, -1.0]) @ Vt
    return np.asarray(R, np.float64)


def _angle_deg(R: FloatArray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def initial_rig(views: Sequence[StereoObservation], size: tuple[int, int], lens: LensModel) -> RigInit:
    """Each camera alone (OpenCV, the two in parallel threads, stopped at :data:`INIT_CRITERIA`), then the
    consensus relative pose. Every view must show both cameras."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        solves = [pool.submit(_mono_init, [o for v in views if (o := getattr(v, side)) is not None], size, lens)
                  for side in ("left", "right")]
        left, right = solves[0].result(), solves[1].result()
    rels = [_relative(rl, tl, rr, tr) for rl, tl, rr, tr in
            zip(left.rvecs, left.tvecs, right.rvecs, right.tvecs, strict=True)]
    Ts = np.array([t for _, t in rels])
    T = np.median(Ts, axis=0)
    near = np.linalg.norm(Ts - T, axis=1) <= np.median(np.linalg.norm(Ts - T, axis=1)) * 3 + 1e-9
    R = _mean_rotation([r for (r, _), ok in zip(rels, near, strict=True) if ok])
    T = np.median(Ts[near], axis=0)
    scores = []
    for v, (Rk, Tk) in zip(views, rels, strict=True):
        same = (v.left is not None and v.right is not None and v.left.img.shape == v.right.img.shape
                and float(np.max(np.abs(v.left.img - v.right.img))) < 1e-3)
        scores.append(PairScore(v.name, float(np.linalg.norm(Tk - T)), _angle_deg(Rk @ R.T), same))
    return RigInit(left, right, R, T, tuple(scores))


def _mono_init(views: Sequence[BoardObservation], size: tuple[int, int], lens: LensModel) -> MonoSolution:
    """One camera's starting point: OpenCV's calibration on at most :data:`MAX_INIT_VIEWS` evenly spaced views
    (stopped at :data:`INIT_CRITERIA`), then every view's board pose fitted alone with those intrinsics."""
    if len(views) <= MAX_INIT_VIEWS:
        return solve_mono_observations(views, size, lens, criteria=INIT_CRITERIA)
    idx = np.unique(np.linspace(0, len(views) - 1, MAX_INIT_VIEWS).round().astype(int))
    sub = solve_mono_observations([views[i] for i in idx], size, lens, criteria=INIT_CRITERIA)
    rvecs, tvecs, errs = [], [], []
    for k, v in enumerate(views):
        obj, img = v.obj.astype(np.float64), v.img.astype(np.float64).reshape(-1, 1, 2)
        ok, rv, tv = cv2.solvePnP(obj, img, sub.K, sub.D)
        if not ok:
            raise CalibrationError(f"the board pose of view {k + 1} could not be fitted", field="input",
                                   hint="check the images (is the whole board visible?)")
        rv, tv = cv2.solvePnPRefineLM(obj, img, sub.K, sub.D, rv, tv)
        proj = cv2.projectPoints(obj, rv, tv, sub.K, sub.D)[0].reshape(-1, 2)
        errs.append(float(np.sqrt(np.mean(np.sum((proj - img.reshape(-1, 2)) ** 2, axis=1)))))
        rvecs.append(np.asarray(rv, np.float64).reshape(3))
        tvecs.append(np.asarray(tv, np.float64).reshape(3))
    return replace(sub, rvecs=tuple(rvecs), tvecs=tuple(tvecs), per_view_px=np.array(errs))


def pair_consistency(scores: Sequence[PairScore], baseline_m: float) -> list[int]:
    """Indices of views whose relative pose disagrees with the consensus: identical images, or translation
    off by more than max(25 % of the baseline, 6 robust sigmas), or rotation by more than max(3 deg, 6 sigmas)."""
    dt = np.array([s.dt_m for s in scores])
    dr = np.array([s.drot_deg for s in scores])
    t_thr = max(0.25 * baseline_m, np.median(dt) + 6 * 1.4826 * np.median(np.abs(dt - np.median(dt))))
    r_thr = max(3.0, np.median(dr) + 6 * 1.4826 * np.median(np.abs(dr - np.median(dr))))
    return [i for i, s in enumerate(scores) if s.identical or s.dt_m > t_thr or s.drot_deg > r_thr]


def check_rig(init: RigInit, *, square_m: float, board_size_m: float) -> None:
    """Refuse (CalibrationError, one line) rigs that are surely a user mistake.

    ``board_size_m`` is the board's largest extent (metres, at the given ``square_m``).
    """
    if all(s.identical for s in init.scores):
        raise CalibrationError("the left and right images are identical", field="input",
                               hint="pass the two cameras' images (left/ and right/ hold copies of one camera)")
    dist = float(np.median([np.linalg.norm(t) for t in init.left.tvecs]))
    baseline = float(np.linalg.norm(init.T))
    if dist > MAX_BOARD_DISTANCE_M or baseline > MAX_BASELINE_M:
        guess = f"; for {square_m:g} mm give --square {square_m / 1000:g}" if square_m >= 1 else ""
        raise CalibrationError(
            f"implausible geometry at --square {square_m:g}: board {dist:.0f} m away, baseline {baseline:.1f} m",
            field="--square", hint=f"--square is the square edge in metres{guess}")
    if dist < MIN_BOARD_DISTANCE_M:
        raise CalibrationError(
            f"implausible geometry at --square {square_m:g}: board {dist * 1000:.1f} mm away "
            f"(a {board_size_m * 1000:.1f} mm board)", field="--square",
            hint="--square is the square edge in metres, e.g. 0.025 for 25 mm squares")
    centre_right = -init.R.T @ init.T
    if centre_right[0] < 0 and abs(centre_right[0]) > abs(centre_right[1]):
        raise SwappedCamerasError(
            f"the right camera is {abs(centre_right[0]) * 1000:.0f} mm to the LEFT of the left camera: "
            "left and right look swapped", field="input",
            hint="exchange the left and right images, or rerun with --swap to let s2r exchange them")
