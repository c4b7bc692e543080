"""Speed of the depth pipeline at 640x480 beside plain OpenCV doing the same work, in one run.

Run: ``.venv/bin/python bench/bench_depth.py [--repeat 30] [--frames 40]``

For every preset, plain OpenCV = what a user writes by hand with the same maps and matcher: (grey conversion for
grey presets), two ``cv2.remap`` with fixed-point maps, one ``compute``, and the usual ``raw / 16`` float
conversion. The pipeline does the same plus input checks, NaN marking and depth. Runs alternate (pipeline, plain,
pipeline, ...) so machine load hits both alike; figures are medians. Then the full preset (its default
post-processing) in frames per second, sequence mode throughput (read PNG, compute, write outputs) serial
against the threaded stages, and the median relative depth error on rendered planes beside Intel's RMS model.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.names import PRESETS
from s2r.depth.outputs import read_image, write_outputs
from s2r.depth.pipeline import StereoPipeline
from s2r.depth.presets import create_matcher
from s2r.depth.sequence import pair_images, run_sequence
from s2r.errors import ProfileError
from s2r.profile import Camera, Distortion, Extrinsics, Provenance, StereoProfile
from s2r.registry import load_profile

W, H = 640, 480


def bench_profile() -> StereoProfile:
    """The shipped sim profile of the seed rig (``gazebo_dual_camera``: 640x480, fx 554.38, B 0.1 m, from 0.5 m:
    112 disparities); without it a rig like the seed tutorial's camera_info (fx 381.36) with mild distortion and
    a 0.5 deg rotation. Remap cost does not depend on the map's content."""
    try:
        return load_profile("gazebo_dual_camera")
    except ProfileError:
        pass
    cam = Camera(width_px=W, height_px=H, fx_px=381.36, fy_px=381.36, cx_px=320.5, cy_px=240.5,
                 distortion=Distortion(coefficients=(-0.05, 0.01, 0.0, 0.0, 0.0)))
    angle = np.deg2rad(0.5)
    rot = ((np.cos(angle), 0.0, np.sin(angle)), (0.0, 1.0, 0.0), (-np.sin(angle), 0.0, np.cos(angle)))
    return StereoProfile(name="bench_rig", left=cam, right=cam,
                         extrinsics=Extrinsics(rotation=rot, translation_m=(-0.1, 0.0, 0.0)),
                         provenance=Provenance(origin="sim", method="bench"))


