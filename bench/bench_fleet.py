"""Fleet drift checks on a separate-process Dask cluster: per-robot cost, 1 against 2 workers, the 1,000-robot night.

Robots are recordings of ordinary scenes ray-cast by tests/drift/scene_gen.py (no s2r code). Figures, in one
run on this machine, with ``os.getloadavg()`` printed beside each (the machine is shared: CPU seconds are the
figures to compare, wall seconds move with the load):

- anchor: plain OpenCV on the same pairs (SIFT detect + ratio-test matching of every pair, the dominant cost of a
  check), in-process, CPU seconds per robot;
- where a check's time goes, in-process, CPU seconds per robot: reading (decode + size checks), matching (SIFT and
  mutual matching of every pair), fit (rotation fit, sigma, jackknife: check_drift minus its matching) and report
  (the HTML page with its figure);
- ``s2r fleet check --scheduler`` as a whole process against a ``dask scheduler`` with one, then two ``dask
  worker`` processes (separate processes on 127.0.0.1, started by this script and stopped by PID): wall seconds,
  the workers' CPU seconds per robot, and the speed-up from 1 to 2 workers (at most the cores free);
- the plan: robots per worker-hour and workers for 1,000 robots in a 6-hour night.

Usage: ``python bench/bench_fleet.py [--robots 8] [--frames 6]`` (prints; asserts nothing).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from s2r.drift.check import check_drift
from s2r.drift.matches import match_frame
from s2r.drift.report import check_report_html
from s2r.drift.source import StereoSource, read_pairs
from s2r.executor import child_environment
from s2r.formats.s2r_yaml import dump_profile
from s2r.rectification import stereo_rectification
from tests.drift.conftest import rig, write_recording
from tests.drift.fleet_cluster import dask_cluster


def _load() -> str:
    return "load " + " ".join(f"{v:.1f}" for v in os.getloadavg())


def _anchor(folder: Path) -> float:
    """CPU seconds of plain OpenCV SIFT + ratio-test matching of every pair in ``folder``."""
    start = time.process_time()
    sift, matcher = cv2.SIFT_create(nfeatures=4000), cv2.BFMatcher(cv2.NORM_L2)
    for left_path in sorted((folder / "left").iterdir()):
        left = cv2.imread(str(left_path), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(folder / "right" / left_path.name), cv2.IMREAD_GRAYSCALE)
        _, dl = sift.detectAndCompute(left, None)
        _, dr = sift.detectAndCompute(right, None)
        good = [m for m, n in matcher.knnMatch(dl, dr, k=2) if m.distance < 0.8 * n.distance]
        assert good
    return time.process_time() - start


def _stages(folder: Path) -> dict[str, float]:
    """CPU seconds of one robot's check by stage: read, match, fit, report."""
    profile = rig()
    times: dict[str, float] = {}
    start = time.process_time()
    pairs = list(read_pairs(StereoSource(folder=folder), sizes=None))
    times["read"] = time.process_time() - start
    rect = stereo_rectification(profile)
    start = time.process_time()
    for name, left, right in pairs:
        match_frame(profile, rect, left, right, name=name)
    times["match"] = time.process_time() - start
    start = time.process_time()
    result = check_drift(profile, pairs)
    times["fit"] = max(0.0, time.process_time() - start - times["match"])
    start = time.process_time()
    check_report_html(result, source=str(folder))
    times["report"] = time.process_time() - start
    return times


def _cpu(processes: list[subprocess.Popen[bytes]]) -> float:
    total = 0.0
    for p in processes:
        times = psutil.Process(p.pid).cpu_times()
        total += times.user + times.system
    return total


