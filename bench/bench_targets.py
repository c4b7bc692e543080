"""Targets and lenses: s2r calibrate beside plain OpenCV on independent ray-cast rigs, in one run.

Rigs (tests/raycast.py, which shares no code with s2r: its own lens maths, boards drawn by cv2.aruco and
Kalibr's layout): 20 stereo views each, about 40 % cut by the image edge:
ChArUco + plumb_bob, AprilGrid + plumb_bob (640x480, 8 cm baseline), chessboard + fisheye, ChArUco + fisheye
(T265-like 848x800 equidistant, 6.4 cm baseline).

s2r: ``calibrate_stereo_target`` with the defaults of ``s2r calibrate --target T.yaml [--lens fisheye]``.
Plain OpenCV on the same images: cv2.aruco (CharucoDetector; ArucoDetector tag36h11 with markerBorderBits 2
and CORNER_REFINE_SUBPIX, Kalibr's corner order) or findChessboardCorners + cornerSubPix, then
calibrateCamera (CALIB_FIX_K3, the same k1 k2 p1 p2 as s2r's default) per camera and stereoCalibrate with
CALIB_FIX_INTRINSIC on the corners both saw; fisheye: cv2.fisheye.calibrate per camera and
cv2.fisheye.stereoCalibrate, which needs the same corners in every view (whole boards only).

Seeds: seed k renders new poses and picks lens/target variant k mod 3 (0: the rigs above; 1: milder, narrower
lenses and other board sizes; 2: strong barrel / ~150-180 deg fisheyes and smaller tags).

Usage: .venv/bin/python bench/bench_targets.py [--rigs charuco_pinhole,...] [--views 20] [--seeds 0,1,2] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target
from s2r.targets import target_from_mapping
from tests import raycast as rc

RIGS = {
    "charuco_pinhole": lambda: rc.pinhole_rig(rc.charuco_target(), "charuco_pinhole"),
    "aprilgrid_pinhole": lambda: rc.pinhole_rig(rc.aprilgrid_target(), "aprilgrid_pinhole"),
    "chess_fisheye": lambda: rc.fisheye_rig(rc.chessboard_target(), "chess_fisheye"),
    "charuco_fisheye": lambda: rc.fisheye_rig(rc.charuco_target(), "charuco_fisheye"),
}
#: Per seed index: (lens focal scale, distortion, target arguments) - variant 0 is the rig above.
_PINHOLE_LENSES = (
    (1.0, None),
    (1.15, (-0.08, 0.012, -0.0003, 0.0005, 0.0)),  # mild barrel, narrower
    (0.85, (-0.34, 0.12, 0.0006, -0.0004, 0.0)),  # strong barrel, wider (~74 deg across)
)
_FISHEYE_LENSES = (
    (1.0, None),  # T265-like, ~160 deg across the image circle
    (0.87, (0.012, -0.006, 0.002, -0.0004)),  # ~180 deg: the whole image circle inside the frame height
    (1.12, (-0.02, 0.01, -0.004, 0.0006)),  # ~150 deg across the width
)
_TARGETS = {
    "charuco": ({}, {"squares": (9, 7), "square_m": 0.035, "marker_m": 0.026, "dictionary": "DICT_4X4_50"},
                {"squares": (12, 9), "square_m": 0.025, "marker_m": 0.017, "dictionary": "DICT_6X6_250"}),
    "aprilgrid": ({}, {"tags": (7, 5), "tag_m": 0.035, "spacing": 0.25}, {"tags": (6, 6), "tag_m": 0.028}),
    "chess": ({}, {"inner": (8, 6), "square_m": 0.035}, {"inner": (10, 7), "square_m": 0.025}),
}


def variant(name: str, k: int) -> rc.Rig:
    """Rig ``name`` with lens strength and target size number ``k`` (0 = the base rig)."""
    kind, lens_kind = name.split("_")
    maker = {"charuco": rc.charuco_target, "aprilgrid": rc.aprilgrid_target, "chess": rc.chessboard_target}[kind]
    target = maker(**_TARGETS[kind][k % 3])  # type: ignore[operator]
    fisheye = lens_kind == "fisheye"
    rig = (rc.fisheye_rig if fisheye else rc.pinhole_rig)(target, f"{name}_v{k}")
    scale, dist = (_FISHEYE_LENSES if fisheye else _PINHOLE_LENSES)[k % 3]

    def lens(base: rc.Lens, sign: float) -> rc.Lens:
        d = base.dist if dist is None else tuple(v * (1 + 0.05 * sign) for v in dist)
        return replace(base, fx=base.fx * scale, fy=base.fy * scale, dist=d)

    return replace(rig, left=lens(rig.left, 1.0), right=lens(rig.right, -1.0))
_SUBPIX = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 0.001)


def _detect_plain(gray: np.ndarray, target, rig: rc.Rig) -> tuple[np.ndarray, np.ndarray] | None:
    kind = rig.target.kind
    if kind == "charuco":
        d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, target.dictionary))
        board = cv2.aruco.CharucoBoard((target.squaresX, target.squaresY), target.squareLength,
                                       target.markerLength, d)
        cc, ci, _, _ = cv2.aruco.CharucoDetector(board).detectBoard(gray)
        return None if ci is None or len(ci) < 6 else (ci.reshape(-1), cc.reshape(-1, 2))
    if kind == "aprilgrid":
        params = cv2.aruco.DetectorParameters()
        params.markerBorderBits = 2
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)
        quads, tids, _ = det.detectMarkers(gray)
        if tids is None:
            return None
        ids = target.tag_corner_ids(tids.reshape(-1))[:, [1, 0, 3, 2]].reshape(-1)
        return ids, np.asarray(quads, np.float32).reshape(-1, 2)
    ok, corners = cv2.findChessboardCorners(gray, target.pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH
                                            | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not ok:
        return None
    corners = cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), _SUBPIX)
    return np.arange(len(corners)), corners.reshape(-1, 2)


def _orient(ids: np.ndarray, pts: np.ndarray, other: np.ndarray | None) -> np.ndarray:
    """Chessboards come back in either order: put the right grid in the left's order (first/last corner)."""
    if other is None:
        return pts
    return pts if np.linalg.norm(pts[0] - other[0]) < np.linalg.norm(pts[-1] - other[0]) else pts[::-1].copy()


