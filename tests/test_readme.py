"""The README's downstream script runs unchanged against the sim and the real profile (names swapped only)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from s2r.registry import load_profile
from s2r.render.scenes import render_scene

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_block(after_heading: str) -> str:
    text = README.read_text()
    section = text[text.index(after_heading):]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, f"no python block after {after_heading!r}"
    return match.group(1)


@pytest.mark.slow
@pytest.mark.parametrize("profile_name", ["gazebo_dual_camera", "realsense_d435_848x480"])
def test_readme_script_runs_on_both_profiles(profile_name: str, tmp_path: Path) -> None:
    script = tmp_path / "depth_demo.py"
    script.write_text(_python_block("## Python API: one script, two profiles"))
    frame = render_scene(load_profile(profile_name), scene="planes", distances_m=(1.0,), supersample=1, jobs=1)[0]
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    cv2.imwrite(str(left), frame.left)
    cv2.imwrite(str(right), frame.right)
    env = {**os.environ, "S2R_PROFILE": profile_name}
    done = subprocess.run([sys.executable, str(script), str(left), str(right)], env=env, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    name, depth, unit = done.stdout.split()
    assert name == profile_name and unit == "m"
    assert float(depth) == pytest.approx(1.0, rel=0.03)  # a plane 1 m away