def _cluster_run(fleet: Path, out: Path, address: str, workers: list[subprocess.Popen[bytes]]) -> tuple[float, float]:
    """(wall s of the whole `s2r fleet check` process, CPU s the workers spent meanwhile)."""
    cpu = _cpu(workers)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "s2r", "-q", "fleet", "check", str(fleet), "-o", str(out),
                           "--scheduler", address, "--json"], check=False, capture_output=True,
                          env=child_environment())
    wall = time.perf_counter() - start
    if done.returncode not in (0, 1):
        raise RuntimeError(done.stderr.decode())
    return wall, _cpu(workers) - cpu


def _make_fleet(base: Path, robots: int, frames: int) -> Path:
    profile_path = base / "rig.yaml"
    dump_profile(rig(), profile_path)
    entries = []
    for k in range(robots):
        turn = (0.0, 0.0, 0.0) if k % 2 == 0 else (0.2, -0.3, 0.15)
        folder = write_recording(base / f"r{k}", rig(), turn, frames=frames, seed=10 * k)
        entries.append({"name": f"r{k}", "profile": str(profile_path), "recording": str(folder)})
    fleet = base / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": entries}))
    return fleet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", type=int, default=8)
    parser.add_argument("--frames", type=int, default=6)
    args = parser.parse_args()
    w, h = rig().image_size
    print(f"{args.robots} robots x {args.frames} pairs of {w}x{h}; {os.cpu_count()} cores; {_load()}")
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        fleet = _make_fleet(base, args.robots, args.frames)
        anchor = sum(_anchor(base / f"r{k}") for k in range(args.robots)) / args.robots
        stages = [_stages(base / f"r{k}") for k in range(args.robots)]
        per_stage = {s: sum(t[s] for t in stages) / args.robots for s in stages[0]}
        in_process = sum(per_stage.values())
        print(f"per robot, in-process CPU: plain OpenCV SIFT matching {anchor:.2f} s; s2r check {in_process:.2f} s "
              f"({in_process / anchor:.2f}x the anchor); {_load()}")
        print("  where it goes: " + ", ".join(f"{s} {v:.2f} s ({100 * v / in_process:.0f} %)"
                                             for s, v in per_stage.items()))
        with dask_cluster(base / "cluster", workers=1) as cluster:
            one, one_cpu = _cluster_run(fleet, base / "out1", cluster.address, cluster.workers)
            print(f"separate-process cluster, 1 worker: {one:.1f} s wall, workers {one_cpu / args.robots:.2f} CPU s "
                  f"per robot; {_load()}")
            cluster.add_worker("w1")
            cluster.wait_for_workers(2)
            two, two_cpu = _cluster_run(fleet, base / "out2", cluster.address, cluster.workers)
            print(f"separate-process cluster, 2 workers: {two:.1f} s wall, workers {two_cpu / args.robots:.2f} CPU s "
                  f"per robot; {_load()}")
    print(f"speed-up 1 -> 2 workers: {one / two:.2f}x wall (the process's start and Dask's connect are in both)")
    cores, load = os.cpu_count() or 1, os.getloadavg()[0]
    if load > cores:
        print(f"  the machine is busier than its cores (load {load:.1f} on {cores}): the second worker finds no free "
              "core, so this wall speed-up measures the queue, not Dask; the CPU s per robot above still hold")
    per_robot = max(one_cpu, two_cpu) / args.robots
    # a nightly check of a real robot: 20 pairs at 848x480 (a D435's infrared pair); matching scales with pixels
    nightly = per_robot * (20.0 / args.frames) * (848 * 480) / (w * h)
    workers = 1000.0 * nightly / (6.0 * 3600.0)
    print(f"plan: a nightly check of 20 pairs at 848x480 costs about {nightly:.1f} CPU s of one worker "
          f"({3600.0 / nightly:.0f} robots per worker-hour); 1,000 robots in a 6-hour night need {workers:.2f} "
          "single-threaded workers (cores), plus copying each recording to its worker, which this bench does not "
          "measure (a 20-pair PNG recording at 848x480 is about 10-15 MB)")


if __name__ == "__main__":
    main()
