"""QA: valid but unusual rigs the row-wise matcher cannot use must be refused in one line naming the profile
file (exit 2), not run to 0 % valid depth (vertical rig: rectified baseline 0) or a confusing depth range."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from s2r.cli import main

REPO = Path(__file__).resolve().parents[2]
PROFILE = REPO / "profiles" / "real" / "realsense_d435_848x480.yaml"


def _profile(tmp_path: Path, name: str, translation_m: list[float]) -> Path:
    data = yaml.safe_load(PROFILE.read_text())
    data["name"] = name
    data["extrinsics"]["translation_m"] = translation_m
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _pair(tmp_path: Path) -> tuple[Path, Path]:
    rng = np.random.default_rng(0)
    image = (rng.random((480, 848)) * 255).astype(np.uint8)
    left, right = tmp_path / "l.png", tmp_path / "r.png"
    cv2.imwrite(str(left), image)
    cv2.imwrite(str(right), np.roll(image, -10, axis=1))
    return left, right


@pytest.mark.parametrize(("name", "translation_m", "words"), [
    ("vertical", [0.0, -0.05, 0.0], "vertical stereo rig"),  # right camera below the left one
    ("swapped", [0.05, 0.0, 0.0], "to the LEFT of the left one"),
])
def test_depth_refuses_unusable_rig(tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str,
                                    translation_m: list[float], words: str) -> None:
    profile = _profile(tmp_path, name, translation_m)
    left, right = _pair(tmp_path)
    out = tmp_path / "out"
    assert main(["depth", "--profile", str(profile), str(left), str(right), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith(f"error: {profile}: extrinsics.translation_m: ") and words in err
    assert not out.exists()


def test_validate_refuses_vertical_rig(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    profile = _profile(tmp_path, "vertical", [0.0, 0.05, 0.0])
    assert main(["validate", str(profile), "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {profile}: extrinsics.translation_m: vertical stereo rig")
    assert "\n" not in err


def test_side_by_side_rigs_still_run(tmp_path: Path) -> None:
    """A 20-degree toe-in and a 4 mm baseline are horizontal after rectification: no refusal."""
    from s2r.depth.pipeline import check_side_by_side
    from s2r.registry import load_profile

    check_side_by_side(load_profile(_profile(tmp_path, "b4mm", [-0.004, 0.0, 0.0])))
    check_side_by_side(load_profile(_profile(tmp_path, "diag", [-0.05, 0.03, 0.0])))


def test_profile_show_flags_a_vertical_rig(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "show", str(_profile(tmp_path, "vertical", [0.0, -0.05, 0.0]))]) == 0
    assert "warning: vertical rig (right camera 5.0 cm below): s2r depth and validate need a side-by-side pair" in (
        capsys.readouterr().out)
    assert main(["profile", "show", str(PROFILE)]) == 0
    assert "vertical" not in capsys.readouterr().out
