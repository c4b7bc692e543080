"""Benchmark `s2r calibrate --mono` against a plain OpenCV script on real image sets, side by side in one run.

Plain OpenCV (a separate script run as its own process, sharing no code with s2r): for each image
findChessboardCorners (ADAPTIVE_THRESH | NORMALIZE_IMAGE | FAST_CHECK) + cornerSubPix 11x11, then
calibrateCamera with k3 fixed (s2r's default k1k2p1p2). With ``--figures`` it also computes, untimed, its own
4-fold held-out error (view i in fold i mod 4; calibrateCamera on the other views from scratch, each held-out
view's pose by solvePnP + solvePnPRefineLM with those intrinsics, RMS per corner) and the 4-fold jackknife std
of fx, fy, cx, cy (``(K-1)/K * sum``).

s2r: ``s2r calibrate --mono --json --no-cache`` (whole process: start-up, detection, solve, resampling, lens
models, profile). Printed per set: fx fy cx cy of both, s2r's covariance / jackknife / reported std against the
plain jackknife, the held-out errors, and the median whole-process time of ``--repeats`` interleaved runs.

Usage: .venv/bin/python bench/bench_calib_mono.py SET_GLOB [SET_GLOB ...] [--pattern 9x6] [--square 0.025]
       e.g. '/work/shared/data/opencv_stereo_chessboard/left*.jpg'
Timings on a shared machine are disturbed by other load: compare the ratios, measured in one run.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

_PLAIN = r'''
import glob, json, sys
import cv2
import numpy as np
pattern = tuple(int(v) for v in sys.argv[2].split("x")); square = float(sys.argv[3]); figures = sys.argv[4] == "1"
find = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
objp = np.zeros((pattern[0] * pattern[1], 3), np.float32)
objp[:, :2] = np.mgrid[0:pattern[0], 0:pattern[1]].T.reshape(-1, 2) * square
pts, size = [], None
for p in sorted(glob.glob(sys.argv[1])):
    img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
    size = img.shape[::-1]
    ok, c = cv2.findChessboardCorners(img, pattern, flags=find)
    if ok:
        pts.append(cv2.cornerSubPix(img, c, (11, 11), (-1, -1), crit))
flags = cv2.CALIB_FIX_K3
rms, K, D, _, _ = cv2.calibrateCamera([objp] * len(pts), pts, size, None, None, flags=flags)
out = {"views": len(pts), "rms": rms, "K": [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]}
if figures:
    k, theta, sq = 4, [], []
    for f in range(k):
        test = set(range(f, len(pts), k))
        train = [pts[i] for i in range(len(pts)) if i not in test]
        _, Kf, Df, _, _ = cv2.calibrateCamera([objp] * len(train), train, size, None, None, flags=flags)
        theta.append([Kf[0, 0], Kf[1, 1], Kf[0, 2], Kf[1, 2]])
        for i in sorted(test):
            _, rv, tv = cv2.solvePnP(objp, pts[i], Kf, Df)
            rv, tv = cv2.solvePnPRefineLM(objp, pts[i], Kf, Df, rv, tv)
            proj = cv2.projectPoints(objp, rv, tv, Kf, Df)[0].reshape(-1, 2)
            sq.append(np.sum((proj - pts[i].reshape(-1, 2)) ** 2, axis=1))
    theta = np.array(theta)
    out["jackknife"] = np.sqrt((k - 1) / k * np.sum((theta - theta.mean(axis=0)) ** 2, axis=0)).tolist()
    out["heldout"] = float(np.sqrt(np.mean(np.concatenate(sq))))
print(json.dumps(out))
'''


def run_plain(images: str, pattern: str, square: float, figures: bool) -> tuple[float, dict[str, object]]:
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _PLAIN, images, pattern, str(square), "1" if figures else "0"],
                         capture_output=True, text=True, check=True)
    return time.perf_counter() - t0, json.loads(out.stdout)


def run_s2r(images: str, pattern: str, square: float, jobs: int) -> tuple[float, dict[str, object]]:
    s2r = Path(sys.executable).with_name("s2r")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        out = subprocess.run([str(s2r), "calibrate", "--mono", "--left", images, "--pattern", pattern, "--square",
                              str(square), "-o", str(Path(tmp) / "mono.yaml"), "--json", "--no-cache", "--jobs",
                              str(jobs)], capture_output=True, text=True, check=True)
        return time.perf_counter() - t0, json.loads(out.stdout)


def report(images: str, pattern: str, square: float, jobs: int, repeats: int) -> None:
    _, plain = run_plain(images, pattern, square, figures=True)
    times: dict[str, list[float]] = {"plain": [], "s2r": []}
    fig: dict[str, object] = {}
    for _ in range(repeats):
        times["plain"].append(run_plain(images, pattern, square, figures=False)[0])
        t, fig = run_s2r(images, pattern, square, jobs)
        times["s2r"].append(t)
    held = fig["heldout"]
    assert isinstance(held, dict)
    params = held["parameters"]
    quality = fig["quality"]
    assert isinstance(quality, dict)
    print(f"{images}: plain {plain['views']} views, s2r {quality['views_used']} used "
          f"({len(fig['dropped'])} skipped or dropped)")  # type: ignore[arg-type]
    print(f"  {'':4} {'plain':>9} {'s2r':>9} {'s2r cov':>8} {'s2r jk':>8} {'s2r std':>8} {'source':>10} "
          f"{'plain jk':>8}  reported / plain jk")
    for i, name in enumerate(("fx", "fy", "cx", "cy")):
        p = params[name]
        pj = plain["jackknife"][i]  # type: ignore[index]
        print(f"  {name:4} {plain['K'][i]:9.2f} {p['value']:9.2f} {p['std_covariance']:8.3f} "  # type: ignore[index]
              f"{p['std_jackknife']:8.3f} {p['std']:8.3f} {p['std_source']:>10} {pj:8.3f}  {p['std'] / pj:.2f}")
    print(f"  RMS plain {plain['rms']:.3f} px, s2r {quality['rms_left_px']:.3f} px; held-out (4 folds) plain "
          f"{plain['heldout']:.3f} px, s2r {held['heldout_px']:.3f} px (all corners {held['heldout_all_px']:.3f})")
    tp, ts = float(np.median(times["plain"])), float(np.median(times["s2r"]))
    print(f"  whole process, median of {repeats}: plain {tp:.2f} s, s2r {ts:.2f} s (jobs {jobs}): "
          f"speed-up {tp / ts:.2f}x; per repeat " + " ".join(
              f"{a / b:.2f}" for a, b in zip(times["plain"], times["s2r"], strict=True)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sets", nargs="+", help="image globs, one per set (quote them)")
    parser.add_argument("--pattern", default="9x6")
    parser.add_argument("--square", type=float, default=0.025)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    for images in args.sets:
        report(images, args.pattern, args.square, args.jobs, args.repeats)


if __name__ == "__main__":
    main()