def plain_opencv(folder: Path, rig: rc.Rig, target) -> dict[str, float | str]:
    """The anchor: detection and calibration with OpenCV's own calls only."""
    t0 = time.perf_counter()
    fisheye = rig.left.model == "equidistant"
    obs = {}
    for side in ("left", "right"):
        for f in sorted((folder / side).glob("*.png")):
            obs[(side, f.stem)] = _detect_plain(cv2.imread(str(f), cv2.IMREAD_GRAYSCALE), target, rig)
    pts_all = target.object_points()
    K, D = {}, {}
    size = (rig.left.width, rig.left.height)
    for side in ("left", "right"):
        views = [v for (s, _), v in sorted(obs.items()) if s == side and v is not None]
        objs = [pts_all[i].astype(np.float32) for i, _ in views]
        imgs = [p.astype(np.float32) for _, p in views]
        if fisheye:
            _, K[side], D[side], _, _ = cv2.fisheye.calibrate(
                [o.reshape(1, -1, 3).astype(np.float64) for o in objs], [p.reshape(1, -1, 2).astype(np.float64)
                                                                          for p in imgs],
                size, np.eye(3), np.zeros(4), flags=cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW)
        else:
            _, K[side], D[side], _, _ = cv2.calibrateCamera(objs, [p.reshape(-1, 1, 2) for p in imgs], size, None,
                                                            None, flags=cv2.CALIB_FIX_K3)
    objs, pl, pr = [], [], []
    full = target.corner_count
    for (side, stem), v in sorted(obs.items()):
        w = obs.get(("right", stem))
        if side != "left" or v is None or w is None:
            continue
        common, il, ir = np.intersect1d(v[0], w[0], return_indices=True)
        if len(common) < 6 or (fisheye and len(common) != full):
            continue
        right = _orient(w[0], w[1], v[1]) if rig.target.kind == "checkerboard" else w[1]
        objs.append(pts_all[common].astype(np.float32))
        pl.append(v[1][il].astype(np.float32))
        pr.append(right[ir].astype(np.float32))
    try:
        if fisheye:
            out = cv2.fisheye.stereoCalibrate([o.reshape(1, -1, 3).astype(np.float64) for o in objs],
                                              [p.reshape(1, -1, 2).astype(np.float64) for p in pl],
                                              [p.reshape(1, -1, 2).astype(np.float64) for p in pr],
                                              K["left"], D["left"], K["right"], D["right"], size,
                                              flags=cv2.CALIB_FIX_INTRINSIC)
            T = out[6]
        else:
            out = cv2.stereoCalibrate(objs, [p.reshape(-1, 1, 2) for p in pl], [p.reshape(-1, 1, 2) for p in pr],
                                      K["left"], D["left"], K["right"], D["right"], size,
                                      flags=cv2.CALIB_FIX_INTRINSIC)
            T = out[6]
        baseline = float(np.linalg.norm(T))
    except cv2.error as exc:
        baseline = float("nan")
        print(f"    plain OpenCV stereo failed: {str(exc).strip().splitlines()[-1][:90]}")
    return _errors(rig, K["left"], K["right"], baseline, time.perf_counter() - t0, f"{len(objs)} pairs")


