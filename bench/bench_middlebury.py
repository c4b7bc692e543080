"""Accuracy of every depth preset on real Middlebury pairs, beside plain OpenCV with the same parameters.

Run: ``.venv/bin/python bench/bench_middlebury.py [--scenes cones teddy aloe] [--extra]``

Each scene becomes an ideal rectified profile (identity R, T = (-B, 0, 0), zero distortion, cx = (W - 1) / 2), so
rectification is the identity and the pipeline sees the same pixels as plain OpenCV. For each preset it prints
bad-2.0 (share of pixels with ground truth AND a returned disparity that are off by more than 2 px) and density
(share of pixels with ground truth that got a disparity), for: plain OpenCV (``matcher.compute`` on the raw
images with the preset's exact parameters), the pipeline without post-processing, and the pipeline with the
preset's default post-processing. ``--extra`` adds more post-processing combinations.
Data: ../shared/data/middlebury (Scharstein & Szeliski 2002/2003; Scharstein et al. 2006).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.pipeline import StereoPipeline
from s2r.depth.presets import PRESETS, create_matcher
from s2r.profile import Camera, Extrinsics, MatcherSettings, Provenance, StereoProfile

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "middlebury"
#: scene -> (left, right, ground truth, ground-truth scale (px per count), disparity range)
SCENES: dict[str, tuple[str, str, str, float, int]] = {
    "cones": ("im2.png", "im6.png", "disp2.png", 0.25, 64),
    "teddy": ("im2.png", "im6.png", "disp2.png", 0.25, 64),
    "aloe": ("aloeL.jpg", "aloeR.jpg", "aloeGT.png", 1.0, 224),  # ground truth reaches 211 px
}
FX_PX, BASELINE_M = 1000.0, 0.1
EXTRA_POST: tuple[tuple[str, ...], ...] = (
    ("median",), ("lr-check",), ("speckle",), ("lr-check", "median"), ("lr-check", "speckle", "median"),
    ("median", "close"), ("lr-check", "speckle", "median", "fill"),
)


def ideal_profile(name: str, width: int, height: int, num_disparities: int) -> StereoProfile:
    """An ideal rectified pair: identity rotation, T = (-B, 0, 0), no distortion, exact-centre principal point."""
    cam = Camera(width_px=width, height_px=height, fx_px=FX_PX, fy_px=FX_PX, cx_px=(width - 1) / 2,
                 cy_px=(height - 1) / 2)
    z_min = FX_PX * BASELINE_M / (num_disparities - 1)
    matcher = MatcherSettings(algorithm="sgbm_3way", num_disparities=num_disparities, block_size=5,
                              min_depth_m=z_min, max_depth_m=100.0)
    return StereoProfile(name=f"middlebury_{name}", left=cam, right=cam,
                         extrinsics=Extrinsics(translation_m=(-BASELINE_M, 0.0, 0.0)), matcher=matcher,
                         provenance=Provenance(origin="real", method="Middlebury rectified pair"))


def load_scene(name: str) -> tuple[NDArray[np.uint8], NDArray[np.uint8], NDArray[np.float32], int]:
    """Left, right (BGR), ground-truth disparity (px, NaN unknown) and the disparity range of a scene."""
    left_name, right_name, gt_name, scale, nd = SCENES[name]
    folder = DATA / name
    left, right = cv2.imread(str(folder / left_name)), cv2.imread(str(folder / right_name))
    gt = cv2.imread(str(folder / gt_name), cv2.IMREAD_GRAYSCALE).astype(np.float32) * scale
    gt[gt == 0] = np.nan
    return left, right, gt, nd  # type: ignore[return-value]


def score(disparity: NDArray[np.floating], gt: NDArray[np.float32]) -> tuple[float, float]:
    """(bad-2.0 % of returned pixels with ground truth, density % of ground-truth pixels returned)."""
    known = np.isfinite(gt)
    returned = known & np.isfinite(disparity)
    bad = returned & (np.abs(np.where(returned, disparity, 0) - np.where(returned, gt, 0)) > 2.0)
    return 100.0 * bad.sum() / max(returned.sum(), 1), 100.0 * returned.sum() / max(known.sum(), 1)


def plain_opencv(pipe: StereoPipeline, left: NDArray[np.uint8], right: NDArray[np.uint8]) -> NDArray[np.float32]:
    """Plain OpenCV with the preset's exact matcher parameters on the raw images; NaN where not returned."""
    cfg = pipe.config
    if cfg.channels == 1:
        left, right = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), cv2.cvtColor(right, cv2.COLOR_BGR2GRAY)
    raw = create_matcher(cfg).compute(left, right)
    disp = raw.astype(np.float32) / 16.0
    disp[raw < cfg.min_disparity * 16] = np.nan
    return disp


def run_scene(name: str, *, extra: bool) -> list[str]:
    """Table rows for one scene."""
    left, right, gt, nd = load_scene(name)
    profile = ideal_profile(name, left.shape[1], left.shape[0], nd)
    rows = []
    for preset in PRESETS:
        pipe = StereoPipeline(profile, preset=preset, num_disparities=nd)
        plain = score(plain_opencv(pipe, left, right), gt)
        core = score(StereoPipeline(profile, preset=preset, num_disparities=nd, postprocess=())
                     .compute(left, right).disparity, gt)
        full = score(pipe.compute(left, right).disparity, gt)
        post = "+".join(pipe.postprocess) or "-"
        rows.append(f"{name:6} {preset:11} {plain[0]:6.2f} {plain[1]:6.1f}   {core[0]:6.2f} {core[1]:6.1f}   "
                    f"{full[0]:6.2f} {full[1]:6.1f}  {post}")
        for stages in EXTRA_POST if extra else ():
            res = score(StereoPipeline(profile, preset=preset, num_disparities=nd, postprocess=stages)
                        .compute(left, right).disparity, gt)
            rows.append(f"{'':6} {'':11} {'':14}   {'':14}   {res[0]:6.2f} {res[1]:6.1f}  {'+'.join(stages)}")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--extra", action="store_true", help="also try more post-processing combinations")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)
    if not DATA.is_dir():
        print(f"Middlebury data not found at {DATA} (see ../shared/data/README.md)")
        return
    print("bad-2.0 % of returned pixels / density % of ground-truth pixels")
    print(f"{'scene':6} {'preset':11} {'plain OpenCV':>14}   {'pipeline core':>14}   {'pipeline+post':>14}  post")
    for name in args.scenes:
        for row in run_scene(name, extra=args.extra):
            print(row, flush=True)


if __name__ == "__main__":
    main()
