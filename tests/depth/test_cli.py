"""``s2r depth``: single pairs, sequences, and bad input (one-line errors, exit code 2)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.depth.synth import SynthPair, make_pair


@pytest.fixture
def setup(tmp_path: Path, pair: SynthPair, small_rig: StereoProfile) -> tuple[Path, Path, Path]:
    profile = dump_profile(small_rig, tmp_path / "small_rig.yaml")
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    cv2.imwrite(str(left), pair.left)
    cv2.imwrite(str(right), pair.right)
    return profile, left, right


def test_single_pair(setup: tuple[Path, Path, Path], tmp_path: Path, pair: SynthPair,
                     capsys: pytest.CaptureFixture[str]) -> None:
    profile, left, right = setup
    out = tmp_path / "out"
    assert main(["depth", "--profile", str(profile), str(left), str(right), "-o", str(out), "--preset", "fast",
                 "--ply"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["camera_info.yaml", "depth.png", "depth_color.png",
                                                     "disparity.npy", "points.ply"]
    assert "small_rig / fast" in capsys.readouterr().out
    disp = np.load(out / "disparity.npy")
    x0, x1, y0, y1 = pair.box
    assert np.nanmedian(disp[y0 + 4:y1 - 4, x0 + 4:x1 - 4]) == pytest.approx(30, abs=0.1)
    depth_mm = cv2.imread(str(out / "depth.png"), cv2.IMREAD_UNCHANGED)
    assert depth_mm.dtype == np.uint16 and np.all((depth_mm == 0) == np.isnan(disp))
    # outputs exist: refused without --force, accepted with it
    args = ["depth", "--profile", str(profile), str(left), str(right), "-o", str(out)]
    assert main(args) == 2
    assert "disparity.npy: already exists; nothing was overwritten (pass --force" in capsys.readouterr().err
    assert main([*args, "--force", "--postprocess", ""]) == 0


def test_sequence(tmp_path: Path, small_rig: StereoProfile) -> None:
    profile = dump_profile(small_rig, tmp_path / "small_rig.yaml")
    (tmp_path / "L").mkdir()
    (tmp_path / "R").mkdir()
    for i in range(5):
        p = make_pair(seed=i, d_box=20 + i)
        cv2.imwrite(str(tmp_path / "L" / f"frame{i}.png"), p.left)
        cv2.imwrite(str(tmp_path / "R" / f"frame{i}.png"), p.right)
    out = tmp_path / "seq"
    assert main(["depth", "--profile", str(profile), "--left-dir", str(tmp_path / "L"), "--right-dir",
                 str(tmp_path / "R"), "-o", str(out), "--preset", "bm"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert len(names) == 16 and "camera_info.yaml" in names
    assert names[:3] == ["00_depth.png", "00_depth_color.png", "00_disparity.npy"]
    for i in range(5):
        disp = np.load(out / f"{i:02d}_disparity.npy")
        assert np.nanmedian(disp[70:170, 170:230]) == pytest.approx(20 + i, abs=0.1)


def test_sequence_errors(tmp_path: Path, small_rig: StereoProfile, capsys: pytest.CaptureFixture[str]) -> None:
    profile = dump_profile(small_rig, tmp_path / "small_rig.yaml")
    (tmp_path / "L").mkdir()
    (tmp_path / "R").mkdir()
    p = make_pair()
    for name in ("a.png", "b.png"):
        cv2.imwrite(str(tmp_path / "L" / name), p.left)
    cv2.imwrite(str(tmp_path / "R" / "a.png"), p.right)
    base = ["depth", "--profile", str(profile), "--left-dir", str(tmp_path / "L"), "-o", str(tmp_path / "o")]
    assert main([*base, "--right-dir", str(tmp_path / "R")]) == 2
    assert "R: 2 left images but 1 right images" in capsys.readouterr().err
    (tmp_path / "R" / "b.png").write_bytes(b"garbage")
    assert main([*base, "--right-dir", str(tmp_path / "R"), "--force"]) == 2
    assert "b.png: cannot read image" in capsys.readouterr().err
    assert main(base) == 2
    assert "sequence mode needs both folders" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--preset", "fast", "--num-disparities", "40"], "num_disparities: num_disparities must be a positive"),
        (["--postprocess", "median,blur"], "unknown post-processing stage 'blur'"),
    ],
)
def test_bad_options(setup: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
                     extra: list[str], message: str) -> None:
    profile, left, right = setup
    assert main(["depth", "--profile", str(profile), str(left), str(right), "-o", str(tmp_path / "o"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_bad_images(setup: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    profile, left, right = setup
    out = str(tmp_path / "o")
    assert main(["depth", "--profile", str(profile), str(tmp_path / "nope.png"), str(right), "-o", out]) == 2
    assert "nope.png: image file not found" in capsys.readouterr().err
    text = tmp_path / "left.txt"
    text.write_text("hello")
    assert main(["depth", "--profile", str(profile), str(text), str(right), "-o", out]) == 2
    assert "left.txt: cannot read image" in capsys.readouterr().err
    big, big_right = tmp_path / "big.png", tmp_path / "big_right.png"
    cv2.imwrite(str(big), np.zeros((480, 640), np.uint8))
    cv2.imwrite(str(big_right), np.zeros((480, 640), np.uint8))
    assert main(["depth", "--profile", str(profile), str(big), str(big_right), "-o", out]) == 2
    assert "images are 640x480 but profile small_rig is 320x240" in capsys.readouterr().err
    assert main(["depth", "--profile", str(profile), str(left), "-o", out]) == 2
    assert "one image given; a pair needs LEFT and RIGHT" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_s2r_profile_default_and_missing(setup: tuple[Path, Path, Path], tmp_path: Path,
                                         monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    profile, left, right = setup
    monkeypatch.delenv("S2R_PROFILE", raising=False)
    assert main(["depth", str(left), str(right), "-o", str(tmp_path / "o")]) == 2
    assert "S2R_PROFILE: no profile given" in capsys.readouterr().err
    monkeypatch.setenv("S2R_PROFILE", str(profile))
    assert main(["depth", str(left), str(right), "-o", str(tmp_path / "o"), "--json"]) == 0
    assert '"profile": "small_rig"' in capsys.readouterr().out