def _errors(rig: rc.Rig, K1: np.ndarray, K2: np.ndarray, baseline: float, seconds: float, note: str
            ) -> dict[str, float | str]:
    f = max(abs(K[i, i] / getattr(lens, a) - 1) for K, lens in ((K1, rig.left), (K2, rig.right))
            for i, a in ((0, "fx"), (1, "fy")))
    c = max(abs(K[i, 2] - getattr(lens, a)) for K, lens in ((K1, rig.left), (K2, rig.right))
            for i, a in ((0, "cx"), (1, "cy")))
    b = abs(baseline / float(np.linalg.norm(rig.T)) - 1)
    return {"focal_pct": 100 * f, "pp_px": c, "baseline_pct": 100 * b, "seconds": seconds, "note": note}


def run_s2r(folder: Path, rig: rc.Rig, target) -> dict[str, float | str]:
    t0 = time.perf_counter()
    lens = "fisheye" if rig.left.model == "equidistant" else "pinhole"
    res = calibrate_stereo_target(sorted((folder / "left").glob("*.png")), sorted((folder / "right").glob("*.png")),
                                  target=target, lens=lens, jobs=2)
    p = res.profile
    out = _errors(rig, p.left.K, p.right.K, p.baseline_m, time.perf_counter() - t0,
                  f"{len(res.used_names)} pairs, model {p.left.distortion.model}")
    out["baseline_std_mm"] = 1000 * (p.extrinsics.baseline_std_m or float("nan"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", default=",".join(RIGS))
    ap.add_argument("--views", type=int, default=20)
    ap.add_argument("--seeds", default="0,1,2", help="seeds; seed k also picks lens/target variant k mod 3")
    ap.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "s2r_bench_targets")
    args = ap.parse_args()
    bars = "bars: fx/fy within 0.2 %, cx/cy within 1.0 px, baseline within 0.3 %"
    print(f"{'rig':<18} {'seed':>4} {'method':<13} {'focal err %':>11} {'pp err px':>9} {'baseline %':>10} "
          f"{'time s':>7}  note")
    for name in args.rigs.split(","):
        for seed in (int(v) for v in args.seeds.split(",")):
            rig = variant(name, seed)
            folder = args.out / f"{name}_v{args.views}_s{seed}"
            if not (folder / "right" / f"{args.views - 1:02d}.png").exists():
                rc.write_rig(rig, folder, views=args.views, seed=seed)
            target = target_from_mapping(yaml.safe_load((folder / "target.yaml").read_text()))
            for method, fn in (("s2r", run_s2r), ("plain OpenCV", plain_opencv)):
                try:
                    r = fn(folder, rig, target)
                except Exception as exc:
                    print(f"{name:<18} {seed:>4} {method:<13} failed: {str(exc).strip().splitlines()[-1][:80]}")
                    continue
                print(f"{name:<18} {seed:>4} {method:<13} {r['focal_pct']:>11.3f} {r['pp_px']:>9.2f} "
                      f"{r['baseline_pct']:>10.3f} {r['seconds']:>7.1f}  {r['note']}", flush=True)
    print(bars + " (worst of both cameras)")


if __name__ == "__main__":
    main()