def textured_pair(seed: int = 0, shift: int = 24) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """A BGR speckle pair with a constant shift (x_right = x_left - shift)."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, size=(H // 2, (W + shift) // 2 + 1, 3), dtype=np.uint8)
    tex = cv2.GaussianBlur(cv2.resize(small, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST), (3, 3), 0)
    return np.ascontiguousarray(tex[:H, :W]), np.ascontiguousarray(tex[:H, shift:shift + W])


def plain_opencv(pipe: StereoPipeline) -> Callable[[NDArray[np.uint8], NDArray[np.uint8]], NDArray[np.float32]]:
    """The same work by hand with plain OpenCV: (cvtColor,) two remaps, one compute, raw / 16."""
    cfg, maps = pipe.config, pipe.maps
    matcher = create_matcher(cfg)
    grey = cfg.channels == 1

    def run(left: NDArray[np.uint8], right: NDArray[np.uint8]) -> NDArray[np.float32]:
        if grey:
            left, right = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), cv2.cvtColor(right, cv2.COLOR_BGR2GRAY)
        rl = cv2.remap(left, maps.left_map1, maps.left_map2, cv2.INTER_LINEAR)
        rr = cv2.remap(right, maps.right_map1, maps.right_map2, cv2.INTER_LINEAR)
        return matcher.compute(rl, rr).astype(np.float32) / 16.0  # type: ignore[no-any-return]

    return run


def alternate(a: Callable[[], object], b: Callable[[], object], repeat: int
              ) -> tuple[float, float, float, float]:
    """Median seconds of ``a`` and ``b``, the median of the per-round ratios a/b (each round runs a then b back to
    back, so load bursts hit both) and the ratio of the minima: (a_med, b_med, ratio_paired, ratio_min)."""
    a(), b()
    ta, tb = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        a()
        t1 = time.perf_counter()
        b()
        t2 = time.perf_counter()
        ta.append(t1 - t0)
        tb.append(t2 - t1)
    paired = statistics.median(x / y for x, y in zip(ta, tb, strict=True)) if tb[0] > 0 else float("nan")
    return statistics.median(ta), statistics.median(tb), paired, min(ta) / max(min(tb), 1e-12)


def cpu_seconds(run: Callable[[], object], repeat: int) -> float:
    """Process CPU seconds (all threads) per call of ``run``, averaged over ``repeat`` calls."""
    run()
    start = time.process_time()
    for _ in range(repeat):
        run()
    return (time.process_time() - start) / repeat


def bench_presets(repeat: int, num_disparities: int | None) -> None:
    profile = bench_profile()
    left, right = textured_pair()
    print(f"640x480 BGR input, {repeat} alternating runs, median ms; ratio = pipeline core / plain OpenCV (median "
          "of back-to-back pairs, and of the minima); full = the preset with its default post-processing")
    print("cpu = process CPU time per frame of the full preset (all threads): 1/cpu is the frame rate a machine "
          "with one free core would reach, a floor for 2 idle cores")
    print(f"{'preset':11} {'ndisp':>5} {'plain':>7} {'core':>7} {'ratio':>6} {'(min)':>6}   {'full':>7} {'fps':>6} "
          f"{'cpu':>7} {'fps':>6}  post")
    for preset in PRESETS:
        core = StereoPipeline(profile, preset=preset, postprocess=(), num_disparities=num_disparities)
        plain = plain_opencv(core)
        t_core, t_plain, ratio, ratio_min = alternate(lambda p=core: p.compute(left, right),
                                                      lambda f=plain: f(left, right), repeat)
        full = StereoPipeline(profile, preset=preset, num_disparities=num_disparities)
        t_full = alternate(lambda p=full: p.compute(left, right), lambda: None, repeat)[0]
        cpu = cpu_seconds(lambda p=full: p.compute(left, right), repeat)
        print(f"{preset:11} {core.config.num_disparities:5d} {1e3 * t_plain:7.2f} {1e3 * t_core:7.2f} "
              f"{ratio:6.3f} {ratio_min:6.3f}   {1e3 * t_full:7.2f} {1 / t_full:6.1f} {1e3 * cpu:7.2f} {1 / cpu:6.1f}  "
              f"{'+'.join(full.postprocess) or '-'}", flush=True)


def bench_sequence(frames: int) -> None:
    profile = bench_profile()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for side in ("L", "R"):
            (root / side).mkdir()
        for i in range(frames):
            left, right = textured_pair(seed=i)
            cv2.imwrite(str(root / "L" / f"{i:04d}.png"), left)
            cv2.imwrite(str(root / "R" / f"{i:04d}.png"), right)
        pairs = pair_images(root / "L", root / "R")
        for preset in ("fast", "profile"):
            pipe = StereoPipeline(profile, preset=preset)
            t0 = time.perf_counter()
            for i, (lp, rp) in enumerate(pairs):
                write_outputs(root / "serial", pipe.compute(read_image(lp), read_image(rp)), prefix=f"{i:04d}_",
                              force=True)
            serial = time.perf_counter() - t0
            rates = []
            for workers in (1, 2):
                t0 = time.perf_counter()
                run_sequence(pipe, pairs, root / f"seq{workers}", workers=workers, force=True)
                rates.append(frames / (time.perf_counter() - t0))
            print(f"sequence {preset:8} {frames} frames: serial {frames / serial:5.1f} fps, threaded stages "
                  f"1 worker {rates[0]:5.1f} fps, 2 workers {rates[1]:5.1f} fps "
                  f"(x{rates[1] * serial / frames:.2f})", flush=True)


def bench_planes(distances: tuple[float, ...]) -> None:
    """Median absolute relative depth error on rendered fronto-parallel planes, beside Intel's RMS model."""
    try:
        from s2r.render.scenes import render_scene
    except ImportError:
        print("rendered planes: s2r.render.scenes not available")
        return
    profile = bench_profile()
    print(f"rendered planes through {profile.name} (fx {profile.left.fx_px:.2f}, B {profile.baseline_m} m): median "
          "|Z - Z_true| / Z_true in %, density % in brackets; Intel model RMS(Z) / Z = Z s / (fx B), s = 0.08 px")
    intel = [100 * float(profile.depth_rms_m(d)) / d for d in distances]
    print(f"{'Intel model':19} " + " ".join(f"{v:14.3f}" for v in intel))
    for scene in ("planes", "slanted"):
        frames = render_scene(profile, scene=scene, distances_m=distances, supersample=2, jobs=2)
        print(f"{scene:19} " + " ".join(f"{d:>13.1f}m" for d in distances))
        _plane_rows(profile, frames)


def _plane_rows(profile: StereoProfile, frames: list[Any]) -> None:
    for preset in PRESETS:
        pipe = StereoPipeline(profile, preset=preset)
        cells = []
        for frame in frames:
            result = pipe.compute(frame.left, frame.right)
            known = np.isfinite(frame.depth_rect_m)
            ok = result.valid & known
            rel = np.abs(result.depth[ok] - frame.depth_rect_m[ok]) / frame.depth_rect_m[ok]
            med = 100 * float(np.median(rel)) if rel.size else float("nan")
            cells.append(f"{med:7.3f} ({100 * ok.sum() / max(known.sum(), 1):3.0f})")
        print(f"  {preset:17} " + " ".join(f"{c:>14}" for c in cells), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--num-disparities", type=int, help="override every preset's disparity range")
    parser.add_argument("--no-planes", action="store_true", help="skip the rendered-planes accuracy table")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)
    print(f"OpenCV {cv2.__version__}, {cv2.getNumberOfCPUs()} CPUs, {cv2.getNumThreads()} OpenCV threads")
    bench_presets(args.repeat, args.num_disparities)
    bench_sequence(args.frames)
    if not args.no_planes:
        bench_planes((0.5, 1.0, 2.0, 3.0, 5.0))


if __name__ == "__main__":
    main()
