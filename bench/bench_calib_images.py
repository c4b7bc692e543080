"""Calibration accuracy on independent *rendered* rigs (corner detection included), plain OpenCV as the anchor.

Rigs: tests/calib/image_rig.py (chessboard images ray-cast by tests/raycast.py through random plumb_bob
lenses with tangential terms up to 5e-4 and |k3| <= 0.02, 20 views, mild blur and sensor noise). Each rig is
calibrated by s2r exactly as ``s2r calibrate`` does with default flags (``calibrate_stereo``: detection,
joint solve, checks; the held-out model comparison is off because it does not change the numbers) and by a
plain OpenCV script on the same images: findChessboardCorners (ADAPTIVE_THRESH | NORMALIZE_IMAGE) +
cornerSubPix (half-window 11 px as OpenCV's stereo sample, "w11", and a small 5 px one, "w5", that does not
reach neighbouring corners on these boards' 20-45 px squares) + calibrateCamera per camera + stereoCalibrate
(intrinsics fixed, as OpenCV's stereo sample and ROS do; and jointly refined with USE_INTRINSIC_GUESS).

Per row: worst and median focal error (% of f, fx and fy of both cameras), principal point error (px, cx and
cy of both cameras), baseline error (% of |T|), and for s2r the share of parameters (fx fy cx cy of both
cameras, baseline) within 1 and 3 reported sigma. Renders are cached under ``--cache`` (about 20 s a rig).

Usage: .venv/bin/python bench/bench_calib_images.py [--rigs 12] [--seed 500] [--hd 2] [--models k1k2p1p2,...]
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

from s2r.calib.solve.pipelines.stereo import calibrate_stereo
from s2r.calib.solve.solvers.cvsolve import DISTORTION_CHOICES
from tests.calib.image_rig import PATTERN, SQUARE_M, ImageRig, errors, make_image_rig, render_rig, sigma_ratios

Row = dict[str, Any]
_FIND = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
_CRIT = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)


def rig_folder(cache: Path, seed: int, size: tuple[int, int], views: int) -> tuple[ImageRig, Path]:
    """The rendered rig (rendered now unless cached) and its folder."""
    folder = cache / f"{size[0]}x{size[1]}-s{seed}-v{views}"
    if not (folder / "done").exists():
        render_rig(seed, folder, views=views, size=size)
        (folder / "done").write_text("ok")
    return make_image_rig(seed, size)[0], folder


def run_s2r(truth: ImageRig, folder: Path, distortion: str) -> Row:
    left, right = sorted((folder / "left").glob("*.png")), sorted((folder / "right").glob("*.png"))
    res = calibrate_stereo(left, right, pattern=PATTERN, square_m=SQUARE_M, distortion=distortion, jobs=1,
                           cache_dir=folder / "corners", compare=False)
    p = res.profile
    cams = [(c.fx_px, c.fy_px, c.cx_px, c.cy_px) for c in (p.left, p.right)]
    stds = [(None,) * 4 if c.std is None else (c.std.fx_px, c.std.fy_px, c.std.cx_px, c.std.cy_px)
            for c in (p.left, p.right)]
    row: Row = errors(truth, cams, p.baseline_m)
    row["z"] = sigma_ratios(truth, cams, stds, p.baseline_m, p.extrinsics.baseline_std_m)
    row["views"] = res.profile.provenance.calibration.views_used if res.profile.provenance.calibration else 0
    return row


def opencv_corners(folder: Path, win: int = 11) -> tuple[list[np.ndarray], list[np.ndarray], tuple[int, int]]:
    """The plain loop's refined corners (cornerSubPix half-window ``win`` px) of the pairs found in both images."""
    cl, cr = [], []
    size = (0, 0)
    for pl in sorted((folder / "left").glob("*.png")):
        found = []
        for p in (pl, folder / "right" / pl.name):
            g = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
            size = (g.shape[1], g.shape[0])
            ok, c = cv2.findChessboardCorners(g, PATTERN, flags=_FIND)
            found.append(cv2.cornerSubPix(g, c, (win, win), (-1, -1), _CRIT) if ok else None)
        if found[0] is not None and found[1] is not None:
            cl.append(found[0])
            cr.append(found[1])
    return cl, cr, size


