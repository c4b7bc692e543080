"""Calibration accuracy and sigma honesty on independent rigs, with plain OpenCV as the anchor, in one run.

Rigs: tests/calib/independent_rig.py (numpy-only plumb_bob projection, tangential terms up to 5e-4, small
k3, 20 views, 640x480, corner noise 0.07 px). Each rig's corners go straight into s2r's solver
(``calibrate_stereo_detections``: no image detection, so only the solve is measured) for every
``--distortion`` choice, and into plain OpenCV: ``calibrateCamera`` per camera then ``stereoCalibrate``
(intrinsics fixed, as OpenCV's stereo sample and ROS do; and jointly refined with USE_INTRINSIC_GUESS).

Per model: worst and median focal error (% of f, fx and fy of both cameras), worst and median principal
point error (px, |cx| and |cy| of both cameras), worst and median baseline error (% of |T|), and the share
of parameters (fx fy cx cy of both cameras, baseline) whose error lies within 1 and 3 reported sigma.

Usage: .venv/bin/python bench/bench_calib_accuracy.py [--rigs 12] [--seed 1000] [--noise 0.07] [--k3 0.02]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.calib.detect import Detection
from s2r.calib.solve.pipelines.stereo import calibrate_stereo_detections
from s2r.calib.solve.solvers.cvsolve import DISTORTION_CHOICES
from tests.calib.independent_rig import PATTERN, SIZE, SQUARE_M, Rig, make_rig

Row = dict[str, Any]


def _pairs(rig: Rig) -> list[tuple[str, Detection, Detection]]:
    out = []
    for i, (pl, pr) in enumerate(zip(rig.left, rig.right, strict=True)):
        dl = Detection(f"left/{i:02d}", "", "ok", size=SIZE, corners=pl.astype(np.float32))
        dr = Detection(f"right/{i:02d}", "", "ok", size=SIZE, corners=pr.astype(np.float32))
        out.append((f"{i:02d}", dl, dr))
    return out


def _errors(rig: Rig, cams: list[tuple[float, float, float, float]], baseline: float,
            stds: list[tuple[float, float, float, float]] | None, baseline_std: float | None) -> Row:
    truth = [(rig.left_lens.fx, rig.left_lens.fy, rig.left_lens.cx, rig.left_lens.cy),
             (rig.right_lens.fx, rig.right_lens.fy, rig.right_lens.cx, rig.right_lens.cy)]
    f_err = [100 * abs(c[k] - t[k]) / t[k] for c, t in zip(cams, truth, strict=True) for k in (0, 1)]
    c_err = [abs(c[k] - t[k]) for c, t in zip(cams, truth, strict=True) for k in (2, 3)]
    b_err = 100 * abs(baseline - rig.baseline_m) / rig.baseline_m
    z: list[float] = []
    if stds is not None and baseline_std is not None:
        for c, t, s in zip(cams, truth, stds, strict=True):
            z += [abs(c[k] - t[k]) / s[k] if s[k] and s[k] > 0 else np.inf for k in range(4)]
        z.append(abs(baseline - rig.baseline_m) / baseline_std if baseline_std > 0 else np.inf)
    return {"f": f_err, "c": c_err, "b": [b_err], "z": z}


def run_s2r(rig: Rig, distortion: str, **kw: Any) -> Row:
    res = calibrate_stereo_detections(_pairs(rig), pattern=PATTERN, square_m=SQUARE_M, name="bench",
                                      distortion=distortion, max_error_px=None, sources=[], compare=False, **kw)
    p = res.profile
    cams = [(c.fx_px, c.fy_px, c.cx_px, c.cy_px) for c in (p.left, p.right)]
    stds = [(c.std.fx_px, c.std.fy_px, c.std.cx_px, c.std.cy_px) for c in (p.left, p.right)  # type: ignore[union-attr]
            ] if p.left.std is not None and p.right.std is not None else None
    return _errors(rig, cams, p.baseline_m, stds, p.extrinsics.baseline_std_m)  # type: ignore[arg-type]


def run_opencv(rig: Rig, flags: int, joint: bool) -> Row:
    obj = [rig.board.astype(np.float32)] * len(rig.left)
    il = [p.astype(np.float32).reshape(-1, 1, 2) for p in rig.left]
    ir = [p.astype(np.float32).reshape(-1, 1, 2) for p in rig.right]
    _, K1, D1, _, _ = cv2.calibrateCamera(obj, il, SIZE, None, None, flags=flags)
    _, K2, D2, _, _ = cv2.calibrateCamera(obj, ir, SIZE, None, None, flags=flags)
    sflags = flags | (cv2.CALIB_USE_INTRINSIC_GUESS if joint else cv2.CALIB_FIX_INTRINSIC)
    out = cv2.stereoCalibrate(obj, il, ir, K1, D1, K2, D2, SIZE, flags=sflags)
    K1, K2, T = out[1], out[3], out[6]
    cams = [(K[0, 0], K[1, 1], K[0, 2], K[1, 2]) for K in (K1, K2)]
    return _errors(rig, cams, float(np.linalg.norm(T)), None, None)


def summarise(label: str, rows: list[Row], seconds: float) -> str:
    f = np.concatenate([r["f"] for r in rows])
    c = np.concatenate([r["c"] for r in rows])
    b = np.concatenate([r["b"] for r in rows])
    z = np.concatenate([r["z"] for r in rows]) if rows and rows[0]["z"] else np.array([])
    cov = f"{100 * np.mean(z <= 1):5.1f} % {100 * np.mean(z <= 3):5.1f} %" if z.size else "    -       -  "
    return (f"{label:<28} {f.max():7.3f} {np.median(f):7.3f} | {c.max():6.2f} {np.median(c):6.2f} | "
            f"{b.max():6.3f} {np.median(b):6.3f} | {cov} | {seconds / len(rows):5.2f}")


def main() -> None:
    logging.disable(logging.WARNING)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rigs", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--noise", type=float, default=0.07)
    ap.add_argument("--k3", type=float, default=0.02, help="largest |k3| of the random lenses")
    ap.add_argument("--models", default=",".join(DISTORTION_CHOICES))
    args = ap.parse_args()
    rigs = [make_rig(args.seed + i, noise_px=args.noise, k3_max=args.k3) for i in range(args.rigs)]
    print(f"{args.rigs} independent rigs, 20 views 640x480, noise {args.noise} px, |p1|,|p2| <= 5e-4, "
          f"|k3| <= {args.k3}")
    print(f"{'model':<28} {'focal err %':>15} | {'pp err px':>13} | {'baseline %':>13} | "
          f"{'<=1sig <=3sig':>15} | s/rig")
    print(f"{'':<28} {'worst':>7} {'median':>7} | {'worst':>6} {'median':>6} | {'worst':>6} {'median':>6} |")
    anchors = {"OpenCV plumb_bob fixed-K": (0, False), "OpenCV plumb_bob joint": (0, True),
               "OpenCV k1k2p1p2 fixed-K": (cv2.CALIB_FIX_K3, False),
               "OpenCV k1k2p1p2 joint": (cv2.CALIB_FIX_K3, True)}
    for label, (flags, joint) in anchors.items():
        t0 = time.perf_counter()
        rows = [run_opencv(r, flags, joint) for r in rigs]
        print(summarise(label, rows, time.perf_counter() - t0))
    for model in args.models.split(","):
        t0 = time.perf_counter()
        rows = [run_s2r(r, model) for r in rigs]
        print(summarise(f"s2r {model}", rows, time.perf_counter() - t0))


if __name__ == "__main__":
    main()
