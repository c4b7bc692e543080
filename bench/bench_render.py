"""Render speed: s2r's PyBullet camera (1x, 2x supersampling, with and without distortion) next to a bare
pybullet getCameraImage of the same scene, and the parallel speed-up of a board set.

Run: ``.venv/bin/python bench/bench_render.py``. Figures are medians on this machine, measured side by side
in one run (other load on the machine shifts absolute times, not the ratios much).
"""

from __future__ import annotations

import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.render.boards.poses import BoardGeometry, sample_board_poses
from s2r.render.boards.sets import board_surface, render_board_set
from s2r.render.camera import PinholeView, render_pinhole
from s2r.render.rig import StereoJob, render_stereo_images, stereo_setups
from s2r.render.sensor import capture, prepared
from s2r.render.world import Surface, set_world
from tests.conftest import make_rig

REPEATS = 15


def _median_ms(fn: object, repeats: int = REPEATS) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()  # type: ignore[operator]
        times.append((time.perf_counter() - t0) * 1000.0)
    return statistics.median(times)


def main() -> None:
    plain = make_rig()
    distorted = make_rig(name="distorted", distortion=(-0.12, 0.05, 0.0, 0.0, 0.0), rotation_deg=(0.3, -0.5, 0.2))
    board = BoardGeometry((9, 6), 0.025, 1.0)
    pose = sample_board_poses(plain, board, views=1, seed=0)[0]
    print(f"640x480 textured chessboard, ms per camera image (median of {REPEATS})")
    print(f"{'case':<34}{'ms':>8}{'x bare pybullet':>18}")
    with tempfile.TemporaryDirectory() as tmp:
        mesh, texture = board_surface(Path(tmp), board)
        set_world([Surface(mesh, texture, pose)])
        bare = PinholeView(plain.left.K, 640, 480, np.eye(4), 0.05, 50.0)
        base = _median_ms(lambda: render_pinhole(bare))
        print(f"{'bare getCameraImage 1x':<34}{base:8.1f}{1.0:18.2f}")
        for profile in (plain, distorted):
            for s in (1, 2):
                left, _ = stereo_setups(profile, supersample=s)
                prepared(left)  # per-process map set-up, done once per camera
                ms = _median_ms(lambda left=left: capture(left))  # type: ignore[misc]
                label = f"s2r capture {s}x {'distorted' if profile is distorted else 'pinhole'}"
                print(f"{label:<34}{ms:8.1f}{ms / base:18.2f}")
        left, right = stereo_setups(plain, supersample=1)
        job = StereoJob(left, right, (Surface(mesh, texture, pose),), 0.0, 1.0, 0, 0)
        pair = _median_ms(lambda: render_stereo_images(job))
        print(f"{'s2r stereo pair 1x (both cameras)':<34}{pair:8.1f}{pair / base:18.2f}")
    print()
    print("render_board_set, 20 views at 2x, 640x480 (wall time incl. PNG writes; best of 2 interleaved runs)")
    cores = os.cpu_count() or 1
    walls: dict[int, float] = {}
    for _ in range(2):
        for jobs in sorted({1, cores}):
            with tempfile.TemporaryDirectory() as out:
                t0 = time.perf_counter()
                render_board_set(plain, Path(out) / "set", views=20, supersample=2, jobs=jobs)
                walls[jobs] = min(walls.get(jobs, float("inf")), time.perf_counter() - t0)
    for jobs, wall in walls.items():
        print(f"  jobs={jobs}: {wall:6.2f} s  ({wall / 20 * 1000:6.1f} ms per stereo view)")
    if cores > 1:
        print(f"  parallel speed-up with {cores} processes: {walls[1] / walls[cores]:.2f}x")


if __name__ == "__main__":
    main()