def run_opencv(truth: ImageRig, corners: tuple[list[np.ndarray], list[np.ndarray], tuple[int, int]], flags: int,
               joint: bool) -> Row:
    il, ir, size = corners
    n = PATTERN[0] * PATTERN[1]
    jj, ii = np.divmod(np.arange(n), PATTERN[0])
    obj = [np.column_stack([ii * SQUARE_M, jj * SQUARE_M, np.zeros(n)]).astype(np.float32)] * len(il)
    _, K1, D1, _, _ = cv2.calibrateCamera(obj, il, size, None, None, flags=flags)
    _, K2, D2, _, _ = cv2.calibrateCamera(obj, ir, size, None, None, flags=flags)
    sflags = flags | (cv2.CALIB_USE_INTRINSIC_GUESS if joint else cv2.CALIB_FIX_INTRINSIC)
    out = cv2.stereoCalibrate(obj, il, ir, K1, D1, K2, D2, size, flags=sflags)
    K1, K2, T = out[1], out[3], out[6]
    row: Row = errors(truth, [(K[0, 0], K[1, 1], K[0, 2], K[1, 2]) for K in (K1, K2)], float(np.linalg.norm(T)))
    row["z"] = []
    row["views"] = len(il)
    return row


def summarise(label: str, rows: list[Row], seconds: float) -> str:
    f = np.concatenate([r["f"] for r in rows])
    c = np.concatenate([r["c"] for r in rows])
    b = np.concatenate([r["b"] for r in rows])
    z = np.concatenate([r["z"] for r in rows]) if rows[0]["z"] else np.array([])
    cov = f"{100 * np.mean(z <= 1):5.1f} % {100 * np.mean(z <= 3):5.1f} %" if z.size else "    -       -  "
    views = sum(r["views"] for r in rows)
    return (f"{label:<28} {f.max():7.3f} {np.median(f):7.3f} | {c.max():6.2f} {np.median(c):6.2f} | "
            f"{b.max():6.3f} {np.median(b):6.3f} | {cov} | {views:5d} | {seconds / len(rows):5.2f}")


def main() -> None:
    logging.disable(logging.WARNING)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rigs", type=int, default=12, help="640x480 rigs")
    ap.add_argument("--hd", type=int, default=2, help="extra 1280x720 rigs")
    ap.add_argument("--seed", type=int, default=500)
    ap.add_argument("--views", type=int, default=20)
    ap.add_argument("--models", default=",".join(DISTORTION_CHOICES))
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s2r-image-rigs"))
    args = ap.parse_args()
    specs = [(args.seed + i, (640, 480)) for i in range(args.rigs)]
    specs += [(args.seed + 100 + i, (1280, 720)) for i in range(args.hd)]
    rigs = [rig_folder(args.cache, s, size, args.views) for s, size in specs]
    print(f"{len(rigs)} rendered rigs ({args.rigs} at 640x480, {args.hd} at 1280x720), {args.views} views, "
          "|p1|,|p2| <= 5e-4, |k3| <= 0.02, blur 0.3-0.7 px, noise 1-2 grey levels")
    print(f"{'calibration':<28} {'focal err %':>15} | {'pp err px':>13} | {'baseline %':>13} | "
          f"{'<=1sig <=3sig':>15} | views | s/rig")
    print(f"{'':<28} {'worst':>7} {'median':>7} | {'worst':>6} {'median':>6} | {'worst':>6} {'median':>6} |")
    for win in (11, 5):
        t0 = time.perf_counter()
        corners = [opencv_corners(folder, win) for _, folder in rigs]
        t_det = (time.perf_counter() - t0) / len(rigs)
        anchors = {"plumb_bob fixed-K": (0, False), "plumb_bob joint": (0, True),
                   "k1k2p1p2 fixed-K": (cv2.CALIB_FIX_K3, False), "k1k2p1p2 joint": (cv2.CALIB_FIX_K3, True)}
        for label, (flags, joint) in anchors.items():
            t0 = time.perf_counter()
            rows = [run_opencv(truth, c, flags, joint) for (truth, _), c in zip(rigs, corners, strict=True)]
            print(summarise(f"OpenCV w{win} {label}", rows, time.perf_counter() - t0 + len(rows) * t_det))
    for model in args.models.split(","):
        t0 = time.perf_counter()
        rows = [run_s2r(truth, folder, model) for truth, folder in rigs]
        print(summarise(f"s2r {model}", rows, time.perf_counter() - t0))


if __name__ == "__main__":
    main()
