"""Fleet drift checks: per-robot cost, 1 against 2 Dask workers, and the plan for 1,000 robots nightly.

Robots are recordings of ordinary scenes ray-cast by tests/drift/scene_gen.py (no s2r code). Figures, in one
run on this machine:

- anchor: plain OpenCV on the same pairs (SIFT detect + ratio-test matching of every pair, the dominant cost of a
  check), in-process;
- ``check_drift`` in-process per robot (matching + fit + jackknife), as a ratio to the anchor;
- ``s2r fleet check`` whole process with a local Dask cluster of 1 and of 2 workers (start-up included), and
  the speed-up from 1 to 2 workers (near 2 when the per-robot cost dominates);
- the plan: robots per worker-hour from the per-robot cost, and workers for 1,000 robots in a 6-hour night.

Usage: ``python bench/bench_fleet.py [--robots 6] [--frames 6]`` (prints; asserts nothing).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.drift.check import check_drift
from s2r.drift.source import StereoSource, read_pairs
from s2r.formats.s2r_yaml import dump_profile
from tests.drift.conftest import rig, write_recording


def _anchor(folder: Path) -> float:
    """Seconds for plain OpenCV SIFT + ratio-test matching of every pair in ``folder``."""
    start = time.perf_counter()
    sift, matcher = cv2.SIFT_create(nfeatures=4000), cv2.BFMatcher(cv2.NORM_L2)
    for left_path in sorted((folder / "left").iterdir()):
        left = cv2.imread(str(left_path), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(folder / "right" / left_path.name), cv2.IMREAD_GRAYSCALE)
        _, dl = sift.detectAndCompute(left, None)
        _, dr = sift.detectAndCompute(right, None)
        good = [m for m, n in matcher.knnMatch(dl, dr, k=2) if m.distance < 0.8 * n.distance]
        assert good
    return time.perf_counter() - start


def _fleet_run(fleet: Path, out: Path, workers: int) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "s2r", "-q", "fleet", "check", str(fleet), "-o", str(out),
                    "--workers", str(workers), "--json"], check=False, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", type=int, default=6)
    parser.add_argument("--frames", type=int, default=6)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        profile_path = base / "rig.yaml"
        dump_profile(rig(), profile_path)
        robots = []
        for k in range(args.robots):
            turn = (0.0, 0.0, 0.0) if k % 2 == 0 else (0.2, -0.3, 0.15)
            folder = write_recording(base / f"r{k}", rig(), turn, frames=args.frames, seed=10 * k)
            robots.append({"name": f"r{k}", "profile": str(profile_path), "recording": str(folder)})
        fleet = base / "fleet.yaml"
        fleet.write_text(json.dumps({"robots": robots}))
        anchor = sum(_anchor(base / f"r{k}") for k in range(args.robots)) / args.robots
        start = time.perf_counter()
        for k in range(args.robots):
            check_drift(rig(), read_pairs(StereoSource(folder=base / f"r{k}")))
        in_process = (time.perf_counter() - start) / args.robots
        one = _fleet_run(fleet, base / "out1", 1)
        two = _fleet_run(fleet, base / "out2", 2)
    w, h = rig().image_size
    print(f"{args.robots} robots x {args.frames} pairs of {w}x{h}")
    print(f"per robot, in-process: plain OpenCV SIFT matching {anchor:.2f} s; s2r check_drift {in_process:.2f} s "
          f"({in_process / anchor:.2f}x the anchor)")
    print(f"fleet check whole process: 1 worker {one:.1f} s, 2 workers {two:.1f} s; speed-up {one / two:.2f}x "
          f"(Dask start-up and the process's own start are in both)")
    # a nightly check of a real robot: 20 pairs at 848x480 (a D435's infrared pair); matching scales with pixels
    nightly = in_process * (20.0 / args.frames) * (848 * 480) / (w * h)
    workers = 1000.0 * nightly / (6.0 * 3600.0)
    startup = max(0.0, one - args.robots * in_process)
    print(f"plan: a nightly check of 20 pairs at 848x480 costs about {nightly:.1f} s of one worker process "
          f"({3600.0 / nightly:.0f} robots per worker-hour); 1,000 robots in a 6-hour night need {workers:.2f} "
          "worker processes, so one two-core machine, or a few for the copying of each robot's recording to the "
          f"cluster, which this bench does not measure (Dask start-up: about {startup:.0f} s per run)")

if __name__ == "__main__":
    main()
