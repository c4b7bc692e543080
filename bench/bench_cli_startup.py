"""Benchmark the start-up of light `s2r` commands against Python importing numpy, yaml and pydantic.

The anchor is ``python -c "import numpy, yaml, pydantic"``: the least any s2r command must pay, since every
command loads a profile (numpy arrays, YAML, pydantic models). Each command runs as a fresh subprocess, the
runs interleaved (anchor, command 1, command 2, ..., anchor, ...) so load from other processes hits all of
them alike; the figure is the median of ``--runs`` runs (default 5) and the ratio to the anchor's median.
The issue's bar: ``--help``, ``--version`` and ``profile show|list|convert`` within 2x the anchor.

s2r's modules are compiled first (``compileall``, as ``make`` does): with PYTHONDONTWRITEBYTECODE set and no
``__pycache__`` (a fresh editable install) every command compiles ~30-150 modules again, ~0.07-0.1 s of CPU that
no installed copy pays (2026-12-06: ``profile show`` read 1.63x CPU without the bytecode, 1.31x with it).

Usage: .venv/bin/python bench/bench_cli_startup.py [--runs 5]
Timings on a shared machine are disturbed by other load: compare the ratios, measured in one run.
"""

from __future__ import annotations

import argparse
import compileall
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: The installed console script (what a user types), else the module.
_SCRIPT = Path(sys.executable).with_name("s2r")
S2R = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "s2r"]
ANCHOR = [sys.executable, "-c", "import numpy, yaml, pydantic"]


def commands(tmp: Path) -> dict[str, list[str]]:
    """Command label -> argv; convert writes into ``tmp`` (with --force, so every run does the same work)."""
    return {
        "python -c 'import numpy, yaml, pydantic'": ANCHOR,
        "s2r --help": [*S2R, "--help"],
        "s2r --version": [*S2R, "--version"],
        "s2r profile list": [*S2R, "profile", "list"],
        "s2r profile show realsense_d435_848x480": [*S2R, "profile", "show", "realsense_d435_848x480"],
        "s2r profile convert ... --to kalibr": [*S2R, "profile", "convert", "realsense_d435_848x480", "--to",
                                                "kalibr", "-o", str(tmp / "camchain.yaml"), "--force"],
        # ROS camera_info holds the rectification (R1, P1): OpenCV's stereoRectify, so cv2 loads
        "s2r profile convert ... --to ros (OpenCV)": [*S2R, "profile", "convert", "realsense_d435_848x480", "--to",
                                                      "ros", "-o", str(tmp / "ros"), "--force"],
    }


def time_once(argv: list[str]) -> tuple[float, float]:
    """``(wall-clock, CPU user + system)`` seconds of one run; raises when the command fails.

    The CPU figure is less disturbed than the wall clock when other processes load the machine.
    """
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="runs per command (median reported, default 5)")
    args = parser.parse_args()
    import s2r  # only to find its folder

    compileall.compile_dir(Path(s2r.__file__).parent, quiet=1)  # the bytecode an installed copy has
    with tempfile.TemporaryDirectory() as tmp:
        cmds = commands(Path(tmp))
        for argv in cmds.values():  # warm the file cache and the .pyc files
            time_once(argv)
        times: dict[str, list[tuple[float, float]]] = {label: [] for label in cmds}
        for _ in range(args.runs):
            for label, argv in cmds.items():
                times[label].append(time_once(argv))
    first = next(iter(times.values()))
    wall0, cpu0 = statistics.median(w for w, _ in first), statistics.median(c for _, c in first)
    print(f"load average before the runs: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'command':<44}{'wall median (s)':>16}{'x anchor':>9}{'CPU median (s)':>16}{'x anchor':>9}"
          f"   (median of {args.runs} runs)")
    for label, values in times.items():
        wall, cpu = statistics.median(w for w, _ in values), statistics.median(c for _, c in values)
        print(f"{label:<44}{wall:>16.3f}{wall / wall0:>9.2f}{cpu:>16.3f}{cpu / cpu0:>9.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
