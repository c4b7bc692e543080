"""Intel's depth-quality metrics on the real chessboard set: s2r beside plain OpenCV doing the same work, one run.

Run: ``.venv/bin/python bench/bench_depth_quality.py [--repeat 5] [--num-disparities 256]``

Needs ``../shared/data/opencv_stereo_chessboard`` (README there). The profile is calibrated from the same set with
``s2r calibrate`` (defaults). Both sides take their depth from the same ``StereoPipeline.compute`` (its speed
beside plain OpenCV is bench_depth.py's subject), so this compares the metrics. Per pair, plain OpenCV = what a
careful user writes by hand on that depth: ``findChessboardCorners`` + ``cornerSubPix`` on the rectified left
image, ``solvePnP`` (IPPE, then LM) for the board's plane, the ROI as the filled hull of the outer corners, and
numpy for Intel's definitions as rs-depth-quality computes them (nearest and farthest 0.5 % of the points by z
dropped; Z accuracy the median of (Z_fit - Z_plane) / Z_plane; plane-fit RMS the perpendicular distances to a total
least squares plane, % of distance; sub-pixel RMS f B / Z - f B / Z_fit) and fill rate, with no mismatch handling
(Intel's tool has none). s2r = ``measure_board_views`` on ``stereo_views`` (what ``s2r depth-quality`` runs), which
also counts mismatches and leaves them out, and marks frames it cannot score.

Prints per frame the figures of both (they agree on frames without mismatches; where the board is matched a
pattern period off, or lies partly outside the matcher's range, the plain figures explode and s2r's stay
measurements or say why there are none), then the time per frame of each, alternating runs, as a ratio.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.cli import main as s2r_main
from s2r.depth.pipeline import StereoPipeline
from s2r.quality.inputs import FramePaths
from s2r.quality.run import measure_board_views
from s2r.quality.views import stereo_fb, stereo_views, stereo_visible_m
from s2r.registry import load_profile

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opencv_stereo_chessboard"
PATTERN, SQUARE_M = (9, 6), 0.025

FloatArray = NDArray[np.float64]


def plain_frame(pipe: StereoPipeline, left_path: Path, right_path: Path) -> dict[str, float] | None:
    """Z accuracy %, plane-fit RMS %, fill % and distance (m) of one pair, by hand with OpenCV and numpy."""
    left, right = cv2.imread(str(left_path), cv2.IMREAD_COLOR), cv2.imread(str(right_path), cv2.IMREAD_COLOR)
    result = pipe.compute(left, right)
    depth = result.depth.astype(np.float64)
    rl = result.rect_left if result.rect_left.ndim == 2 else cv2.cvtColor(result.rect_left, cv2.COLOR_BGR2GRAY)
    found, corners = cv2.findChessboardCorners(rl, PATTERN)
    if not found:
        return None
    corners = cv2.cornerSubPix(rl, corners, (11, 11), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01))
    K = np.asarray(pipe.geometry_for((rl.shape[1], rl.shape[0])).rectification.P1[:3, :3], np.float64)
    obj = np.zeros((PATTERN[0] * PATTERN[1], 3), np.float64)
    obj[:, :2] = np.mgrid[0:PATTERN[0], 0:PATTERN[1]].T.reshape(-1, 2) * SQUARE_M
    _, rvec, tvec = cv2.solvePnP(obj, corners, K, None, flags=cv2.SOLVEPNP_IPPE)
    rvec, tvec = cv2.solvePnPRefineLM(obj, corners, K, None, rvec, tvec)
    normal = cv2.Rodrigues(rvec)[0][:, 2]
    offset = float(normal @ tvec.ravel())
    grid = corners.reshape(PATTERN[1], PATTERN[0], 2)
    hull = np.array([grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]])
    mask = np.zeros(depth.shape, np.uint8)
    cv2.fillConvexPoly(mask, np.round(hull * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    ys, xs = np.nonzero(mask)
    rays = np.column_stack([(xs - K[0, 2]) / K[0, 0], (ys - K[1, 2]) / K[1, 1], np.ones(xs.size)])
    truth = offset / (rays @ normal)
    z = depth[ys, xs]
    valid = np.isfinite(z) & (z > 0)
    order = np.argsort(z[valid])  # Intel's trim: the nearest and farthest 0.5 % of the points (by z) dropped
    cut = order.size // 200
    keep = order[cut:order.size - cut]
    zk, rk, tk = z[valid][keep], rays[valid][keep], truth[valid][keep]
    points = rk * zk[:, None]
    centre = points.mean(axis=0)
    n_fit = np.linalg.svd(points - centre, full_matrices=False)[2][-1]
    fitted = (n_fit @ centre) / (rk @ n_fit)
    fb = pipe.rectification.fx_px * pipe.rectification.baseline_m
    dist = float(np.median(truth))
    return {"distance_m": dist,
            "z_accuracy_pct": float(np.median((fitted - tk) / tk)) * 100.0,
            "plane_fit_rms_pct": float(np.sqrt(np.mean(np.square(points @ n_fit - n_fit @ centre)))) / dist * 100.0,
            "subpixel_rms_px": float(np.sqrt(np.mean(np.square(fb / zk - fb / fitted)))),
            "fill_rate_pct": 100.0 * valid.sum() / valid.size}


def _num(value: float | None, width: int, digits: int) -> str:
    return f"{'-':>{width}}" if value is None else f"{value:{width}.{digits}f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--num-disparities", type=int, default=256)
    parser.add_argument("--frames", default="01,02,03,04,05,06,07,08,09,11,12,13,14",
                        help="pair numbers of the real set")
    args = parser.parse_args()
    if not DATA.is_dir():
        print(f"skipped: {DATA} is absent (see ../shared/data/README.md)")
        return 0
    pairs = [FramePaths(DATA / f"left{n}.jpg", right=DATA / f"right{n}.jpg") for n in args.frames.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        profile_path = Path(tmp) / "real.yaml"
        if s2r_main(["-q", "calibrate", str(DATA), "--pattern", "9x6", "--square", str(SQUARE_M), "-o",
                     str(profile_path), "--jobs", "2"]) != 0:
            print("calibration of the real set failed", file=sys.stderr)
            return 1
        profile = load_profile(str(profile_path))
    pipe = StereoPipeline(profile, num_disparities=args.num_disparities)

    def run_s2r() -> list[dict[str, float | None]]:
        result = measure_board_views(profile, stereo_views(pipe, pairs), pattern=PATTERN, square_m=SQUARE_M,
                                     fb_px_m=stereo_fb(pipe), source="bench", visible_m=stereo_visible_m(pipe))
        return [f.as_dict() for f in result.frames]

    def run_plain() -> list[dict[str, float] | None]:
        return [plain_frame(pipe, p.left, p.right) for p in pairs if p.right is not None]

    ours, plain = run_s2r(), run_plain()
    print(f"real set, {len(pairs)} pairs, {args.num_disparities} disparities, preset {pipe.preset}")
    print(f"{'pair':8} {'dist m':>7} | {'Z acc % s2r':>11} {'plain':>7} | {'RMS % s2r':>9} {'plain':>9} | "
          f"{'subpx s2r':>9} {'plain':>8} | {'fill % s2r':>10} {'plain':>6} | {'out %':>5} | not scored")
    for pair, a, b in zip(pairs, ours, plain, strict=True):
        if b is None or a["distance_m"] is None:
            print(f"{pair.left.stem:8} board not found (s2r: {a['not_scored']!r}, plain: {b is not None})")
            continue
        print(f"{pair.left.stem:8} {a['distance_m']:7.3f} | {_num(a['z_accuracy_pct'], 11, 3)} "
              f"{b['z_accuracy_pct']:7.3f} | {_num(a['plane_fit_rms_pct'], 9, 3)} {b['plane_fit_rms_pct']:9.3f} | "
              f"{_num(a['subpixel_rms_px'], 9, 3)} {b['subpixel_rms_px']:8.3f} | {_num(a['fill_rate_pct'], 10, 1)} "
              f"{b['fill_rate_pct']:6.1f} | {_num(a['outlier_pct'], 5, 1)} | {a['not_scored']}")
    t_s2r, t_plain = [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        run_s2r()
        t1 = time.perf_counter()
        run_plain()
        t_s2r.append(t1 - t0)
        t_plain.append(time.perf_counter() - t1)
    per = len(pairs)
    s, p = statistics.median(t_s2r) / per, statistics.median(t_plain) / per
    print(f"time per frame (median of {args.repeat} alternating runs): s2r {s * 1e3:.1f} ms, plain OpenCV "
          f"{p * 1e3:.1f} ms, ratio s2r/plain {s / p:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
