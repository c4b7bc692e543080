"""mrcal anchor of bench_calib_realsets.py: fold solves of both cameras jointly on given corners.

Run with the SYSTEM python that has Debian's python3-mrcal (``/usr/bin/python3``), never the project venv:

    /usr/bin/python3 bench/mrcal_heldout.py IN.npz OUT.npz [--lensmodel LENSMODEL_OPENCV4]

IN.npz (written by bench_calib_realsets.py): ``left``, ``right`` corners (n, N, 2) px in OpenCV's chessboard
order; ``pattern`` (cols, rows) inner corners; ``square`` (m); ``size`` (width, height) px; ``folds`` (K, n) bool,
True for the held-out views of each fold; ``K1 D1 K2 D2 R T`` a seed (OpenCV conventions, T in m).

For the full set and for every fold's training views, one mrcal.optimize of both cameras (camera 0 the
reference, ``R T`` mapping camera-0 points to camera 1 as OpenCV's stereoCalibrate), first flat, then with
mrcal's board warp (``calobject_warp``: a bend along each board axis). OUT.npz holds per variant (``flat``,
``warp``) and fold: intrinsics (K, 2, 4 + distortion terms) in mrcal's order (fx fy cx cy, then the OpenCV
coefficients), ``rt`` (K, 6) camera 1 from camera 0, ``board`` (K, N, 3) the board points (m) with the
fold's warp, ``warp`` (K, 2) m; and the same for the full set (``*_full``), with its RMS.
The held-out error itself is computed by the caller with its own evaluator on these models.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import mrcal
import numpy as np


def _seed_intrinsics(d: Any, n_dist: int) -> np.ndarray:
    out = np.zeros((2, 4 + n_dist))
    for cam, (k, dist) in enumerate(((d["K1"], d["D1"]), (d["K2"], d["D2"]))):
        out[cam, :4] = (k[0, 0], k[1, 1], k[0, 2], k[1, 2])
        src = np.asarray(dist, float).reshape(-1)[:n_dist]
        out[cam, 4:4 + len(src)] = src
    return out


def _observations(left: np.ndarray, right: np.ndarray, idx: np.ndarray, cols: int, rows: int) -> np.ndarray:
    obs = np.ones((2 * len(idx), rows, cols, 3))
    for j, i in enumerate(idx):
        obs[2 * j, ..., :2] = left[i].reshape(rows, cols, 2)
        obs[2 * j + 1, ..., :2] = right[i].reshape(rows, cols, 2)
    return obs


def solve(d: Any, idx: np.ndarray, *, lensmodel: str, warp: bool) -> dict[str, np.ndarray]:
    """One joint solve of both cameras on views ``idx``; the model, the board points and the RMS (px)."""
    cols, rows = (int(v) for v in d["pattern"])
    square = float(d["square"])
    n_dist = mrcal.lensmodel_num_params(lensmodel) - 4
    intr = _seed_intrinsics(d, n_dist)
    obs = _observations(d["left"], d["right"], idx, cols, rows)
    ind = np.array([(f, cam, cam - 1) for f in range(len(idx)) for cam in (0, 1)], np.int32)
    rt_tocam = mrcal.estimate_monocular_calobject_poses_Rt_tocam(
        ind, obs, square, ((lensmodel, intr[0]), (lensmodel, intr[1])))
    frames = np.array([mrcal.rt_from_Rt(rt_tocam[2 * f]) for f in range(len(idx))])
    ext = np.array([np.concatenate([mrcal.r_from_R(np.asarray(d["R"], float)), np.asarray(d["T"], float)])])
    size = np.asarray(d["size"], np.int32)
    warpv = np.zeros(2) if warp else None
    common = dict(extrinsics_rt_fromref=ext, frames_rt_toref=frames, points=None, observations_board=obs,
                  indices_frame_camintrinsics_camextrinsics=ind, observations_point=None,
                  indices_point_camintrinsics_camextrinsics=None, lensmodel=lensmodel,
                  imagersizes=np.array([size, size]), calibration_object_spacing=square,
                  do_apply_outlier_rejection=True, calobject_warp=warpv)
    mrcal.optimize(intr, do_optimize_intrinsics_distortions=False, do_optimize_calobject_warp=False, **common)
    stats = mrcal.optimize(intr, do_optimize_calobject_warp=warp, **common)
    board = mrcal.ref_calibration_object(cols, rows, square, calobject_warp=warpv).reshape(-1, 3)
    return {"intrinsics": intr, "rt": ext[0].copy(), "board": board,
            "warp": np.zeros(2) if warpv is None else warpv, "rms": np.array(stats["rms_reproj_error__pixels"])}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("inp")
    ap.add_argument("out")
    ap.add_argument("--lensmodel", default="LENSMODEL_OPENCV4")
    args = ap.parse_args(argv)
    d = dict(np.load(args.inp))
    n = len(d["left"])
    out: dict[str, np.ndarray] = {}
    for variant, warp in (("flat", False), ("warp", True)):
        full = solve(d, np.arange(n), lensmodel=args.lensmodel, warp=warp)
        for key, val in full.items():
            out[f"{variant}_full_{key}"] = val
        folds = [solve(d, np.flatnonzero(~mask), lensmodel=args.lensmodel, warp=warp) for mask in d["folds"]]
        for key in ("intrinsics", "rt", "board", "warp", "rms"):
            out[f"{variant}_{key}"] = np.array([f[key] for f in folds])
    np.savez(args.out, **out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
