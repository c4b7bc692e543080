"""Benchmark ``s2r check`` on a real rig against plain OpenCV feature matching of the same pairs, side by side.

Data: OpenCV's stereo chessboard set (a real webcam rig, 640x480, ``../shared/data/opencv_stereo_chessboard``)
and a profile of it (``PROFILE``; ``s2r calibrate`` it first, see Usage).

- anchor, whole process: a plain Python script (``python -c``) that reads every ``leftNN``/``rightNN`` pair with
  ``cv2.imread`` and matches it as any drift check must: SIFT (4000 features) in both images, brute-force k=2
  matching with Lowe's ratio test (0.8) and a mutual best-match check (a full backward k=1 search);
- s2r, whole process: the installed ``s2r check PROFILE FOLDER --json``, start to exit;
- in-process, where s2r's time goes: reading, SIFT matching, ORB matching (the second detector whose estimators
  widen sigma), and the fit (five jackknifed estimators, the swap tests, costs and verdict: ``summarise``).

Rounds are interleaved (anchor, s2r, anchor, ...) so load from other processes hits both alike; the figures are
medians over ``--rounds``, CPU seconds (user + system, of the child and every process it started) first, since
they hold under load, then wall seconds, with the load average beside them. The issue's bar: s2r <= 1.2x.

Figures (2026-12-06, 2 shared cores, 13 pairs, whole process, interleaved rounds; the old tree on PYTHONPATH for
"before"). At load 2.4-2.9: before plain 3.11 CPU s / 2.07 s wall, s2r 5.49 CPU s (1.77x) / 4.14 s (2.00x); after
plain 3.17 / 2.55 s, s2r 4.05 CPU s (**1.28x**) / 3.90 s (1.53x). At load 5.1-5.4: before 1.77x CPU (in-process
SIFT 3.19, ORB 1.58, fit 0.99 CPU s), after 1.39x CPU (SIFT 2.84, ORB 0.99, fit 0.33); the wall clock at that load
(2.02x) is not a figure to compare. The rest over the anchor: ORB (its detection and matching of ~3000 features a frame,
0.08 CPU s a pair: the second detector's estimators widen sigma, so they stay), the fit (five jackknifed
estimators, 0.33 s) and s2r's imports (pydantic and the profile models, ~0.2 s more than ``import cv2``).

Usage: s2r calibrate ../shared/data/opencv_stereo_chessboard --pattern 9x6 --square 0.025 -o /tmp/webcam.yaml
       .venv/bin/python bench/bench_check.py /tmp/webcam.yaml [--rounds 5]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

FOLDER = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opencv_stereo_chessboard"
_SCRIPT = Path(sys.executable).with_name("s2r")
S2R = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "s2r"]

PLAIN = """
import sys
from pathlib import Path
import cv2
folder = Path(sys.argv[1])
sift, matcher = cv2.SIFT_create(nfeatures=4000), cv2.BFMatcher(cv2.NORM_L2)
total = 0
for left_path in sorted(folder.glob("left[0-9]*.*")):
    left = cv2.imread(str(left_path), cv2.IMREAD_GRAYSCALE)
    right = cv2.imread(str(left_path.with_name("right" + left_path.name[4:])), cv2.IMREAD_GRAYSCALE)
    kl, dl = sift.detectAndCompute(left, None)
    kr, dr = sift.detectAndCompute(right, None)
    back = {m.queryIdx: m.trainIdx for m, in matcher.knnMatch(dr, dl, k=1)}
    total += sum(1 for m, n in matcher.knnMatch(dl, dr, k=2)
                 if m.distance < 0.8 * n.distance and back.get(m.trainIdx) == m.queryIdx)
print(total)
"""


def _load() -> str:
    return "load " + " ".join(f"{v:.1f}" for v in os.getloadavg())


def time_once(argv: list[str]) -> tuple[float, float]:
    """``(wall, CPU user + system)`` seconds of one child process (and its children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 1):  # 1: a check that found drift or cannot tell is still a run
        raise RuntimeError(f"{argv} exited {done.returncode}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def in_process(profile_path: Path, folder: Path) -> dict[str, float]:
    """CPU seconds of s2r's check by stage, in this process."""
    from s2r.drift.check import summarise
    from s2r.drift.matches import gate_matches, raw_matches
    from s2r.drift.source import StereoSource, read_pairs
    from s2r.rectification import stereo_rectification
    from s2r.registry import load_profile

    profile = load_profile(profile_path)
    rect = stereo_rectification(profile)
    times: dict[str, float] = {}
    start = time.process_time()
    pairs = list(read_pairs(StereoSource(folder=folder)))
    times["read"] = time.process_time() - start
    start = time.process_time()
    sift = [raw_matches(left, right, detector="sift") for _, left, right in pairs]
    times["match SIFT"] = time.process_time() - start
    start = time.process_time()
    orb = [raw_matches(left, right, detector="orb") for _, left, right in pairs]
    times["match ORB"] = time.process_time() - start
    from s2r.drift.matches import FrameMatches

    frames = []
    for (name, _, _), raw, other in zip(pairs, sift, orb, strict=True):
        rect_l, rect_r, behind = gate_matches(profile, rect, raw)
        frames.append(FrameMatches(name, rect_l, rect_r, raw.keypoints, raw.sharpness, behind=behind,
                                   identical=raw.identical, raw=raw, second=other))
    start = time.process_time()
    summarise(profile, frames)
    times["fit (summarise)"] = time.process_time() - start
    return times


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("profile", type=Path, help="a profile of the webcam rig (see Usage)")
    parser.add_argument("--folder", type=Path, default=FOLDER, help="leftNN/rightNN pairs (default: the webcam set)")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds (median reported, default 5)")
    args = parser.parse_args()
    runs = {"plain OpenCV (SIFT + ratio + mutual)": [sys.executable, "-c", PLAIN, str(args.folder)],
            "s2r check --json": [*S2R, "check", str(args.profile), str(args.folder), "--json"],
            "s2r check --json --jobs 1": [*S2R, "check", str(args.profile), str(args.folder), "--json", "--jobs", "1"]}
    for argv in runs.values():  # warm the file cache and the bytecode
        time_once(argv)
    times: dict[str, list[tuple[float, float]]] = {label: [] for label in runs}
    print(f"before the rounds: {_load()} on {os.cpu_count()} cores")
    for _ in range(args.rounds):
        for label, argv in runs.items():
            times[label].append(time_once(argv))
    anchor_wall, anchor_cpu = (statistics.median(v[i] for v in times[next(iter(runs))]) for i in (0, 1))
    print(f"whole process, median of {args.rounds} interleaved rounds ({_load()}):")
    for label, values in times.items():
        wall, cpu = (statistics.median(v[i] for v in values) for i in (0, 1))
        print(f"  {label:<40} CPU {cpu:6.2f} s ({cpu / anchor_cpu:4.2f}x)   wall {wall:6.2f} s "
              f"({wall / anchor_wall:4.2f}x)")
    stages = in_process(args.profile, args.folder)
    total = sum(stages.values())
    print(f"in-process, where s2r's check goes (CPU s, one run, {_load()}): "
          + ", ".join(f"{k} {v:.2f}" for k, v in stages.items()) + f"; total {total:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
